//! Figures as PNG and SVG, all in this module: the drawing helpers here, and a module per
//! family of figures, each a function per figure that the commands call:
//!
//! * [`recording`]: one recording's figures (`replay plot`);
//! * [`transient`]: transient runs over a branch (`replay transient`);
//! * [`campaign`]: a campaign's runs overlaid (`tmrotor campaign plot`, and at the end of a
//!   campaign);
//! * [`map`]: the operating map (`tmrotor campaign map`);
//! * [`linear`]: the Campbell diagram, mode shapes and unbalance response (`campbell`,
//!   `modes`, `unbalance`).
//!
//! The helpers:
//!
//! * [`Chart`] is one set of axes: polylines ([`Series`], solid, dashed or as points),
//!   labelled [`Marker`]s, optional reference lines, optional category labels on the
//!   x-axis, optionally equal scales on both axes (orbits, the unit circle);
//! * [`Figure`] is what a file holds: panels on a grid, one legend outside the axes (to the
//!   right or below, [`LegendAt`]) and a title drawn only on request ([`Output::title`]);
//! * [`write_figure`] draws a figure once per requested [`Format`] (PNG through an RGB
//!   buffer and `png`, SVG through plotters' SVG backend) and returns the files;
//! * [`layout`] draws a figure into memory and returns where its plot areas, marker labels
//!   and legend went, so that tests check the placement on geometry.
//!
//! Marker labels (bifurcations) are placed by [`place_labels`]: the first of a ring of
//! candidate places around the circle that stays inside the plot area and covers no label
//! placed before, no other circle and no drawn data; a label set off from its circle gets
//! a thin leader line. A label with no free place is left out (its circle stays).
//!
//! Text needs a TrueType font, found at run time (no system font library is used): the
//! file named by `TMROTOR_FONT`, else DejaVu Sans or Liberation Sans at their usual
//! Debian/Fedora paths ([`font`]). Without one (or with `TMROTOR_FONT=none`) figures are
//! drawn without any text; callers tell the user. SVG files name the font family
//! (`sans-serif`) instead of embedding glyphs, so their text stays text.

pub mod campaign;
pub mod linear;
pub mod map;
pub mod recording;
pub mod transient;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A bifurcation's label on a figure: its abbreviation and its 1-based number (`SN2`).
pub fn bifurcation_label(kind: crate::stability::BifurcationKind, number: u32) -> String {
    format!("{}{}", kind.abbreviation(), number + 1)
}

/// What a figure says about a located bifurcation beyond its kind: `?` a fold the orbits'
/// multipliers do not confirm, `~` one that moved at a higher truncation order, `!` one
/// found at some orders and not at the highest (the verdicts `replay info` lists); `None`
/// for a result that holds. Vanished ones are not results and are not drawn at all.
pub fn bifurcation_flag(
    rec: &crate::record::reader::Recording,
    b: &crate::record::BifurcationRecord,
) -> Option<char> {
    use crate::record::types::TruncationVerdict;
    match rec.truncation_of(b).map(|c| c.verdict()) {
        Some(TruncationVerdict::Unsettled { .. }) => Some('!'),
        Some(TruncationVerdict::Moved { .. }) => Some('~'),
        _ if !b.confirmed => Some('?'),
        _ => None,
    }
}

/// The legend text explaining the flags of [`bifurcation_flag`] that occur in `flags`.
pub fn flag_legend_text(flags: impl IntoIterator<Item = char>) -> Option<String> {
    let flags: Vec<char> = flags.into_iter().collect();
    let parts: Vec<&str> = [
        ('?', "? not confirmed by the multipliers"),
        ('~', "~ moved at a higher order"),
        ('!', "! unsettled at a higher order"),
    ]
    .into_iter()
    .filter(|(f, _)| flags.contains(f))
    .map(|(_, t)| t)
    .collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::DrawingErrorKind;
use thiserror::Error;

/// The speed axis's description, the same on every figure.
pub const OMEGA: &str = "speed ω (rad/s)";

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

impl From<FigureError> for crate::campaign::CampaignError {
    fn from(e: FigureError) -> Self {
        crate::campaign::CampaignError::Figure(Box::new(e))
    }
}

/// What drawing functions return: any plotters error, turned into
/// [`FigureError::Draw`] by [`write_figure`].
pub type DrawResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// A file format of the figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Raster, for a quick look and for web pages.
    Png,
    /// Vector, for print: lines stay lines and text stays text.
    Svg,
}

impl Format {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Png => "png",
            Self::Svg => "svg",
        }
    }
}

/// Parses a comma-separated list of formats (`png`, `svg`, `png,svg`); the error says what
/// is accepted. PDF is not offered: plotters has no PDF backend (convert the SVG, e.g.
/// with `rsvg-convert -f pdf`).
pub fn parse_formats(s: &str) -> Result<Vec<Format>, String> {
    let mut out = Vec::new();
    for word in s.split(',').map(str::trim).filter(|w| !w.is_empty()) {
        let f = match word.to_ascii_lowercase().as_str() {
            "png" => Format::Png,
            "svg" => Format::Svg,
            "pdf" => {
                return Err(
                    "pdf is not written (no PDF backend): write svg and convert it, \
                     e.g. `rsvg-convert -f pdf -o fig.pdf fig.svg`"
                        .into(),
                );
            }
            other => return Err(format!("unknown figure format {other:?} (png, svg)")),
        };
        if !out.contains(&f) {
            out.push(f);
        }
    }
    if out.is_empty() {
        return Err("no figure format given (png, svg)".into());
    }
    Ok(out)
}

