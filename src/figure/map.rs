//! The operating map's figure ([`write_map_figure`]): the located bifurcations of the
//! campaign's runs over (parameter, ω), with the fold-pair ends and the regions where
//! responses coexist or none is stable; the map itself is [`crate::campaign::map`]'s.

use std::path::Path;

use plotters::style::RGBColor;

use crate::campaign::CampaignError;
use crate::campaign::map::{MapFiles, OperatingMap};
use crate::figure::{
    self, Chart, Figure, LegendAt, LegendEntry, LegendSample, LineStyle, OMEGA, Series,
};
use crate::stability::BifurcationKind;

/// Draws `map` as `out/operating_map.<format>` (`out` must exist) at `size` pixels;
/// returns the files written, with a note when no font was found.
pub fn write_map_figure(
    map: &OperatingMap,
    out: &Path,
    size: (u32, u32),
    output: &figure::Output,
) -> Result<MapFiles, CampaignError> {
    let fig = map_figure(map, size);
    let written = figure::write_figure(&out.join("operating_map"), &fig, output)?;
    let mut notes = Vec::new();
    if figure::font().is_none() {
        notes.push(
            "no TrueType font found (set TMROTOR_FONT to a .ttf file): the figure has no text"
                .into(),
        );
    }
    Ok(MapFiles {
        written: written.files,
        notes,
    })
}

fn kind_colour(kind: BifurcationKind) -> RGBColor {
    match kind {
        BifurcationKind::SaddleNode => RGBColor(20, 20, 20),
        BifurcationKind::NeimarkSacker => RGBColor(214, 96, 0),
        BifurcationKind::PeriodDoubling => RGBColor(118, 42, 131),
    }
}

/// The axis label of a parameter: the study's own names for its keys, else the key.
fn param_description(param: &str) -> String {
    match param {
        "flow_l_min" => "lubricant flow rate per bearing q_l (L/min)".into(),
        "cooling_temp_c" => "lubricant cooling temperature T_L∞ (°C)".into(),
        "ambient_temp_c" => "ambient temperature T_∞ (°C)".into(),
        other => other.to_string(),
    }
}

const HYSTERESIS: RGBColor = RGBColor(158, 202, 225);
const NONE_STABLE: RGBColor = RGBColor(244, 165, 130);

/// One panel of the map over `x_range` and `y_range`.
fn map_panel(
    map: &OperatingMap,
    title: String,
    x_range: (f64, f64),
    y_range: (f64, f64),
    size: (u32, u32),
) -> Chart {
    let mut chart = Chart {
        title,
        title_px: 16,
        font_px: 14,
        x_desc: param_description(&map.param),
        y_desc: OMEGA.into(),
        x_range: Some(x_range),
        y_range: Some(y_range),
        ..Chart::default()
    };
    // bands as thick vertical strokes at each swept value
    let visible = map
        .slices
        .iter()
        .filter(|s| s.p >= x_range.0 && s.p <= x_range.1)
        .count()
        .max(1) as u32;
    let band_px = (size.0 / (6 * visible)).clamp(3, 24);
    for r in &map.regions {
        let colour = match (r.stable, r.unstable) {
            (s, _) if s >= 2 => HYSTERESIS,
            (0, u) if u > 0 => NONE_STABLE,
            _ => continue,
        };
        chart.series.push(Series {
            width: band_px,
            ..Series::new(vec![(r.p, r.omega_from), (r.p, r.omega_to)], colour)
        });
    }
    for c in &map.curves {
        let colour = kind_colour(c.kind);
        let line = match c.kind {
            BifurcationKind::SaddleNode => LineStyle::Solid,
            _ => LineStyle::Dashed,
        };
        chart.series.push(Series {
            line,
            ..Series::new(c.points.clone(), colour)
        });
        chart.series.push(Series {
            line: LineStyle::Points,
            width: 3,
            ..Series::new(c.points.clone(), colour)
        });
    }
    for e in &map.pair_ends {
        chart.markers.push(figure::Marker {
            x: 0.5 * (e.p_with + e.p_without),
            y: e.omega,
            label: "cusp".into(),
            colour: kind_colour(BifurcationKind::SaddleNode),
        });
    }
    chart
}

/// ω against the parameter: the bands of each swept value (blue: two or more stable
/// responses; red: none stable), the curves by kind, the fold-pair ends.
fn map_figure(map: &OperatingMap, size: (u32, u32)) -> Figure {
    let (plo, phi) = figure::data_range(map.slices.iter().map(|s| s.p));
    let (wlo, whi) = figure::data_range(
        map.slices
            .iter()
            .flat_map(|s| s.branch.iter().map(|b| b.0))
            .filter(|w| w.is_finite()),
    );
    let mut panels = vec![map_panel(
        map,
        "all swept values".into(),
        (plo, phi),
        (wlo, whi),
        size,
    )];
    // A second panel on the bifurcations and the swept values beside them, when they
    // cover only part of the map.
    let bif_ps: Vec<f64> = map
        .curves
        .iter()
        .flat_map(|c| c.points.iter().map(|q| q.0))
        .collect();
    if !bif_ps.is_empty() {
        let (blo, bhi) = figure::data_range(bif_ps.iter().copied());
        let ps: Vec<f64> = map.slices.iter().map(|s| s.p).collect();
        let below = ps
            .iter()
            .copied()
            .filter(|p| *p < blo)
            .reduce(f64::max)
            .unwrap_or(blo);
        let above = ps
            .iter()
            .copied()
            .filter(|p| *p > bhi)
            .reduce(f64::min)
            .unwrap_or(bhi);
        let (zlo, zhi) = figure::data_range(
            map.curves
                .iter()
                .flat_map(|c| c.points.iter().map(|q| q.1))
                .chain(map.pair_ends.iter().map(|e| e.omega)),
        );
        let margin = (0.1 * (zhi - zlo)).max(0.02 * (whi - wlo));
        if above - below < 0.7 * (phi - plo) || zhi - zlo < 0.5 * (whi - wlo) {
            panels.push(map_panel(
                map,
                "where the bifurcations are".into(),
                (below, above),
                (zlo - margin, zhi + margin),
                size,
            ));
        }
    }
    let mut legend = vec![];
    for kind in [
        BifurcationKind::SaddleNode,
        BifurcationKind::NeimarkSacker,
        BifurcationKind::PeriodDoubling,
    ] {
        if map.curves.iter().any(|c| c.kind == kind) {
            legend.push(LegendEntry {
                sample: LegendSample::Line(
                    kind_colour(kind),
                    if kind == BifurcationKind::SaddleNode {
                        LineStyle::Solid
                    } else {
                        LineStyle::Dashed
                    },
                ),
                text: format!("{} points", kind.label()),
            });
        }
    }
    legend.push(LegendEntry {
        sample: LegendSample::Line(HYSTERESIS, LineStyle::Solid),
        text: "two or more stable responses".into(),
    });
    legend.push(LegendEntry {
        sample: LegendSample::Line(NONE_STABLE, LineStyle::Solid),
        text: "no stable response".into(),
    });
    if !map.pair_ends.is_empty() {
        legend.push(LegendEntry {
            sample: LegendSample::Marker(kind_colour(BifurcationKind::SaddleNode)),
            text: "cusp: a fold pair ends inside the bracket (grid or bisection)".into(),
        });
    }
    Figure {
        title: format!("Operating map over {}", map.param),
        panels,
        legend,
        legend_at: LegendAt::Right,
        size,
        ..Figure::default()
    }
}
