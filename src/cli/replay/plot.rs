//! `replay plot FILE [--out DIR]`: PNG figures of one recording, drawn with the shared
//! helpers of [`crate::figure`].
//!
//! * `amplitude_node<id>.png` per dynamic node: RMS amplitude (Eq. 35, µm) against ω,
//!   stable parts blue, unstable parts red, not-assessed parts grey; bifurcations marked
//!   with black circles and labelled SN / PD / NS (like the paper's Figs. 7–11); points
//!   whose `ω/2` share reaches [`PERIOD_DOUBLED_SHARE`] (the period-doubled response,
//!   see [`crate::derive::half_order_share`]) dotted in purple;
//! * `clearance.png`: RC variation δv (µm) of every bearing against ω, when recorded;
//! * `temperatures.png`: mean temperature of every thermal node against ω, when recorded.
//!
//! Text needs a TrueType font ([`crate::figure::font`]); without one the figures are drawn
//! without any text and a note says so.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use plotters::prelude::*;

use crate::derive::{PERIOD_DOUBLED_SHARE, is_period_doubled};
use crate::figure::{Chart, LineStyle, Marker, PALETTE, Series, draw_chart, font, render_png};
use crate::record::reader::Recording;

const WIDTH: u32 = 1000;
const HEIGHT: u32 = 650;

fn draw(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: Vec<Series>,
    markers: Vec<Marker>,
) -> anyhow::Result<()> {
    let chart = Chart {
        title: title.into(),
        x_desc: x_desc.into(),
        y_desc: y_desc.into(),
        series,
        markers,
        legend: true,
        ..Chart::default()
    };
    let text = font().is_some();
    render_png(path, (WIDTH, HEIGHT), |root| draw_chart(root, &chart, text))?;
    Ok(())
}

const STABLE: RGBColor = RGBColor(31, 119, 180);
const UNSTABLE: RGBColor = RGBColor(214, 39, 40);
const UNKNOWN: RGBColor = RGBColor(127, 127, 127);
const PERIOD_DOUBLED: RGBColor = RGBColor(148, 103, 189);

/// Dots at the points whose response is period-doubled (see [`PERIOD_DOUBLED_SHARE`]);
/// `None` when there are none.
fn period_doubled_dots(rec: &Recording, y: impl Fn(usize) -> f64) -> Option<Series> {
    let points: Vec<(f64, f64)> = rec
        .points
        .iter()
        .enumerate()
        .filter(|(_, p)| is_period_doubled(&rec.run, p))
        .map(|(i, p)| (p.omega_rad_s, y(i)))
        .collect();
    (!points.is_empty()).then(|| Series {
        line: LineStyle::Points,
        width: 3,
        label: Some(format!(
            "period-doubled (ω/2 share ≥ {:.0} %)",
            100.0 * PERIOD_DOUBLED_SHARE
        )),
        ..Series::new(points, PERIOD_DOUBLED)
    })
}

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
            out.push(Series::new(Vec::new(), colour));
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
        let amplitude = |i: usize| rec.points[i].amplitude_rms_m[k] * 1e6;
        let mut series = stability_segments(rec, amplitude);
        series.extend(period_doubled_dots(rec, amplitude));
        let markers: Vec<Marker> = rec
            .bifurcations
            .iter()
            .filter_map(|b| {
                Some(Marker {
                    x: b.omega_rad_s,
                    y: b.amplitude_rms_m.get(k)? * 1e6,
                    label: format!("{}{}", b.kind.abbreviation(), b.number + 1),
                    colour: BLACK,
                })
            })
            .collect();
        let path = dir.join(format!("amplitude_node{}.png", node.id));
        draw(
            &path,
            &if node.name == format!("node {}", node.id) {
                format!("Amplitude–frequency response, node {}", node.id)
            } else {
                format!(
                    "Amplitude–frequency response, node {} ({})",
                    node.id, node.name
                )
            },
            "ω (rad/s)",
            "RMS amplitude (µm), Eq. 35",
            series,
            markers,
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
                label: Some(format!("δv {}", info.name)),
                ..Series::new(
                    with_clearance
                        .iter()
                        .map(|p| (p.omega_rad_s, p.clearances[b].delta_v_m * 1e6))
                        .collect(),
                    PALETTE[b % PALETTE.len()],
                )
            })
            .collect();
        let path = dir.join("clearance.png");
        draw(
            &path,
            "Radial clearance variation",
            "ω (rad/s)",
            "δv (µm)",
            series,
            Vec::new(),
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
                label: labelled.then(|| format!("node {}", info.id)),
                ..Series::new(
                    with_temps
                        .iter()
                        .map(|p| (p.omega_rad_s, p.temperatures[t].mean_c))
                        .collect(),
                    PALETTE[t % PALETTE.len()],
                )
            })
            .collect();
        let path = dir.join("temperatures.png");
        draw(
            &path,
            "Mean temperatures",
            "ω (rad/s)",
            "T (°C)",
            series,
            Vec::new(),
        )?;
        written.push(path);
    }
    for p in written {
        writeln!(out, "wrote {}", p.display())?;
    }
    Ok(())
}