/// How figures are written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Output {
    /// The formats, one file each (default PNG and SVG: the PNG to look at, the SVG for a
    /// paper; the SVG costs milliseconds).
    pub formats: Vec<Format>,
    /// Draw the figure's title above the panels (default false: the caption of a paper
    /// says what a figure shows).
    pub title: bool,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            formats: vec![Format::Png, Format::Svg],
            title: false,
        }
    }
}

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

/// Lighter companions of [`PALETTE`]'s colours (the second half of the "tab20" set; for its
/// light grey, too close to the grid lines, an indigo).
pub const PALETTE_LIGHT: [RGBColor; 10] = [
    RGBColor(174, 199, 232),
    RGBColor(255, 187, 120),
    RGBColor(152, 223, 138),
    RGBColor(255, 152, 150),
    RGBColor(197, 176, 213),
    RGBColor(196, 156, 148),
    RGBColor(247, 182, 210),
    RGBColor(82, 84, 163),
    RGBColor(219, 219, 141),
    RGBColor(158, 218, 229),
];

/// Colour number `k`: the ten colours of [`PALETTE`], then the ten of [`PALETTE_LIGHT`],
/// then again.
pub fn colour(k: usize) -> RGBColor {
    let n = PALETTE.len() + PALETTE_LIGHT.len();
    match k % n {
        i if i < PALETTE.len() => PALETTE[i],
        i => PALETTE_LIGHT[i - PALETTE.len()],
    }
}

/// Stable parts of a branch drawn in one colour per stability (`replay plot`).
pub const STABLE: RGBColor = RGBColor(31, 119, 180);
/// Unstable parts.
pub const UNSTABLE: RGBColor = RGBColor(214, 39, 40);
/// Parts whose stability was not assessed.
pub const NOT_ASSESSED: RGBColor = RGBColor(127, 127, 127);

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
    /// Its entry in the figure's legend ([`Figure::legend_from_series`]).
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

/// How [`branch_series`] shows stability.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BranchStyle {
    /// [`STABLE`], [`UNSTABLE`], [`NOT_ASSESSED`], each named once in the legend (one
    /// branch per figure).
    Colours,
    /// One colour, solid where stable or not assessed, dashed and lighter where unstable
    /// (several branches or quantities in a figure).
    Dashes(RGBColor),
}

/// The unstable colour of [`BranchStyle::Dashes`].
pub fn unstable_of(colour: RGBColor) -> RGBColor {
    lighter(colour, 0.35)
}

/// A branch as polylines: `points` are (x, y, stable) in branch order; a point with no y
/// (or a y that is not finite) breaks the line. Neighbouring pieces of different stability
/// share their boundary point so that the curve stays connected.
pub fn branch_series(
    points: impl IntoIterator<Item = (f64, Option<f64>, Option<bool>)>,
    style: BranchStyle,
) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    let mut previous: Option<((f64, f64), Option<bool>)> = None;
    let kind = |s: Option<bool>| match style {
        BranchStyle::Colours => s,
        // stable and not assessed look alike
        BranchStyle::Dashes(_) => Some(s != Some(false)),
    };
    for (x, y, stable) in points {
        let Some(y) = y.filter(|v| v.is_finite()) else {
            previous = None;
            continue;
        };
        let pt = (x, y);
        match previous {
            Some((_, k)) if k == kind(stable) => {
                if let Some(s) = out.last_mut() {
                    s.points.push(pt);
                }
            }
            _ => {
                let mut points: Vec<(f64, f64)> = previous.map(|(q, _)| q).into_iter().collect();
                points.push(pt);
                out.push(match style {
                    BranchStyle::Colours => Series::new(
                        points,
                        match stable {
                            Some(true) => STABLE,
                            Some(false) => UNSTABLE,
                            None => NOT_ASSESSED,
                        },
                    ),
                    BranchStyle::Dashes(c) if stable == Some(false) => Series {
                        line: LineStyle::Dashed,
                        ..Series::new(points, unstable_of(c))
                    },
                    BranchStyle::Dashes(c) => Series::new(points, c),
                });
            }
        }
        previous = Some((pt, kind(stable)));
    }
    if style == BranchStyle::Colours {
        for (c, name) in [
            (STABLE, "stable"),
            (UNSTABLE, "unstable"),
            (NOT_ASSESSED, "stability not assessed"),
        ] {
            if let Some(s) = out.iter_mut().find(|s| s.colour == c) {
                s.label = Some(name.into());
            }
        }
    }
    out
}

/// A rectangle on the canvas, pixels (`x0 ≤ x1`, `y0 ≤ y1`, y downwards).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelBox {
    pub x0: i32,
    pub y0: i32,
    pub x1: i32,
    pub y1: i32,
}

impl PixelBox {
    /// The interiors intersect (touching edges do not count).
    pub fn overlaps(&self, o: &Self) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    /// `o` lies inside this box (edges included).
    pub fn contains(&self, o: &Self) -> bool {
        o.x0 >= self.x0 && o.x1 <= self.x1 && o.y0 >= self.y0 && o.y1 <= self.y1
    }

    fn grown(&self, d: i32) -> Self {
        Self {
            x0: self.x0 - d,
            y0: self.y0 - d,
            x1: self.x1 + d,
            y1: self.y1 + d,
        }
    }

