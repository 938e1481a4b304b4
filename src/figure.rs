//! PNG figures: plotters draws into an RGB buffer, `png` encodes it. The drawing helpers
//! shared by `replay plot` (one recording) and `tmrotor campaign plot` (several runs).
//!
//! * [`Chart`] is one set of axes: polylines ([`Series`], solid, dashed or as points),
//!   labelled [`Marker`]s, optional reference lines, optional category labels on the
//!   x-axis, optional in-chart legend; [`draw_chart`] draws it on any drawing area;
//! * [`draw_legend`] lays out a legend in its own strip (for figures with several panels
//!   sharing one legend), [`legend_height`] says how tall that strip must be;
//! * [`render_png`] gives a drawing function a white canvas and writes the PNG.
//!
//! Text needs a TrueType font, found at run time (no system font library is used): the
//! file named by `TMROTOR_FONT`, else DejaVu Sans or Liberation Sans at their usual
//! Debian/Fedora paths ([`font`]). Without one (or with `TMROTOR_FONT=none`) figures are
//! drawn without any text; callers tell the user.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::DrawingErrorKind;
use thiserror::Error;

/// Family name under which the font is registered with plotters.
pub const FONT: &str = "sans-serif";

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

/// Errors writing a figure; every variant names the file.
#[derive(Debug, Error)]
pub enum FigureError {
    #[error("drawing {path}: {reason}")]
    Draw { path: PathBuf, reason: String },
    #[error("writing {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("encoding {path}: {source}")]
    Encode {
        path: PathBuf,
        source: png::EncodingError,
    },
}

/// What drawing functions return: any plotters error, turned into
/// [`FigureError::Draw`] by [`render_png`].
pub type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A drawing area of the in-memory bitmap.
pub type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Ten distinguishable colours (the "tab10" palette), for runs or bearings.
pub const PALETTE: [RGBColor; 10] = [
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

/// Dark grey of reference lines.
pub const REFERENCE: RGBColor = RGBColor(70, 70, 70);

/// `colour` mixed with white: `amount` 0 keeps it, 1 gives white.
pub fn lighter(colour: RGBColor, amount: f64) -> RGBColor {
    let mix = |c: u8| (f64::from(c) + (255.0 - f64::from(c)) * amount.clamp(0.0, 1.0)) as u8;
    RGBColor(mix(colour.0), mix(colour.1), mix(colour.2))
}

/// How a [`Series`] is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineStyle {
    Solid,
    Dashed,
    /// Filled circles at the points, no line.
    Points,
}

/// One polyline (or set of points) of one colour.
#[derive(Clone, Debug)]
pub struct Series {
    pub points: Vec<(f64, f64)>,
    pub colour: RGBColor,
    pub line: LineStyle,
    /// Line width, or circle radius for [`LineStyle::Points`], pixels.
    pub width: u32,
    /// Entry of the in-chart legend ([`Chart::legend`]).
    pub label: Option<String>,
}

impl Series {
    /// A solid line of width 2 without a label.
    pub fn new(points: Vec<(f64, f64)>, colour: RGBColor) -> Self {
        Self {
            points,
            colour,
            line: LineStyle::Solid,
            width: 2,
            label: None,
        }
    }
}

/// A marker label's extent on the canvas, pixels (`x0 ≤ x1`, `y0 ≤ y1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LabelBox {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl LabelBox {
    fn overlaps(&self, o: &Self) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

/// Where each label goes, in order: the index of the first of its candidate boxes that
/// overlaps neither a label placed before it nor an obstacle (the markers' circles), or
/// `None` (left out: where bifurcations crowd, every circle is drawn but not every label).
fn place_labels(candidates: &[Vec<LabelBox>], obstacles: &[LabelBox]) -> Vec<Option<usize>> {
    let mut kept: Vec<LabelBox> = Vec::new();
    candidates
        .iter()
        .map(|boxes| {
            let free = boxes
                .iter()
                .position(|b| kept.iter().chain(obstacles).all(|k| !k.overlaps(b)));
            if let Some(i) = free {
                kept.push(boxes[i]);
            }
            free
        })
        .collect()
}

/// A labelled circle, e.g. a bifurcation point.
#[derive(Clone, Debug)]
pub struct Marker {
    pub x: f64,
    pub y: f64,
    pub label: String,
    pub colour: RGBColor,
}

