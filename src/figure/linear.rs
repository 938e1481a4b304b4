//! Figures of the linear analyses: the Campbell diagram, mode shapes along the shaft, and
//! the unbalance response (Bode and polar).

use num_complex::Complex;

use crate::figure::{
    Chart, Figure, LegendAt, LegendEntry, LegendSample, LineStyle, Marker, OMEGA, PALETTE, Series,
    colour,
};
use crate::linear::{Campbell, Mode, NodeOrbit, UnbalanceResponse, Whirl};

const FORWARD: plotters::style::RGBColor = PALETTE[0];
const BACKWARD: plotters::style::RGBColor = PALETTE[3];
const GREY: plotters::style::RGBColor = plotters::style::RGBColor(90, 90, 90);

fn whirl_colour(w: Whirl) -> plotters::style::RGBColor {
    match w {
        Whirl::Forward => FORWARD,
        Whirl::Backward => BACKWARD,
        Whirl::Planar => GREY,
    }
}

/// The Campbell diagram: each followed mode's frequency against speed, drawn in the colour
/// of its whirl at each speed (blue forward, red backward, grey planar), every rotor's 1×
/// line dashed, and the critical speeds circled (labelled `F`/`B` and numbered; an open
/// label for those unbalance does not excite).
pub fn campbell_figure(c: &Campbell, title: &str) -> Figure {
    let mut chart = Chart {
        x_desc: OMEGA.into(),
        y_desc: "frequency (rad/s)".into(),
        ..Chart::default()
    };
    let n_modes = c.points.iter().map(|p| p.modes.len()).max().unwrap_or(0);
    for i in 0..n_modes {
        // pieces of one whirl each, sharing their boundary point
        let mut piece: Vec<(f64, f64)> = Vec::new();
        let mut whirl = None;
        for p in &c.points {
            let Some(m) = p.modes.get(i) else { break };
            let pt = (p.speed_rad_s, m.frequency_rad_s);
            if whirl.is_some_and(|w| w != m.whirl) {
                piece.push(pt);
                chart
                    .series
                    .push(mode_series(std::mem::take(&mut piece), whirl));
            }
            whirl = Some(m.whirl);
            piece.push(pt);
        }
        if piece.len() > 1 {
            chart.series.push(mode_series(piece, whirl));
        }
    }
    let (w0, w1) = (
        c.points.first().map_or(0.0, |p| p.speed_rad_s),
        c.points.last().map_or(1.0, |p| p.speed_rad_s),
    );
    for (k, (rotor, s)) in c.lines.iter().enumerate() {
        chart.series.push(Series {
            points: vec![(w0, s.abs() * w0), (w1, s.abs() * w1)],
            colour: colour(k + 4),
            line: LineStyle::Dashed,
            width: 1,
            label: Some(if *s < 0.0 {
                format!("1× {rotor} ({} ω, counter-rotating)", s.abs())
            } else {
                format!("1× {rotor} ({s} ω)")
            }),
        });
    }
    for (k, cs) in c.critical_speeds.iter().enumerate() {
        let tag = match cs.whirl {
            Whirl::Forward => "F",
            Whirl::Backward => "B",
            Whirl::Planar => "P",
        };
        chart.markers.push(Marker {
            x: cs.speed_rad_s,
            y: cs.frequency_rad_s,
            label: if cs.excited_by_unbalance() {
                format!("{tag}{}", k + 1)
            } else {
                format!("({tag}{})", k + 1)
            },
            colour: whirl_colour(cs.whirl),
        });
    }
    let y_max = c
        .points
        .iter()
        .flat_map(|p| p.modes.iter().map(|m| m.frequency_rad_s))
        .fold(0.0f64, f64::max);
    chart.x_range = Some((w0, w1));
    chart.y_range = Some((0.0, 1.05 * y_max.max(1e-9)));
    let mut legend = Figure::legend_from_series(std::slice::from_ref(&chart));
    legend.push(LegendEntry {
        sample: LegendSample::Marker(GREY),
        text: "critical speed (F/B: whirl; in brackets: not excited by unbalance)".into(),
    });
    Figure {
        title: title.into(),
        panels: vec![chart],
        legend,
        legend_at: LegendAt::Below,
        size: (1100, 800),
        ..Figure::default()
    }
}

fn mode_series(points: Vec<(f64, f64)>, whirl: Option<Whirl>) -> Series {
    let w = whirl.unwrap_or(Whirl::Planar);
    Series {
        points,
        colour: whirl_colour(w),
        line: LineStyle::Solid,
        width: 2,
        label: Some(format!("{w} whirl")),
    }
}