    /// The segment `a`–`b` crosses or touches the box (Liang–Barsky clipping).
    pub fn hit_by_segment(&self, a: (i32, i32), b: (i32, i32)) -> bool {
        let (x0, y0) = (f64::from(a.0), f64::from(a.1));
        let (dx, dy) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
        let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
        for (p, q) in [
            (-dx, x0 - f64::from(self.x0)),
            (dx, f64::from(self.x1) - x0),
            (-dy, y0 - f64::from(self.y0)),
            (dy, f64::from(self.y1) - y0),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return false;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
                if t0 > t1 {
                    return false;
                }
            }
        }
        true
    }
}

/// What a label must keep clear of: boxes (circles, points, other text) and polylines.
#[derive(Clone, Debug, Default)]
pub struct Obstacles {
    pub boxes: Vec<PixelBox>,
    /// Drawn polylines, pixels.
    pub lines: Vec<Vec<(i32, i32)>>,
}

impl Obstacles {
    fn hit(&self, b: &PixelBox) -> bool {
        let g = b.grown(2);
        self.boxes.iter().any(|o| o.overlaps(&g))
            || self.lines.iter().any(|line| {
                line.windows(2).any(|w| {
                    let (a, c) = (w[0], w[1]);
                    // cheap bounding-box test first
                    a.0.max(c.0) >= g.x0
                        && a.0.min(c.0) <= g.x1
                        && a.1.max(c.1) >= g.y0
                        && a.1.min(c.1) <= g.y1
                        && g.hit_by_segment(a, c)
                }) || (line.len() == 1
                    && g.contains(&PixelBox {
                        x0: line[0].0,
                        y0: line[0].1,
                        x1: line[0].0,
                        y1: line[0].1,
                    }))
            })
    }
}

/// Pixels kept free between two labels.
pub const LABEL_GAP: i32 = 3;

/// Where each label goes, in order: the index of the first of its candidate boxes that
/// lies inside `bounds` and overlaps neither a label placed before it nor an obstacle
/// (circles, data), or `None` (left out: where bifurcations crowd, every circle is drawn
/// but not every label).
pub fn place_labels(
    candidates: &[Vec<PixelBox>],
    obstacles: &Obstacles,
    bounds: PixelBox,
) -> Vec<Option<usize>> {
    let mut kept: Vec<PixelBox> = Vec::new();
    candidates
        .iter()
        .map(|boxes| {
            let free = boxes.iter().position(|b| {
                // labels keep a gap of a few pixels between them
                bounds.contains(b)
                    && kept.iter().all(|k| !k.overlaps(&b.grown(LABEL_GAP)))
                    && !obstacles.hit(b)
            });
            if let Some(i) = free {
                kept.push(boxes[i]);
            }
            free
        })
        .collect()
}

/// Offsets (top left corner relative to the marker's centre) of the candidate places of a
/// `w × h` label, nearest first: beside the circle above and below on either side, then
/// rings further out in eight directions.
fn label_offsets(w: i32, h: i32) -> Vec<(i32, i32)> {
    let mut out = vec![(9, -h - 2), (9, 3), (-9 - w, -h - 2), (-9 - w, 3)];
    for d in [16, 28, 44, 64, 90, 120] {
        out.extend([
            (d, -d - h),
            (d, d),
            (-d - w, -d - h),
            (-d - w, d),
            (-w / 2, -d - h - 4),
            (-w / 2, d + 4),
            (d + 6, -h / 2),
            (-d - 6 - w, -h / 2),
        ]);
    }
    out
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
    /// Panel caption above the axes, outside the plot area (empty: none).
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
    /// One unit on the x axis as long as one on the y axis (orbits, the unit circle): the
    /// shorter range is widened about its centre.
    pub equal_aspect: bool,
    /// Names of categories at x = 0, 1, 2, … drawn instead of numeric x labels (each
    /// name may have several lines separated by `\n`).
    pub x_categories: Vec<String>,
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
            equal_aspect: false,
            x_categories: Vec::new(),
            title_px: 18,
            font_px: 16,
        }
    }
}

impl Chart {
    /// The x range drawn without [`Self::equal_aspect`]: the given one, else the data's.
    pub fn x_extent(&self) -> (f64, f64) {
        self.x_range.unwrap_or_else(|| {
            data_range(
                self.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.0))
                    .chain(self.markers.iter().map(|m| m.x)),
            )
        })
    }

    /// The y range drawn without [`Self::equal_aspect`].
    pub fn y_extent(&self) -> (f64, f64) {
        self.y_range.unwrap_or_else(|| {
            data_range(
                self.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.1))
                    .chain(self.markers.iter().map(|m| m.y))
                    .chain(self.hlines.iter().copied()),
            )
        })
    }
}