/// One set of axes and what is drawn on them.
#[derive(Clone, Debug)]
pub struct Chart {
    /// Caption above the axes (empty: none).
    pub title: String,
    pub x_desc: String,
    pub y_desc: String,
    pub series: Vec<Series>,
    pub markers: Vec<Marker>,
    /// Horizontal reference lines (thin, dark grey, dashed).
    pub hlines: Vec<f64>,
    /// Axis ranges; `None`: the data's range plus 5 %.
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    /// Names of categories at x = 0, 1, 2, … drawn instead of numeric x labels (each
    /// name may have several lines separated by `\n`).
    pub x_categories: Vec<String>,
    /// Draw an in-chart legend of the labelled series (upper right).
    pub legend: bool,
    /// Caption size, pixels.
    pub title_px: u32,
    /// Tick and axis label size, pixels.
    pub font_px: u32,
}

impl Default for Chart {
    fn default() -> Self {
        Self {
            title: String::new(),
            x_desc: String::new(),
            y_desc: String::new(),
            series: Vec::new(),
            markers: Vec::new(),
            hlines: Vec::new(),
            x_range: None,
            y_range: None,
            x_categories: Vec::new(),
            legend: false,
            title_px: 24,
            font_px: 16,
        }
    }
}

/// Range of the finite values plus 5 % on each side; `(0, 1)` when there are none.
pub fn data_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
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

/// A tick label: at most three decimals, trailing zeros dropped (`300`, `2.5`, `0.125`).
pub fn tick(v: &f64) -> String {
    let s = format!("{v:.3}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        &s
    };
    if s == "-0" { "0".into() } else { s.into() }
}

/// Draws `chart` on `area`. With `text` false nothing textual is drawn (no font).
pub fn draw_chart(area: &Area, chart: &Chart, text: bool) -> DrawResult {
    let (x0, x1) = chart.x_range.unwrap_or_else(|| {
        data_range(
            chart
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0))
                .chain(chart.markers.iter().map(|m| m.x)),
        )
    });
    let (y0, y1) = chart.y_range.unwrap_or_else(|| {
        data_range(
            chart
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1))
                .chain(chart.markers.iter().map(|m| m.y))
                .chain(chart.hlines.iter().copied()),
        )
    });
    let categories = !chart.x_categories.is_empty();
    let lines = chart
        .x_categories
        .iter()
        .map(|c| c.lines().count())
        .max()
        .unwrap_or(1) as u32;
    let mut builder = ChartBuilder::on(area);
    builder.margin(chart.font_px.max(10));
    if text {
        if !chart.title.is_empty() {
            builder.caption(&chart.title, (FONT, chart.title_px));
        }
        let x_area = if categories {
            (lines + 1) * (chart.font_px + 4) + 4
        } else {
            2 * chart.font_px + 14
        };
        builder
            .x_label_area_size(x_area)
            .y_label_area_size(4 * chart.font_px + 16);
    } else {
        builder.x_label_area_size(10).y_label_area_size(10);
    }
    let mut ctx = builder.build_cartesian_2d(x0..x1, y0..y1)?;
    {
        let mut mesh = ctx.configure_mesh();
        if text {
            mesh.x_desc(chart.x_desc.as_str())
                .y_desc(chart.y_desc.as_str())
                .label_style((FONT, chart.font_px))
                .axis_desc_style((FONT, chart.font_px))
                .x_label_formatter(&tick)
                .y_label_formatter(&tick);
        } else {
            mesh.y_labels(0).x_labels(0);
        }
        if categories {
            mesh.x_labels(0).disable_x_mesh();
        }
        mesh.draw()?;
    }
    for &h in &chart.hlines {
        ctx.draw_series(DashedLineSeries::new(
            [(x0, h), (x1, h)],
            10,
            6,
            REFERENCE.stroke_width(1),
        ))?;
    }
    let mut legend = false;
    for s in &chart.series {
        let style = ShapeStyle::from(&s.colour).stroke_width(s.width);
        let drawn = match s.line {
            LineStyle::Solid => {
                ctx.draw_series(LineSeries::new(s.points.iter().copied(), style))?
            }
            LineStyle::Dashed => {
                ctx.draw_series(DashedLineSeries::new(s.points.iter().copied(), 8, 5, style))?
            }
            LineStyle::Points => ctx.draw_series(
                s.points
                    .iter()
                    .map(|&p| Circle::new(p, s.width, style.filled())),
            )?,
        };
        if let (Some(label), true) = (&s.label, text && chart.legend) {
            let (c, line) = (s.colour, s.line);
            drawn.label(label.as_str()).legend(move |at| LegendGlyph {
                at,
                width: 20,
                colour: c,
                line,
            });
            legend = true;
        }
    }
    ctx.draw_series(
        chart
            .markers
            .iter()
            .map(|m| Circle::new((m.x, m.y), 6, m.colour.stroke_width(2))),
    )?;
    if text {
        // each label above right of its circle, else below right, above left, below
        // left; one that would cover every way a label placed before it or another
        // circle is left out (its circle stays)
        let font = (FONT, chart.font_px).into_font();
        let measure = TextStyle::from(font.clone());
        let (gap, up) = (8, -(chart.font_px as i32) - 2);
        let mut offsets = Vec::with_capacity(chart.markers.len());
        let mut candidates = Vec::with_capacity(chart.markers.len());
        let mut circles = Vec::with_capacity(chart.markers.len());
        for m in &chart.markers {
            let (px, py) = ctx.backend_coord(&(m.x, m.y));
            let (w, h) = area
                .estimate_text_size(&m.label, &measure)
                .unwrap_or((0, chart.font_px));
            let (w, h) = (w as i32, h as i32);
            let corners = [(gap, up), (gap, 4), (-gap - w, up), (-gap - w, 4)];
            candidates.push(
                corners
                    .iter()
                    .map(|&(dx, dy)| LabelBox {
                        x0: px + dx,
                        y0: py + dy,
                        x1: px + dx + w,
                        y1: py + dy + h,
                    })
                    .collect::<Vec<_>>(),
            );
            offsets.push(corners);
            circles.push(LabelBox {
                x0: px - 7,
                y0: py - 7,
                x1: px + 7,
                y1: py + 7,
            });
        }
        let placed = place_labels(&candidates, &circles);
        ctx.draw_series(
            chart
                .markers
                .iter()
                .zip(placed.iter().zip(&offsets))
                .filter_map(|(m, (at, corners))| {
                    let offset = corners[(*at)?];
                    Some(
                        EmptyElement::at((m.x, m.y))
                            + Text::new(m.label.clone(), offset, font.color(&m.colour)),
                    )
                }),
        )?;
        if categories {
            let style = TextStyle::from((FONT, chart.font_px).into_font())
                .pos(Pos::new(HPos::Center, VPos::Top));
            for (i, name) in chart.x_categories.iter().enumerate() {
                for (k, line) in name.lines().enumerate() {
                    let dy = 6 + k as i32 * (chart.font_px as i32 + 4);
                    ctx.draw_series(std::iter::once(
                        EmptyElement::at((i as f64, y0))
                            + Text::new(line.to_string(), (0, dy), style.clone()),
                    ))?;
                }
            }
        }
        if legend {
            ctx.configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, chart.font_px))
                .draw()?;
        }
    }
    Ok(())
}