/// Mode shapes along the shaft: per mode the orbit's semi-major axis at each node against
/// the node's axial position (one line per rotor), scaled to a largest value of 1.
pub fn shapes_figure(
    modes: &[Mode],
    axial_m: &[f64],
    rotors: &[(String, Vec<usize>)],
    title: &str,
) -> Figure {
    let mut panels = Vec::new();
    for (k, m) in modes.iter().enumerate() {
        let major: Vec<f64> = (0..axial_m.len())
            .map(|i| major_axis(m.shape[4 * i], m.shape[4 * i + 1]))
            .collect();
        let top = major.iter().copied().fold(0.0, f64::max).max(1e-300);
        let mut chart = Chart {
            title: format!(
                "mode {}: {:.1} rad/s, {}, ζ = {:.4}",
                k + 1,
                m.frequency_rad_s,
                m.whirl,
                m.damping_ratio
            ),
            x_desc: "axial position (m)".into(),
            y_desc: "orbit major axis (scaled)".into(),
            y_range: Some((0.0, 1.05)),
            font_px: 13,
            title_px: 14,
            ..Chart::default()
        };
        for (r, (rotor, nodes)) in rotors.iter().enumerate() {
            let mut pts: Vec<(f64, f64)> = nodes
                .iter()
                .map(|&i| (axial_m[i], major[i] / top))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart.series.push(Series {
                points: pts,
                colour: colour(r),
                line: LineStyle::Solid,
                width: 2,
                label: Some(format!("rotor {rotor}")),
            });
        }
        panels.push(chart);
    }
    let legend = Figure::legend_from_series(&panels);
    let (rows, cols) = crate::figure::grid(panels.len());
    Figure {
        title: title.into(),
        panels,
        legend,
        legend_at: LegendAt::Below,
        size: (420 * cols as u32 + 100, 320 * rows as u32 + 120),
        ..Figure::default()
    }
}

fn major_axis(x: Complex<f64>, y: Complex<f64>) -> f64 {
    NodeOrbit { x, y }.major_axis()
}

/// Bode and polar plots of the unbalance response at the nodes `nodes` (DoF-order
/// positions with their ids): semi-major axis (log scale is not offered by the chart, so
/// µm on a linear axis) and the phase of x against speed, and the polar plot of x.
pub fn unbalance_figure(resp: &[UnbalanceResponse], nodes: &[(usize, u32)], title: &str) -> Figure {
    let mut amp = Chart {
        title: "orbit semi-major axis".into(),
        x_desc: OMEGA.into(),
        y_desc: "µm".into(),
        ..Chart::default()
    };
    let mut phase = Chart {
        title: "phase of x".into(),
        x_desc: OMEGA.into(),
        y_desc: "degrees".into(),
        y_range: Some((-180.0, 180.0)),
        ..Chart::default()
    };
    let mut polar = Chart {
        title: "polar (x)".into(),
        x_desc: "Re X (µm)".into(),
        y_desc: "Im X (µm)".into(),
        equal_aspect: true,
        ..Chart::default()
    };
    let mut rotors: Vec<&str> = Vec::new();
    for r in resp {
        if !rotors.contains(&r.rotor_id.as_str()) {
            rotors.push(&r.rotor_id);
        }
    }
    let mut k = 0;
    for rotor in &rotors {
        for &(i, id) in nodes {
            let rows: Vec<&UnbalanceResponse> =
                resp.iter().filter(|r| r.rotor_id == *rotor).collect();
            let label = if rotors.len() > 1 {
                format!("node {id}, unbalance of {rotor}")
            } else {
                format!("node {id}")
            };
            let c = colour(k);
            k += 1;
            let orbit = |r: &UnbalanceResponse| r.node(i);
            amp.series.push(Series {
                points: rows
                    .iter()
                    .map(|r| (r.speed_rad_s, orbit(r).major_axis() * 1e6))
                    .collect(),
                colour: c,
                line: LineStyle::Solid,
                width: 2,
                label: Some(label.clone()),
            });
            phase.series.push(Series {
                points: rows
                    .iter()
                    .map(|r| (r.speed_rad_s, orbit(r).x.arg().to_degrees()))
                    .collect(),
                colour: c,
                line: LineStyle::Points,
                width: 2,
                label: Some(label.clone()),
            });
            polar.series.push(Series {
                points: rows
                    .iter()
                    .map(|r| (orbit(r).x.re * 1e6, orbit(r).x.im * 1e6))
                    .collect(),
                colour: c,
                line: LineStyle::Solid,
                width: 2,
                label: Some(label),
            });
        }
    }
    let panels = vec![amp, phase, polar];
    let legend = Figure::legend_from_series(&panels);
    Figure {
        title: title.into(),
        panels,
        grid: Some((1, 3)),
        legend,
        legend_at: LegendAt::Below,
        size: (1500, 560),
    }
}