/// One x range and one y range for all `panels` (small multiples compare directly).
pub fn share_axes(panels: &mut [Chart], x: bool, y: bool) {
    let fold = |r: Vec<(f64, f64)>| {
        r.into_iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (c, d)| {
                (a.min(c), b.max(d))
            })
    };
    let has_data =
        |c: &Chart| c.series.iter().any(|s| !s.points.is_empty()) || !c.markers.is_empty();
    let xr = fold(
        panels
            .iter()
            .filter(|c| has_data(c))
            .map(Chart::x_extent)
            .collect(),
    );
    let yr = fold(
        panels
            .iter()
            .filter(|c| has_data(c))
            .map(Chart::y_extent)
            .collect(),
    );
    for c in panels {
        if x && xr.0 < xr.1 {
            c.x_range = Some(xr);
        }
        if y && yr.0 < yr.1 {
            c.y_range = Some(yr);
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

/// Where a chart's parts went on the canvas.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChartLayout {
    /// The plot area (inside the axes).
    pub plot: PixelBox,
    /// Each marker's label box, `None` when left out (or drawn without text).
    pub labels: Vec<Option<PixelBox>>,
}

fn x_label_area(chart: &Chart, text: bool) -> u32 {
    if !text {
        return 10;
    }
    if chart.x_categories.is_empty() {
        2 * chart.font_px + 14
    } else {
        let lines = chart
            .x_categories
            .iter()
            .map(|c| c.lines().count())
            .max()
            .unwrap_or(1) as u32;
        (lines + 1) * (chart.font_px + 4) + 4
    }
}

fn y_label_area(chart: &Chart, text: bool) -> u32 {
    if text { 4 * chart.font_px + 16 } else { 10 }
}

/// Widens the shorter of two ranges about its centre so that a unit is as long on both
/// axes of a `w × h` pixel plot area.
fn equalise(
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    w: f64,
    h: f64,
) -> ((f64, f64), (f64, f64)) {
    if w <= 0.0 || h <= 0.0 {
        return ((x0, x1), (y0, y1));
    }
    let (sx, sy) = ((x1 - x0) / w, (y1 - y0) / h);
    if sx > sy {
        let (c, half) = (0.5 * (y0 + y1), 0.5 * sx * h);
        ((x0, x1), (c - half, c + half))
    } else {
        let (c, half) = (0.5 * (x0 + x1), 0.5 * sy * w);
        ((c - half, c + half), (y0, y1))
    }
}

/// Draws `chart` on `area` (its caption above the axes, the labels of its markers where
/// [`place_labels`] finds room) and returns where its parts went. With `text` false
/// nothing textual is drawn (no font).
pub fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart,
    text: bool,
) -> DrawResult<ChartLayout>
where
    DB::ErrorType: 'static,
{
    let area = if text && !chart.title.is_empty() {
        area.titled(&chart.title, (FONT, chart.title_px))?
    } else {
        area.clone()
    };
    let margin = chart.font_px.max(10);
    let (xl, yl) = (x_label_area(chart, text), y_label_area(chart, text));
    let (mut xr, mut yr) = (chart.x_extent(), chart.y_extent());
    if chart.equal_aspect {
        let (aw, ah) = area.dim_in_pixel();
        let w = f64::from(aw) - f64::from(2 * margin + yl);
        let h = f64::from(ah) - f64::from(2 * margin + xl);
        (xr, yr) = equalise(xr, yr, w, h);
    }
    let ((x0, x1), (y0, y1)) = (xr, yr);
    let categories = !chart.x_categories.is_empty();
    let mut builder = ChartBuilder::on(&area);
    builder
        .margin(margin)
        .x_label_area_size(xl)
        .y_label_area_size(yl);
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
    let mut obstacles = draw_series(&mut ctx, chart)?;
    ctx.draw_series(
        chart
            .markers
            .iter()
            .map(|m| Circle::new((m.x, m.y), 6, m.colour.stroke_width(2))),
    )?;
    let (px, py) = ctx.plotting_area().get_pixel_range();
    let plot = PixelBox {
        x0: px.start,
        y0: py.start,
        x1: px.end,
        y1: py.end,
    };
    let mut layout = ChartLayout {
        plot,
        labels: vec![None; chart.markers.len()],
    };
    if !text {
        return Ok(layout);
    }
    layout.labels = draw_marker_labels(&mut ctx, &area, chart, &mut obstacles, plot)?;
    if categories {
        draw_categories(&mut ctx, chart, y0)?;
    }
    Ok(layout)
}

