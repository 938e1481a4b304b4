//! `replay plot FILE [--out DIR]`: PNG figures drawn with plotters into an RGB buffer and
//! encoded with `png`.
//!
//! * `amplitude_node<id>.png` per dynamic node: RMS amplitude (Eq. 35, µm) against ω,
//!   stable parts blue, unstable parts red, not-assessed parts grey; bifurcations marked
//!   with black circles and labelled SN / PD / NS (like the paper's Figs. 7–11);
//! * `clearance.png`: RC variation δv (µm) of every bearing against ω, when recorded;
//! * `temperatures.png`: mean temperature of every thermal node against ω, when recorded.
//!
//! Text needs a TrueType font, found at run time (no system font library is used): the
//! file named by `TMROTOR_FONT`, else DejaVu Sans or Liberation Sans at their usual
//! Debian/Fedora paths. Without one (or with `TMROTOR_FONT=none`) the figures are drawn
//! without any text and a note says so.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::Context;
use plotters::prelude::*;

use crate::record::reader::Recording;
use crate::stability::BifurcationKind;

const WIDTH: u32 = 1000;
const HEIGHT: u32 = 650;
const FONT: &str = "sans-serif";

const FONT_PATHS: [&str; 5] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
];

static FONT_READY: OnceLock<Option<PathBuf>> = OnceLock::new();

/// Registers a font once per process; returns where it came from, `None` when no usable
/// font was found.
pub fn font() -> Option<&'static Path> {
    FONT_READY
        .get_or_init(|| {
            let candidates: Vec<PathBuf> = match std::env::var_os("TMROTOR_FONT") {
                Some(v) if v == "none" => return None,
                Some(v) => vec![PathBuf::from(v)],
                None => FONT_PATHS.iter().map(PathBuf::from).collect(),
            };
            candidates.into_iter().find(|p| {
                std::fs::read(p).ok().is_some_and(|bytes| {
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    plotters::style::register_font(FONT, FontStyle::Normal, bytes).is_ok()
                })
            })
        })
        .as_deref()
}

/// A polyline of one colour.
struct Series {
    points: Vec<(f64, f64)>,
    colour: RGBColor,
    label: Option<String>,
}

struct Marker {
    x: f64,
    y: f64,
    label: String,
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1.0)
    };
    (lo - pad, hi + pad)
}

fn encode_png(path: &Path, rgb: &[u8]) -> anyhow::Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), WIDTH, HEIGHT);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header()?;
    w.write_image_data(rgb)?;
    w.finish()?;
    Ok(())
}

fn draw(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    markers: &[Marker],
) -> anyhow::Result<()> {
    let text = font().is_some();
    let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
        let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
        let (x0, x1) = range(xs);
        let (y0, y1) = range(ys);
        let mut builder = ChartBuilder::on(&root);
        builder.margin(20);
        if text {
            builder
                .caption(title, (FONT, 24))
                .x_label_area_size(45)
                .y_label_area_size(80);
        } else {
            builder.x_label_area_size(10).y_label_area_size(10);
        }
        let mut chart = builder.build_cartesian_2d(x0..x1, y0..y1)?;
        if text {
            chart
                .configure_mesh()
                .x_desc(x_desc)
                .y_desc(y_desc)
                .label_style((FONT, 16))
                .draw()?;
        } else {
            chart.configure_mesh().x_labels(0).y_labels(0).draw()?;
        }
        let mut legend = false;
        for s in series {
            let style = ShapeStyle::from(&s.colour).stroke_width(2);
            let drawn = chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
            if let (Some(label), true) = (&s.label, text) {
                let c = s.colour;
                drawn
                    .label(label.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
                legend = true;
            }
        }
        chart.draw_series(
            markers
                .iter()
                .map(|m| Circle::new((m.x, m.y), 6, BLACK.stroke_width(2))),
        )?;
        if text {
            chart.draw_series(markers.iter().map(|m| {
                Text::new(
                    m.label.clone(),
                    (m.x, m.y),
                    (FONT, 16).into_font().color(&BLACK),
                )
            }))?;
            if legend {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .label_font((FONT, 16))
                    .draw()?;
            }
        }
        root.present()?;
    }
    encode_png(path, &buf)
}

fn short(kind: BifurcationKind) -> &'static str {
    match kind {
        BifurcationKind::SaddleNode => "SN",
        BifurcationKind::PeriodDoubling => "PD",
        BifurcationKind::NeimarkSacker => "NS",
    }
}