/// The small picture in front of a legend entry: a line, a dashed line or a dot
/// starting at its point, `width` pixels wide.
struct LegendGlyph {
    at: (i32, i32),
    width: i32,
    colour: RGBColor,
    line: LineStyle,
}

impl<'a> PointCollection<'a, (i32, i32)> for &'a LegendGlyph {
    type Point = &'a (i32, i32);
    type IntoIter = std::iter::Once<&'a (i32, i32)>;
    fn point_iter(self) -> std::iter::Once<&'a (i32, i32)> {
        std::iter::once(&self.at)
    }
}

impl<DB: DrawingBackend> Drawable<DB> for LegendGlyph {
    fn draw<I: Iterator<Item = (i32, i32)>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let style = ShapeStyle::from(&self.colour).stroke_width(2);
        let w = self.width;
        match self.line {
            LineStyle::Solid => backend.draw_line((x, y), (x + w, y), &style),
            LineStyle::Dashed => {
                for k in 0..3 {
                    let x0 = x + k * w / 3;
                    backend.draw_line((x0, y), (x0 + w / 5, y), &style)?;
                }
                Ok(())
            }
            LineStyle::Points => backend.draw_circle((x + w / 2, y), 5, &style, true),
        }
    }
}

/// What stands in front of a legend text.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LegendSample {
    Line(RGBColor, LineStyle),
    /// An open circle, as drawn for a [`Marker`].
    Marker(RGBColor),
    /// Nothing: a heading or a note.
    None,
}

/// One entry of a legend strip.
#[derive(Clone, Debug)]
pub struct LegendEntry {
    pub sample: LegendSample,
    pub text: String,
}

const SAMPLE_W: i32 = 30;
const GAP: i32 = 24;