/// The chart's plotting context: f64 axes.
type Axes<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws the chart's series; returns what they cover, for the placing of labels.
fn draw_series<DB: DrawingBackend>(ctx: &mut Axes<'_, DB>, chart: &Chart) -> DrawResult<Obstacles>
where
    DB::ErrorType: 'static,
{
    let mut obstacles = Obstacles::default();
    for s in &chart.series {
        let style = ShapeStyle::from(&s.colour).stroke_width(s.width);
        match s.line {
            LineStyle::Solid => {
                ctx.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
            }
            LineStyle::Dashed => {
                ctx.draw_series(DashedLineSeries::new(s.points.iter().copied(), 8, 5, style))?;
            }
            LineStyle::Points => {
                ctx.draw_series(
                    s.points
                        .iter()
                        .map(|&p| Circle::new(p, s.width, style.filled())),
                )?;
            }
        }
        let pixels: Vec<(i32, i32)> = s.points.iter().map(|p| ctx.backend_coord(p)).collect();
        match s.line {
            LineStyle::Points => obstacles.boxes.extend(pixels.iter().map(|&(x, y)| {
                let r = s.width as i32;
                PixelBox {
                    x0: x - r,
                    y0: y - r,
                    x1: x + r,
                    y1: y + r,
                }
            })),
            _ => obstacles.lines.push(pixels),
        }
    }
    Ok(obstacles)
}

/// Draws the labels of the chart's markers where [`place_labels`] finds room (each
/// marker's circle an obstacle too), with a leader line for a label set off from its
/// circle; returns where each went.
fn draw_marker_labels<DB: DrawingBackend>(
    ctx: &mut Axes<'_, DB>,
    area: &DrawingArea<DB, Shift>,
    chart: &Chart,
    obstacles: &mut Obstacles,
    plot: PixelBox,
) -> DrawResult<Vec<Option<PixelBox>>>
where
    DB::ErrorType: 'static,
{
    let mut labels = vec![None; chart.markers.len()];
    let font = (FONT, chart.font_px).into_font();
    let measure = TextStyle::from(font.clone());
    let mut candidates = Vec::with_capacity(chart.markers.len());
    let mut centres = Vec::with_capacity(chart.markers.len());
    for m in &chart.markers {
        let (cx, cy) = ctx.backend_coord(&(m.x, m.y));
        obstacles.boxes.push(PixelBox {
            x0: cx - 7,
            y0: cy - 7,
            x1: cx + 7,
            y1: cy + 7,
        });
        let (w, h) = area
            .estimate_text_size(&m.label, &measure)
            .unwrap_or((0, chart.font_px));
        candidates.push(
            label_offsets(w as i32, h as i32)
                .into_iter()
                .map(|(dx, dy)| PixelBox {
                    x0: cx + dx,
                    y0: cy + dy,
                    x1: cx + dx + w as i32,
                    y1: cy + dy + h as i32,
                })
                .collect::<Vec<_>>(),
        );
        centres.push((cx, cy));
    }
    let placed = place_labels(&candidates, obstacles, plot);
    for (k, (m, at)) in chart.markers.iter().zip(&placed).enumerate() {
        let Some(i) = *at else { continue };
        let b = candidates[k][i];
        let (cx, cy) = centres[k];
        let (dx, dy) = (b.x0 - cx, b.y0 - cy);
        // a label set off from its circle gets a leader line from the circle's edge to
        // the nearest point of the label
        let near = (cx.clamp(b.x0, b.x1), cy.clamp(b.y0, b.y1));
        let (lx, ly) = (near.0 - cx, near.1 - cy);
        let dist = f64::from(lx * lx + ly * ly).sqrt();
        if dist > 14.0 {
            let edge = (
                (f64::from(lx) * 7.0 / dist).round() as i32,
                (f64::from(ly) * 7.0 / dist).round() as i32,
            );
            ctx.draw_series(std::iter::once(
                EmptyElement::at((m.x, m.y))
                    + PathElement::new(
                        vec![edge, (lx, ly)],
                        lighter(m.colour, 0.3).stroke_width(1),
                    ),
            ))?;
        }
        ctx.draw_series(std::iter::once(
            EmptyElement::at((m.x, m.y))
                + Text::new(m.label.clone(), (dx, dy), font.color(&m.colour)),
        ))?;
        labels[k] = Some(b);
    }
    Ok(labels)
}

/// Writes the chart's category names under the x-axis, one per integer x, a line of text
/// per line of the name.
fn draw_categories<DB: DrawingBackend>(ctx: &mut Axes<'_, DB>, chart: &Chart, y0: f64) -> DrawResult
where
    DB::ErrorType: 'static,
{
    {
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

/// One entry of a legend.
#[derive(Clone, Debug)]
pub struct LegendEntry {
    pub sample: LegendSample,
    pub text: String,
}

/// Where a figure's legend goes: always outside the axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LegendAt {
    /// A column to the right of the panels (figures of one or two panels).
    #[default]
    Right,
    /// A strip below the panels, entries in columns (figures of many panels, long texts).
    Below,
}

const SAMPLE_W: i32 = 30;
const GAP: i32 = 24;
/// Legend text size, pixels.
pub const LEGEND_PX: u32 = 15;

fn widest(entries: &[LegendEntry], font_px: u32) -> i32 {
    let font = FontDesc::from((FONT, f64::from(font_px)));
    entries
        .iter()
        .map(|e| font.box_size(&e.text).map_or(0, |(w, _)| w as i32))
        .max()
        .unwrap_or(0)
}

/// Columns and cell width of a legend of `entries` on `width` pixels.
fn legend_grid(entries: &[LegendEntry], font_px: u32, width: u32) -> (usize, i32) {
    let cell = SAMPLE_W + 6 + widest(entries, font_px) + GAP;
    let cols = ((width as i32 - 20) / cell.max(1)).clamp(1, entries.len().max(1) as i32) as usize;
    (cols, cell)
}

/// Size in pixels of a legend of `entries`: below panels `width` pixels wide (a strip of
/// that width), or to their right (a column as wide as its longest entry).
fn legend_size(entries: &[LegendEntry], font_px: u32, at: LegendAt, width: u32) -> (u32, u32) {
    if entries.is_empty() {
        return (0, 0);
    }
    let row_h = font_px + 8;
    match at {
        LegendAt::Below => {
            let (cols, _) = legend_grid(entries, font_px, width);
            let rows = entries.len().div_ceil(cols) as u32;
            (width, rows * row_h + 16)
        }
        LegendAt::Right => {
            let w = (SAMPLE_W + 6 + widest(entries, font_px) + 24) as u32 + 12;
            (w.min(width / 2), entries.len() as u32 * row_h + 16)
        }
    }
}

/// Draws `entries` in columns on `area` (row by row, left to right) inside a thin frame,
/// centred horizontally (below) or at the top (right); returns the frame.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    font_px: u32,
    at: LegendAt,
) -> DrawResult<Option<PixelBox>>
where
    DB::ErrorType: 'static,
{
    if entries.is_empty() {
        return Ok(None);
    }
    let (w, h) = area.dim_in_pixel();
    let (cols, cell) = match at {
        LegendAt::Below => legend_grid(entries, font_px, w),
        LegendAt::Right => (1, 0),
    };
    let row_h = (font_px + 8) as i32;
    let rows = entries.len().div_ceil(cols) as i32;
    let (left, top, used_w) = match at {
        LegendAt::Below => {
            let used_w = (cols as i32 * cell - GAP + 20).min(w as i32 - 2);
            ((w as i32 - used_w) / 2, 2, used_w)
        }
        LegendAt::Right => (4, 16, w as i32 - 12),
    };
    let bottom = (top + rows * row_h + 10).min(h as i32 - 2);
    area.draw(&Rectangle::new(
        [(left, top), (left + used_w, bottom)],
        BLACK.stroke_width(1),
    ))?;
    let style =
        TextStyle::from((FONT, font_px).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for (k, e) in entries.iter().enumerate() {
        let (r, c) = ((k / cols) as i32, (k % cols) as i32);
        let x = left + 10 + c * cell;
        let y = top + 6 + r * row_h + row_h / 2;
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
    let (bx, by) = area.get_base_pixel();
    Ok(Some(PixelBox {
        x0: bx + left,
        y0: by + top,
        x1: bx + left + used_w,
        y1: by + bottom,
    }))
}

/// Rows and columns for `n` panels.
pub fn grid(n: usize) -> (usize, usize) {
    match n {
        0 | 1 => (1, 1),
        2 => (1, 2),
        3 | 4 => (2, 2),
        5 | 6 => (2, 3),
        n => (n.div_ceil(3), 3),
    }
}

/// What one figure file holds.
#[derive(Clone, Debug, Default)]
pub struct Figure {
    /// Drawn above the panels only with [`Output::title`].
    pub title: String,
    pub panels: Vec<Chart>,
    /// Rows and columns of the panels (default [`grid`] of their number).
    pub grid: Option<(usize, usize)>,
    pub legend: Vec<LegendEntry>,
    pub legend_at: LegendAt,
    /// Canvas size, pixels.
    pub size: (u32, u32),
}

impl Figure {
    /// One entry per distinct labelled series of the panels, in order of appearance.
    pub fn legend_from_series(panels: &[Chart]) -> Vec<LegendEntry> {
        let mut out: Vec<LegendEntry> = Vec::new();
        for s in panels.iter().flat_map(|c| &c.series) {
            if let Some(label) = &s.label
                && !out.iter().any(|e| &e.text == label)
            {
                out.push(LegendEntry {
                    sample: LegendSample::Line(s.colour, s.line),
                    text: label.clone(),
                });
            }
        }
        out
    }
}

/// Where a figure's parts went on the canvas.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    pub panels: Vec<ChartLayout>,
    /// The legend's frame (`None` without a legend or without text).
    pub legend: Option<PixelBox>,
}

fn draw_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    title: bool,
    text: bool,
) -> DrawResult<Layout>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let area = if text && title && !fig.title.is_empty() {
        root.titled(&fig.title, (FONT, 22))?
    } else {
        root.clone()
    };
    let (w, h) = area.dim_in_pixel();
    let legend: &[LegendEntry] = if text { &fig.legend } else { &[] };
    let (lw, lh) = legend_size(legend, LEGEND_PX, fig.legend_at, w);
    let (plots, strip) = match fig.legend_at {
        LegendAt::Below => area.split_vertically(h as i32 - lh.min(h / 2) as i32),
        LegendAt::Right => area.split_horizontally(w as i32 - lw as i32),
    };
    let cells = plots.split_evenly(fig.grid.unwrap_or_else(|| grid(fig.panels.len())));
    let mut layout = Layout::default();
    for (cell, chart) in cells.iter().zip(&fig.panels) {
        layout.panels.push(draw_chart(cell, chart, text)?);
    }
    layout.legend = draw_legend(&strip, legend, LEGEND_PX, fig.legend_at)?;
    root.present()?;
    Ok(layout)
}

/// Draws `fig` into memory (an SVG string) and returns where its parts went.
pub fn layout(fig: &Figure, title: bool) -> Result<Layout, FigureError> {
    let text = font().is_some();
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, fig.size).into_drawing_area();
    draw_figure(&root, fig, title, text).map_err(|e| FigureError::Draw {
        path: PathBuf::from("(memory)"),
        reason: e.to_string(),
    })
}