const STABLE: RGBColor = RGBColor(31, 119, 180);
const UNSTABLE: RGBColor = RGBColor(214, 39, 40);
const UNKNOWN: RGBColor = RGBColor(127, 127, 127);

/// Splits a branch into runs of equal stability; neighbouring runs share their boundary
/// point so the drawn curve stays connected.
fn stability_segments(rec: &Recording, y: impl Fn(usize) -> f64) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    let mut current: Option<Option<bool>> = None;
    for (i, p) in rec.points.iter().enumerate() {
        let pt = (p.omega_rad_s, y(i));
        if current != Some(p.stable) {
            if let Some(last) = out.last_mut() {
                last.points.push(pt);
            }
            let colour = match p.stable {
                Some(true) => STABLE,
                Some(false) => UNSTABLE,
                None => UNKNOWN,
            };
            out.push(Series {
                points: Vec::new(),
                colour,
                label: None,
            });
            current = Some(p.stable);
        }
        if let Some(last) = out.last_mut() {
            last.points.push(pt);
        }
    }
    // One legend entry per colour.
    for (colour, name) in [
        (STABLE, "stable"),
        (UNSTABLE, "unstable"),
        (UNKNOWN, "not assessed"),
    ] {
        if let Some(s) = out.iter_mut().find(|s| s.colour == colour) {
            s.label = Some(name.into());
        }
    }
    out
}

const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Writes the figures into `dir` and lists them on `out`.
pub fn run(
    rec: &Recording,
    dir: &Path,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    if rec.points.is_empty() {
        anyhow::bail!("{} has no points to plot", rec.file.display());
    }
    if font().is_none() {
        writeln!(
            err,
            "note: no TrueType font found (set TMROTOR_FONT to a .ttf file); figures have no text"
        )?;
    }
    let mut written = Vec::new();
    let run = &rec.run;
    for (k, node) in run.nodes.iter().enumerate() {
        let series = stability_segments(rec, |i| rec.points[i].amplitude_rms_m[k] * 1e6);
        let markers: Vec<Marker> = rec
            .bifurcations
            .iter()
            .filter_map(|b| {
                Some(Marker {
                    x: b.omega_rad_s,
                    y: b.amplitude_rms_m.get(k)? * 1e6,
                    label: format!("  {}{}", short(b.kind), b.number + 1),
                })
            })
            .collect();
        let path = dir.join(format!("amplitude_node{}.png", node.id));
        draw(
            &path,
            &format!(
                "Amplitude–frequency response, node {} ({})",
                node.id, node.name
            ),
            "ω (rad/s)",
            "RMS amplitude (µm), Eq. 35",
            &series,
            &markers,
        )?;
        written.push(path);
    }
    let with_clearance: Vec<_> = rec
        .points
        .iter()
        .filter(|p| !p.clearances.is_empty())
        .collect();
    if !with_clearance.is_empty() {
        let series: Vec<Series> = run
            .bearings
            .iter()
            .enumerate()
            .map(|(b, info)| Series {
                points: with_clearance
                    .iter()
                    .map(|p| (p.omega_rad_s, p.clearances[b].delta_v_m * 1e6))
                    .collect(),
                colour: PALETTE[b % PALETTE.len()],
                label: Some(format!("δv {}", info.name)),
            })
            .collect();
        let path = dir.join("clearance.png");
        draw(
            &path,
            "Radial clearance variation",
            "ω (rad/s)",
            "δv (µm)",
            &series,
            &[],
        )?;
        written.push(path);
    }
    let with_temps: Vec<_> = rec
        .points
        .iter()
        .filter(|p| !p.temperatures.is_empty())
        .collect();
    if !with_temps.is_empty() {
        let labelled = run.thermal_nodes.len() <= PALETTE.len();
        let series: Vec<Series> = run
            .thermal_nodes
            .iter()
            .enumerate()
            .map(|(t, info)| Series {
                points: with_temps
                    .iter()
                    .map(|p| (p.omega_rad_s, p.temperatures[t].mean_c))
                    .collect(),
                colour: PALETTE[t % PALETTE.len()],
                label: labelled.then(|| format!("node {}", info.id)),
            })
            .collect();
        let path = dir.join("temperatures.png");
        draw(
            &path,
            "Mean temperatures",
            "ω (rad/s)",
            "T (°C)",
            &series,
            &[],
        )?;
        written.push(path);
    }
    for p in written {
        writeln!(out, "wrote {}", p.display())?;
    }
    Ok(())
}