fn legend_grid(
    area: &Area,
    entries: &[LegendEntry],
    font_px: u32,
) -> Result<(usize, i32), Box<dyn std::error::Error>> {
    let style = TextStyle::from((FONT, font_px).into_font());
    let mut widest = 0;
    for e in entries {
        let (w, _) = area.estimate_text_size(&e.text, &style)?;
        widest = widest.max(w as i32);
    }
    let cell = SAMPLE_W + 6 + widest + GAP;
    let (w, _) = area.dim_in_pixel();
    let cols = ((w as i32 - 20) / cell.max(1)).clamp(1, entries.len().max(1) as i32) as usize;
    Ok((cols, cell))
}

/// Height in pixels a [`draw_legend`] strip of `entries` needs on an area as wide as `area`.
pub fn legend_height(area: &Area, entries: &[LegendEntry], font_px: u32, text: bool) -> u32 {
    if !text || entries.is_empty() {
        return 0;
    }
    let cols = legend_grid(area, entries, font_px).map_or(1, |(c, _)| c);
    let rows = entries.len().div_ceil(cols) as u32;
    rows * (font_px + 8) + 16
}

/// Draws `entries` in columns on `area` (row by row, left to right), inside a thin frame.
pub fn draw_legend(area: &Area, entries: &[LegendEntry], font_px: u32, text: bool) -> DrawResult {
    if !text || entries.is_empty() {
        return Ok(());
    }
    let (cols, cell) = legend_grid(area, entries, font_px)?;
    let (w, h) = area.dim_in_pixel();
    let row_h = (font_px + 8) as i32;
    let rows = entries.len().div_ceil(cols) as i32;
    let used_w = (cols as i32 * cell - GAP + 20).min(w as i32 - 2);
    let left = (w as i32 - used_w) / 2;
    area.draw(&Rectangle::new(
        [
            (left, 2),
            (left + used_w, (rows * row_h + 12).min(h as i32 - 2)),
        ],
        BLACK.stroke_width(1),
    ))?;
    let style =
        TextStyle::from((FONT, font_px).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for (k, e) in entries.iter().enumerate() {
        let (r, c) = ((k / cols) as i32, (k % cols) as i32);
        let x = left + 10 + c * cell;
        let y = 8 + r * row_h + row_h / 2;
        let text_x = match e.sample {
            LegendSample::Line(colour, line) => {
                area.draw(&LegendGlyph {
                    at: (x, y),
                    width: SAMPLE_W,
                    colour,
                    line,
                })?;
                x + SAMPLE_W + 6
            }
            LegendSample::Marker(colour) => {
                area.draw(&Circle::new(
                    (x + SAMPLE_W / 2, y),
                    6,
                    colour.stroke_width(2),
                ))?;
                x + SAMPLE_W + 6
            }
            LegendSample::None => x,
        };
        area.draw_text(&e.text, &style, (text_x, y))?;
    }
    Ok(())
}

/// Gives `draw` a white `width × height` canvas and writes it to `path` as an RGB PNG.
pub fn render_png(
    path: &Path,
    (width, height): (u32, u32),
    draw: impl FnOnce(&Area) -> DrawResult,
) -> Result<(), FigureError> {
    let mut buf = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        let drawn = root
            .fill(&WHITE)
            .map_err(Into::into)
            .and_then(|()| draw(&root))
            .and_then(|()| root.present().map_err(Into::into));
        drawn.map_err(|e| FigureError::Draw {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    }
    let io = |source| FigureError::Io {
        path: path.to_path_buf(),
        source,
    };
    let encode = |source| FigureError::Encode {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(encode)?;
    w.write_image_data(&buf).map_err(encode)?;
    w.finish().map_err(encode)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{LabelBox, place_labels};

    #[test]
    fn labels_take_the_first_free_place_or_are_left_out() {
        let b = |x0, y0| LabelBox {
            x0,
            y0,
            x1: x0 + 40,
            y1: y0 + 12,
        };
        let candidates = [
            vec![b(0, 0)],
            // the first place overlaps the first label: the second
            vec![b(10, 5), b(10, 30)],
            // both places overlap a label placed before: left out
            vec![b(5, 0), b(5, 28)],
            // touches the first label's edge only
            vec![b(40, 0)],
        ];
        assert_eq!(
            place_labels(&candidates, &[]),
            vec![Some(0), Some(1), None, Some(0)]
        );
        let two = |x0, y0| vec![b(x0, y0), b(x0, y0 + 20)];
        // an obstacle (another marker's circle) counts as well
        let circle = LabelBox {
            x0: 5,
            y0: 2,
            x1: 10,
            y1: 8,
        };
        assert_eq!(place_labels(&[two(0, 0)], &[circle]), vec![Some(1)]);
    }
}