/// The files of one figure and where its parts went.
#[derive(Clone, Debug, Default)]
pub struct Written {
    pub files: Vec<PathBuf>,
    pub layout: Layout,
}

/// Writes `fig` as `stem.png`, `stem.svg` (the formats of `output`).
pub fn write_figure(stem: &Path, fig: &Figure, output: &Output) -> Result<Written, FigureError> {
    let text = font().is_some();
    let mut written = Written::default();
    for &format in &output.formats {
        let path = stem.with_extension(format.extension());
        let draw_error = |e: Box<dyn std::error::Error>| FigureError::Draw {
            path: path.clone(),
            reason: e.to_string(),
        };
        match format {
            Format::Svg => {
                let root = SVGBackend::new(&path, fig.size).into_drawing_area();
                written.layout = draw_figure(&root, fig, output.title, text).map_err(draw_error)?;
            }
            Format::Png => {
                let (width, height) = fig.size;
                let mut buf = vec![0u8; width as usize * height as usize * 3];
                {
                    let root =
                        BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
                    written.layout =
                        draw_figure(&root, fig, output.title, text).map_err(draw_error)?;
                }
                write_png(&path, (width, height), &buf)?;
            }
        }
        written.files.push(path);
    }
    Ok(written)
}

fn write_png(path: &Path, (width, height): (u32, u32), buf: &[u8]) -> Result<(), FigureError> {
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
    w.write_image_data(buf).map_err(encode)?;
    w.finish().map_err(encode)?;
    Ok(())
}

/// The parts of a bearing position, as the thermal network names its nodes
/// (`"<bearing> rolling elements"`, …), with the colour each has in every figure.
pub const BEARING_PARTS: [(&str, RGBColor); 6] = [
    ("rolling elements", PALETTE[3]),
    ("inner ring", PALETTE[1]),
    ("outer ring", PALETTE[0]),
    ("lubricant", PALETTE[2]),
    ("housing seat", PALETTE[5]),
    ("housing flank", PALETTE[7]),
];

/// Colours of shafts (by order of appearance) in [`thermal_groups`]: none of a bearing part.
const SHAFT_COLOURS: [RGBColor; 3] = [PALETTE[9], PALETTE[4], PALETTE[8]];
/// Colours of disks: none of a bearing part or a shaft.
const DISK_COLOURS: [RGBColor; 4] = [
    PALETTE[6],
    PALETTE_LIGHT[7],
    RGBColor(0, 0, 0),
    PALETTE_LIGHT[3],
];

/// One panel's worth of thermal nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalGroup {
    /// Panel caption, e.g. `"bearing 2#"`, `"shafts and disks"`.
    pub title: String,
    /// (index into the thermal nodes, legend text, colour) per node; nodes sharing a
    /// legend text (the segments of one shaft) share the colour.
    pub members: Vec<(usize, String, RGBColor)>,
}

/// Groups thermal nodes by their names (`nodes`: id and name, in the recording's order):
/// a group per bearing of `bearings` (its rolling elements, rings, lubricant and the
/// housing of the same name), then the shafts and disks (a colour per shaft, named by the
/// words before "shaft", and one per disk), then any other nodes.
pub fn thermal_groups(nodes: &[(u32, &str)], bearings: &[&str]) -> Vec<ThermalGroup> {
    let mut used = vec![false; nodes.len()];
    let mut groups = Vec::new();
    for b in bearings {
        let mut members = Vec::new();
        for (part, colour) in BEARING_PARTS {
            for (k, (_, name)) in nodes.iter().enumerate() {
                if used[k] {
                    continue;
                }
                // "1# lubricant", "bearing 1# lubricant", "1# housing flank 2"
                let Some(at) = name.find(part) else { continue };
                let owner = name[..at].trim_end();
                if owner == *b || owner.ends_with(&format!(" {b}")) {
                    used[k] = true;
                    // the flanks of a housing share one entry
                    let text = if part == "housing flank" {
                        "housing flanks".to_string()
                    } else {
                        name[at..].to_string()
                    };
                    members.push((k, text, colour));
                }
            }
        }
        if !members.is_empty() {
            groups.push(ThermalGroup {
                title: format!("bearing {b}"),
                members,
            });
        }
    }
    let mut shafts: Vec<String> = Vec::new();
    let mut members = Vec::new();
    let mut disks = 0;
    for (k, (_, name)) in nodes.iter().enumerate() {
        if used[k] {
            continue;
        }
        if let Some(at) = name.find("shaft") {
            let shaft = name[..at + 5].to_string();
            let i = shafts.iter().position(|s| *s == shaft).unwrap_or_else(|| {
                shafts.push(shaft.clone());
                shafts.len() - 1
            });
            used[k] = true;
            members.push((k, shaft, SHAFT_COLOURS[i % SHAFT_COLOURS.len()]));
        } else if name.contains("disk") {
            used[k] = true;
            members.push((
                k,
                name.to_string(),
                DISK_COLOURS[disks % DISK_COLOURS.len()],
            ));
            disks += 1;
        }
    }
    if !members.is_empty() {
        groups.push(ThermalGroup {
            title: "shafts and disks".into(),
            members,
        });
    }
    let rest: Vec<(usize, String, RGBColor)> = (0..nodes.len())
        .filter(|&k| !used[k])
        .enumerate()
        .map(|(i, k)| (k, nodes[k].1.to_string(), colour(i)))
        .collect();
    if !rest.is_empty() {
        groups.push(ThermalGroup {
            title: if groups.is_empty() {
                "thermal nodes".into()
            } else {
                "other nodes".into()
            },
            members: rest,
        });
    }
    groups
}

/// The panels of the mean temperatures of every thermal node against ω (`replay plot`'s
/// `temperatures`, a campaign's `node_temperatures_<run>`): a panel per bearing and one of
/// the shafts and disks ([`thermal_groups`] of `nodes` and `bearings`), each node in its
/// own colour and named in the legend, unstable parts dashed, the y axes shared; panel
/// titles only when there are several. `points(t)` gives thermal node `t`'s (ω, mean
/// temperature in °C, stable) along the branches (a `None` temperature breaks the line).
pub fn node_temperature_panels<I>(
    nodes: &[(u32, &str)],
    bearings: &[&str],
    points: impl Fn(usize) -> I,
) -> Vec<Chart>
where
    I: IntoIterator<Item = (f64, Option<f64>, Option<bool>)>,
{
    let groups = thermal_groups(nodes, bearings);
    let several = groups.len() > 1;
    let mut panels: Vec<Chart> = groups
        .iter()
        .map(|g| {
            let mut series = Vec::new();
            for (t, label, c) in &g.members {
                let mut s = branch_series(points(*t), BranchStyle::Dashes(*c));
                if let Some(first) = s.iter_mut().find(|s| s.colour == *c) {
                    first.label = Some(label.clone());
                }
                series.extend(s);
            }
            Chart {
                title: if several {
                    g.title.clone()
                } else {
                    String::new()
                },
                x_desc: OMEGA.into(),
                y_desc: "mean temperature (°C)".into(),
                series,
                font_px: if several { 14 } else { 16 },
                title_px: 16,
                ..Chart::default()
            }
        })
        .collect();
    share_axes(&mut panels, false, true);
    panels
}

#[cfg(test)]
mod tests {
    use super::{Format, Obstacles, PixelBox, parse_formats, place_labels};

    fn b(x0: i32, y0: i32) -> PixelBox {
        PixelBox {
            x0,
            y0,
            x1: x0 + 40,
            y1: y0 + 12,
        }
    }

    const ALL: PixelBox = PixelBox {
        x0: -1000,
        y0: -1000,
        x1: 1000,
        y1: 1000,
    };

    #[test]
    fn labels_take_the_first_free_place_or_are_left_out() {
        let none = Obstacles::default();
        let candidates = [
            vec![b(0, 0)],
            // the first place overlaps the first label: the second
            vec![b(10, 5), b(10, 30)],
            // both places overlap a label placed before: left out
            vec![b(5, 0), b(5, 28)],
            // keeps the gap to the first label
            vec![b(40 + super::LABEL_GAP, 0)],
        ];
        assert_eq!(
            place_labels(&candidates, &none, ALL),
            vec![Some(0), Some(1), None, Some(0)]
        );
        let two = |x0, y0| vec![b(x0, y0), b(x0, y0 + 20)];
        // an obstacle (another marker's circle) counts as well
        let circle = Obstacles {
            boxes: vec![PixelBox {
                x0: 5,
                y0: 2,
                x1: 10,
                y1: 8,
            }],
            ..Obstacles::default()
        };
        assert_eq!(place_labels(&[two(0, 0)], &circle, ALL), vec![Some(1)]);
        // so does a line through the first place, and the bounds of the plot area
        let line = Obstacles {
            lines: vec![vec![(-50, 6), (100, 6)]],
            ..Obstacles::default()
        };
        assert_eq!(place_labels(&[two(0, 0)], &line, ALL), vec![Some(1)]);
        let bounds = PixelBox {
            x0: 0,
            y0: 15,
            x1: 100,
            y1: 100,
        };
        assert_eq!(place_labels(&[two(0, 0)], &none, bounds), vec![Some(1)]);
    }

    #[test]
    fn segments_hit_boxes_they_cross_only() {
        let r = b(0, 0);
        assert!(r.hit_by_segment((-10, 6), (50, 6)));
        assert!(r.hit_by_segment((-10, -10), (50, 30)));
        assert!(r.hit_by_segment((5, 5), (6, 6)), "inside");
        assert!(!r.hit_by_segment((-10, -10), (-1, 30)));
        assert!(!r.hit_by_segment((50, -10), (60, 30)));
    }

    #[test]
    fn thermal_nodes_group_by_bearing_then_shafts_and_disks() {
        use super::thermal_groups;
        let nodes = [
            (1, "LP shaft LP element 1-2 seg 1/1"),
            (2, "HP shaft HP element 12-13 seg 1/2"),
            (3, "LPC disk"),
            (4, "1# housing seat"),
            (5, "1# inner ring"),
            (6, "bearing 2# rolling elements"),
            (7, "1# lubricant"),
            (8, "11# lubricant"),
            (9, "oil tank"),
        ];
        let groups = thermal_groups(&nodes, &["1#", "2#", "11#"]);
        let titles: Vec<&str> = groups.iter().map(|g| g.title.as_str()).collect();
        assert_eq!(
            titles,
            [
                "bearing 1#",
                "bearing 2#",
                "bearing 11#",
                "shafts and disks",
                "other nodes"
            ]
        );
        let names =
            |g: usize| -> Vec<&str> { groups[g].members.iter().map(|m| m.1.as_str()).collect() };
        assert_eq!(names(0), ["inner ring", "lubricant", "housing seat"]);
        assert_eq!(names(1), ["rolling elements"]);
        assert_eq!(names(2), ["lubricant"]);
        assert_eq!(names(3), ["LP shaft", "HP shaft", "LPC disk"]);
        assert_eq!(names(4), ["oil tank"]);
    }

    #[test]
    fn formats_parse_from_a_list() {
        assert_eq!(parse_formats("png,svg"), Ok(vec![Format::Png, Format::Svg]));
        assert_eq!(parse_formats(" SVG "), Ok(vec![Format::Svg]));
        assert!(parse_formats("pdf").is_err_and(|e| e.contains("rsvg-convert")));
        assert!(parse_formats("jpg").is_err_and(|e| e.contains("jpg")));
        assert!(parse_formats("").is_err());
    }
}
