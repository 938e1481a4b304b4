//! `replay plot FILE [--out DIR] [--format png,svg] [--node ID] [--thermal-node ID]
//! [--point N] [--title]`: figures of one recording, drawn with the shared helpers of
//! [`crate::figure`], each as PNG and/or SVG (`<name>.png`, `<name>.svg`).
//!
//! | figure | what |
//! |---|---|
//! | `amplitude_node<id>` | RMS amplitude of each dynamic node against ω: stable parts blue, unstable red, not assessed grey; bifurcations circled and labelled SN / PD / NS, in grey with `?` (a fold the multipliers do not confirm), `~` (moved at a higher truncation order) or `!` (unsettled at a higher order), those that vanished at a higher order left out; period-doubled points ([`PERIOD_DOUBLED_SHARE`]) dotted in purple |
//! | `clearance` | RC variation δv of every bearing against ω (unstable parts dashed) |
//! | `temperatures` | mean temperatures against ω, a panel per bearing (its rolling elements, rings, lubricant, housing, named in the legend) and one of the shafts and disks |
//! | `temperature_node<id>` | mean temperature of one thermal node against ω in the stability colours, bifurcations circled |
//! | `multipliers_bifurcations` | Floquet multipliers against the unit circle, a panel per located bifurcation: the located point's multipliers (NS, PD of the fast multipliers), or the counted multipliers of the points on either side (SN, NS of the near-zero exponents: the fast ones outside their disk and `exp(λP)` of the exponents) |
//! | `multipliers_point<N>` | the multipliers of one point against the unit circle |
//! | `orbits_peaks` | orbits (x vertical over y horizontal, equal scales) of the dynamic nodes at the resonant peaks of the chosen node, a panel per peak and rotor, re-derived from the harmonic coefficients |
//! | `bearing_loads_point<N>` | radial load of each bearing over one response period at one point (re-derived through the embedded model, else the recorded samples) |
//! | `bearing_loads_mean` | mean radial load of each bearing against ω (stability colours) with its range over a period |
//!
//! Text needs a TrueType font ([`crate::figure::font`]); without one the figures are drawn
//! without any text and a note says so.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use num_complex::Complex64;
use plotters::style::{BLACK, RGBColor};

use crate::derive::{self, PERIOD_DOUBLED_SHARE, is_period_doubled, rederivers_for};
use crate::figure::{
    self, BranchStyle, Chart, Figure, LegendAt, LegendEntry, LegendSample, LineStyle, Marker,
    OMEGA, Output, PALETTE, Series, branch_series, colour, font, node_temperature_panels, tick,
    write_figure,
};
use crate::record::reader::Recording;
use crate::record::types::BearingLoad;
use crate::record::{BifurcationRecord, PointRecord, RunInfo};
use crate::stability::BifurcationKind;

/// What `replay plot` draws and how.
#[derive(Clone, Debug, Default)]
pub struct PlotOptions {
    pub output: Output,
    /// Dynamic node whose resonant peaks give the orbits and whose highest point is the
    /// default point (default: node 8 when recorded, else the first).
    pub node: Option<u32>,
    /// Thermal node of `temperature_node<id>` (default: 58, the paper's Fig. 15, for the
    /// built-in dual rotor; else the hottest node at the last point).
    pub thermal_node: Option<u32>,
    /// Point of the multiplier and bearing-load figures (default: the highest amplitude of
    /// the chosen node).
    pub point: Option<u64>,
}

const SIZE: (u32, u32) = (1100, 650);
const PERIOD_DOUBLED: RGBColor = RGBColor(148, 103, 189);
const BEFORE: RGBColor = PALETTE[0];
const AFTER: RGBColor = PALETTE[1];
const AT: RGBColor = PALETTE[3];

/// `"node 8"`, or `"node 1 (disk)"` for a node with a name of its own.
fn node_label(id: u32, name: &str) -> String {
    if name == format!("node {id}") || name.is_empty() {
        format!("node {id}")
    } else {
        format!("node {id} ({name})")
    }
}

/// Samples per response period for smooth curves: 24 per cycle of the highest harmonic,
/// 256 to 4096.
fn period_samples(run: &RunInfo) -> usize {
    run.basis()
        .map_or(256, |b| 24 * b.max_integer_multiple() as usize)
        .clamp(256, 4096)
}

/// Revolutions of the reference rotor in one response period (`ωT / 2π`).
fn period_revolutions(run: &RunInfo) -> f64 {
    run.basis().map_or(1.0, |b| f64::from(b.base_den()))
}

fn omega_at(x: f64) -> String {
    format!("ω = {x:.1} rad/s")
}

/// Dots at the points whose response is period-doubled; `None` when there are none.
fn period_doubled_dots(rec: &Recording, y: impl Fn(&PointRecord) -> Option<f64>) -> Option<Series> {
    let points: Vec<(f64, f64)> = rec
        .points
        .iter()
        .filter(|p| {
            rec.run_of(p.branch)
                .is_some_and(|run| is_period_doubled(&run, p))
        })
        .filter_map(|p| Some((p.omega_rad_s, y(p)?)))
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

fn bifurcation_label(b: &BifurcationRecord) -> String {
    crate::figure::bifurcation_label(b.kind, b.number)
}

/// Grey: the circle of a bifurcation the figure flags.
const FLAGGED: RGBColor = RGBColor(140, 140, 140);

/// The legend entry explaining the flags that occur among `bifs`.
fn flag_entry(rec: &Recording, bifs: &[BifurcationRecord]) -> Option<LegendEntry> {
    let text = crate::figure::flag_legend_text(
        bifs.iter()
            .filter_map(|b| crate::figure::bifurcation_flag(rec, b)),
    )?;
    Some(LegendEntry {
        sample: LegendSample::Marker(FLAGGED),
        text,
    })
}

/// The legend entry of the bifurcation circles, naming the kinds that occur.
fn bifurcation_entry(bifs: &[BifurcationRecord]) -> Option<LegendEntry> {
    let mut kinds: Vec<String> = Vec::new();
    for b in bifs {
        let name = match b.kind {
            BifurcationKind::SaddleNode => "saddle-node",
            BifurcationKind::PeriodDoubling => "period doubling",
            BifurcationKind::NeimarkSacker => "Neimark–Sacker",
        };
        let k = format!("{} {name}", b.kind.abbreviation());
        if !kinds.contains(&k) {
            kinds.push(k);
        }
    }
    (!kinds.is_empty()).then(|| LegendEntry {
        sample: LegendSample::Marker(BLACK),
        text: format!("bifurcation: {}", kinds.join(", ")),
    })
}

/// `(ω, y, stable)` of every point, with a break (no y) where the branch changes: each
/// branch of the recording is its own line.
fn per_branch(
    rec: &Recording,
    f: impl Fn(usize, &PointRecord) -> (f64, Option<f64>, Option<bool>),
) -> Vec<(f64, Option<f64>, Option<bool>)> {
    let mut out = Vec::with_capacity(rec.points.len());
    for (i, p) in rec.points.iter().enumerate() {
        if i > 0 && rec.points[i - 1].branch != p.branch {
            out.push((p.omega_rad_s, None, None));
        }
        out.push(f(i, p));
    }
    out
}

/// One panel against ω in the stability colours, with its legend to the right.
fn branch_figure(
    rec: &Recording,
    title: String,
    y_desc: String,
    y: impl Fn(&PointRecord) -> Option<f64>,
    marker_y: impl Fn(&BifurcationRecord) -> Option<f64>,
) -> Figure {
    let mut series = branch_series(
        per_branch(rec, |_, p| (p.omega_rad_s, y(p), p.stable)),
        BranchStyle::Colours,
    );
    series.extend(period_doubled_dots(rec, &y));
    // bifurcations that vanished at a higher truncation order are not results
    let results: Vec<BifurcationRecord> = rec
        .bifurcations
        .iter()
        .filter(|b| !rec.vanished(b))
        .cloned()
        .collect();
    let markers = results
        .iter()
        .filter_map(|b| {
            let flag = crate::figure::bifurcation_flag(rec, b);
            Some(Marker {
                x: b.omega_rad_s,
                y: marker_y(b)?,
                label: format!(
                    "{}{}",
                    bifurcation_label(b),
                    flag.map(String::from).unwrap_or_default()
                ),
                colour: if flag.is_some() { FLAGGED } else { BLACK },
            })
        })
        .collect::<Vec<_>>();
    let chart = Chart {
        x_desc: OMEGA.into(),
        y_desc,
        series,
        ..Chart::default()
    };
    let mut legend = Figure::legend_from_series(std::slice::from_ref(&chart));
    if !markers.is_empty() {
        legend.extend(bifurcation_entry(&results));
        legend.extend(flag_entry(rec, &results));
    }
    Figure {
        title,
        panels: vec![Chart { markers, ..chart }],
        legend,
        size: SIZE,
        ..Figure::default()
    }
}

/// Value of `y` at a bifurcation, interpolated on the arc length between the points on
/// either side.
fn between(
    rec: &Recording,
    b: &BifurcationRecord,
    y: impl Fn(&PointRecord) -> Option<f64>,
) -> Option<f64> {
    let p = rec.point(b.after_point)?;
    let q = rec.point(b.after_point + 1)?;
    let (yp, yq) = (y(p)?, y(q)?);
    let span = q.arc_length - p.arc_length;
    let t = if span.abs() > 0.0 {
        ((b.arc_length - p.arc_length) / span).clamp(0.0, 1.0)
    } else {
        0.5
    };
    Some(yp + t * (yq - yp))
}

/// The dynamic node the peaks and the default point follow: `wanted`, else 8, else the
/// first. Errors name the recorded nodes.
fn chosen_node(run: &RunInfo, wanted: Option<u32>) -> anyhow::Result<Option<usize>> {
    match wanted {
        Some(id) => run
            .nodes
            .iter()
            .position(|n| n.id == id)
            .map(Some)
            .with_context(|| {
                let ids: Vec<String> = run.nodes.iter().map(|n| n.id.to_string()).collect();
                format!(
                    "no dynamic node {id} in the recording (nodes: {})",
                    ids.join(", ")
                )
            }),
        None => Ok(run
            .nodes
            .iter()
            .position(|n| n.id == 8)
            .or((!run.nodes.is_empty()).then_some(0))),
    }
}

/// Indices of the `most` highest resonant peaks of `y` along the branch
/// ([`crate::derive::peaks::resonant_peaks`], the report's rule), in branch order.
pub fn resonant_peaks(y: &[f64], most: usize) -> Vec<usize> {
    let values: Vec<Option<f64>> = y.iter().map(|v| v.is_finite().then_some(*v)).collect();
    let mut peaks = crate::derive::peaks::resonant_peaks(&values);
    peaks.sort_by(|&a, &b| y[b].total_cmp(&y[a]));
    peaks.truncate(most);
    peaks.sort_unstable();
    peaks
}

/// The unit circle with multipliers: `sets` of (legend text, colour, multipliers).
fn unit_circle(title: String, sets: Vec<(String, RGBColor, &[Complex64])>) -> Chart {
    let circle: Vec<(f64, f64)> = (0..=360)
        .map(|k| {
            let a = (k as f64).to_radians();
            (a.cos(), a.sin())
        })
        .collect();
    let reach = sets
        .iter()
        .flat_map(|s| s.2.iter().map(|m| m.norm()))
        .fold(1.0_f64, f64::max)
        * 1.08;
    let mut series = vec![Series {
        width: 1,
        label: Some("unit circle".into()),
        ..Series::new(circle, figure::REFERENCE)
    }];
    for (k, (label, c, mults)) in sets.into_iter().enumerate() {
        series.push(Series {
            line: LineStyle::Points,
            width: if k == 0 { 5 } else { 4 },
            label: Some(label),
            ..Series::new(mults.iter().map(|m| (m.re, m.im)).collect(), c)
        });
    }
    Chart {
        title,
        x_desc: "Re μ".into(),
        y_desc: "Im μ".into(),
        series,
        x_range: Some((-reach, reach)),
        y_range: Some((-reach, reach)),
        equal_aspect: true,
        font_px: 14,
        title_px: 16,
        ..Chart::default()
    }
}

struct Plotter<'a> {
    rec: &'a Recording,
    dir: &'a Path,
    options: &'a PlotOptions,
    written: Vec<std::path::PathBuf>,
    notes: Vec<String>,
}

impl Plotter<'_> {
    fn write(&mut self, name: &str, fig: &Figure) -> anyhow::Result<()> {
        let w = write_figure(&self.dir.join(name), fig, &self.options.output)?;
        let left_out = w
            .layout
            .panels
            .iter()
            .flat_map(|p| &p.labels)
            .filter(|l| l.is_none())
            .count();
        if left_out > 0 && font().is_some() {
            self.notes.push(format!(
                "{name}: {left_out} bifurcation label(s) left out where they would cover data or another label (the circles are drawn)"
            ));
        }
        self.written.extend(w.files);
        Ok(())
    }

    fn amplitudes(&mut self) -> anyhow::Result<()> {
        let run = &self.rec.run;
        for (k, node) in run.nodes.iter().enumerate() {
            let label = node_label(node.id, &node.name);
            let fig = branch_figure(
                self.rec,
                format!("Amplitude–frequency response, {label}"),
                format!("RMS amplitude, {label} (µm)"),
                |p| p.amplitude_rms_m.get(k).map(|a| a * 1e6),
                |b| b.amplitude_rms_m.get(k).map(|a| a * 1e6),
            );
            self.write(&format!("amplitude_node{}", node.id), &fig)?;
        }
        Ok(())
    }

    fn clearance(&mut self) -> anyhow::Result<()> {
        let rec = self.rec;
        if !rec.points.iter().any(|p| !p.clearances.is_empty()) {
            return Ok(());
        }
        let mut series = Vec::new();
        for (b, info) in rec.run.bearings.iter().enumerate() {
            let c = colour(b);
            let mut s = branch_series(
                per_branch(rec, |_, p| {
                    (
                        p.omega_rad_s,
                        p.clearances.get(b).map(|c| c.delta_v_m * 1e6),
                        p.stable,
                    )
                }),
                BranchStyle::Dashes(c),
            );
            if let Some(first) = s.iter_mut().find(|s| s.colour == c) {
                first.label = Some(format!("bearing {}", info.name));
            }
            series.extend(s);
        }
        let chart = Chart {
            x_desc: OMEGA.into(),
            y_desc: "radial clearance variation δv (µm)".into(),
            series,
            hlines: vec![0.0],
            ..Chart::default()
        };
        let mut legend = Figure::legend_from_series(std::slice::from_ref(&chart));
        legend.extend(dashes_entry(rec));
        self.write(
            "clearance",
            &Figure {
                title: "Radial clearance variation of the bearings".into(),
                panels: vec![chart],
                legend,
                size: SIZE,
                ..Figure::default()
            },
        )
    }

    fn temperatures(&mut self) -> anyhow::Result<()> {
        let rec = self.rec;
        let run = &rec.run;
        if run.thermal_nodes.is_empty() || !rec.points.iter().any(|p| !p.temperatures.is_empty()) {
            return Ok(());
        }
        let fig = temperature_groups(rec);
        self.write("temperatures", &fig)?;

        // one node in the stability colours (the paper's Fig. 15)
        let t = match self.options.thermal_node {
            Some(id) => run
                .thermal_nodes
                .iter()
                .position(|n| n.id == id)
                .with_context(|| {
                    format!(
                        "no thermal node {id} in the recording (nodes 1 to {}; `replay info` lists them)",
                        run.thermal_nodes.len()
                    )
                })?,
            None => default_thermal_node(rec),
        };
        let node = &run.thermal_nodes[t];
        let nc = run.n_coeffs();
        let temp = |p: &PointRecord| p.temperatures.get(t).map(|s| s.mean_c);
        let fig = branch_figure(
            rec,
            format!(
                "Mean temperature of thermal node {} ({})",
                node.id, node.name
            ),
            format!(
                "mean temperature, {} (thermal node {}) (°C)",
                node.name, node.id
            ),
            temp,
            |b| {
                b.coeffs_therm
                    .get(node.dof * nc)
                    .copied()
                    .or_else(|| between(rec, b, temp))
            },
        );
        self.write(&format!("temperature_node{}", node.id), &fig)
    }

    fn multipliers(&mut self, point: Option<&PointRecord>) -> anyhow::Result<()> {
        let rec = self.rec;
        let mut panels = Vec::new();
        let mut used = [false; 3];
        // what the stable flag counts: the fast multipliers outside the disk of the
        // coupled exponents nearest zero, and exp(λP) of those (docs/stability.md)
        let counted: Vec<Vec<Complex64>> =
            rec.points.iter().map(|p| p.counted_multipliers()).collect();
        let counted_at = |idx: u64| {
            rec.points
                .iter()
                .position(|p| p.index == idx)
                .map(|i| counted[i].as_slice())
                .filter(|m| !m.is_empty())
        };
        for b in &rec.bifurcations {
            let title = format!(
                "{} at {}{}{}{}",
                bifurcation_label(b),
                omega_at(b.omega_rad_s),
                if b.confirmed { "" } else { " (not confirmed)" },
                if rec.vanished(b) {
                    " (vanished at a higher order)"
                } else {
                    ""
                },
                b.modulation
                    .map(|m| format!(
                        ", {}{:.0} s",
                        if m.thermo_mechanical() {
                            "thermo-mech., "
                        } else {
                            ""
                        },
                        m.period_s
                    ))
                    .unwrap_or_default()
            );
            let mut sets: Vec<(String, RGBColor, &[Complex64])> = Vec::new();
            if !b.multipliers.is_empty()
                && b.kind != BifurcationKind::SaddleNode
                && b.modulation.is_none_or(|m| m.exponent.is_none())
            {
                sets.push(("at the located bifurcation".into(), AT, &b.multipliers));
                used[2] = true;
            } else {
                for (idx, text, c, u) in [
                    (b.after_point, "point before", BEFORE, 0),
                    (b.after_point + 1, "point after", AFTER, 1),
                ] {
                    if let Some(m) = counted_at(idx) {
                        sets.push((text.into(), c, m));
                        used[u] = true;
                    }
                }
            }
            if !sets.is_empty() {
                panels.push(unit_circle(title, sets));
            }
        }
        if !panels.is_empty() {
            let mut legend = vec![LegendEntry {
                sample: LegendSample::Line(figure::REFERENCE, LineStyle::Solid),
                text: "unit circle".into(),
            }];
            for (u, (text, c)) in used.iter().zip([
                (
                    "multipliers of the point before (SN; NS of the near-zero exponents)",
                    BEFORE,
                ),
                (
                    "multipliers of the point after (SN; NS of the near-zero exponents)",
                    AFTER,
                ),
                ("multipliers at the located bifurcation (PD, NS)", AT),
            ]) {
                if *u {
                    legend.push(LegendEntry {
                        sample: LegendSample::Line(c, LineStyle::Points),
                        text: text.into(),
                    });
                }
            }
            let n = panels.len();
            let cols = n.min(3);
            let rows = n.div_ceil(cols);
            self.write(
                "multipliers_bifurcations",
                &Figure {
                    title: "Floquet multipliers at the bifurcations".into(),
                    grid: Some((rows, cols)),
                    panels,
                    legend,
                    legend_at: LegendAt::Below,
                    size: (420 * cols as u32 + 40, 420 * rows as u32 + 70),
                },
            )?;
        }
        if let Some(p) = point.filter(|p| !p.multipliers.is_empty()) {
            let state = match p.stable {
                Some(true) => "stable",
                Some(false) => "unstable",
                None => "not assessed",
            };
            let chart = unit_circle(
                format!("point {}, {}, {state}", p.index, omega_at(p.omega_rad_s)),
                vec![(
                    format!("multipliers of point {}", p.index),
                    RGBColor(0, 0, 0),
                    &p.multipliers,
                )],
            );
            let legend = Figure::legend_from_series(std::slice::from_ref(&chart));
            self.write(
                &format!("multipliers_point{}", p.index),
                &Figure {
                    title: format!("Floquet multipliers of point {}", p.index),
                    panels: vec![Chart {
                        title: String::new(),
                        ..chart
                    }],
                    legend,
                    size: (820, 600),
                    ..Figure::default()
                },
            )?;
        }
        Ok(())
    }

    fn orbits(&mut self, k: usize) -> anyhow::Result<()> {
        let rec = self.rec;
        let run = &rec.run;
        let amplitude: Vec<f64> = rec
            .points
            .iter()
            .map(|p| p.amplitude_rms_m.get(k).copied().unwrap_or(f64::NAN))
            .collect();
        let peaks = resonant_peaks(&amplitude, 4);
        if peaks.is_empty() {
            self.notes.push(format!(
                "orbits_peaks not written: the amplitude of node {} has no resonant peak",
                run.nodes[k].id
            ));
            return Ok(());
        }
        let mut rotors: Vec<&str> = Vec::new();
        for n in &run.nodes {
            if !rotors.contains(&n.rotor.as_str()) {
                rotors.push(&n.rotor);
            }
        }
        let mut panels = Vec::new();
        for &i in &peaks {
            let p = &rec.points[i];
            let own = rec.run_of(p.branch).ok_or_else(|| {
                anyhow::anyhow!("point {}: branch {} not described", p.index, p.branch)
            })?;
            let orbits = derive::orbits(&own, &p.coeffs_mech, p.omega_rad_s, period_samples(&own))?;
            for rotor in &rotors {
                let series = run
                    .nodes
                    .iter()
                    .zip(&orbits)
                    .enumerate()
                    .filter(|(_, (n, _))| n.rotor == *rotor)
                    .map(|(j, (n, o))| {
                        let mut pts: Vec<(f64, f64)> = o
                            .y_m
                            .iter()
                            .zip(&o.x_m)
                            .map(|(y, x)| (y * 1e6, x * 1e6))
                            .collect();
                        if let Some(&first) = pts.first() {
                            pts.push(first);
                        }
                        // thin: plotters draws wide lines of short segments dotted
                        Series {
                            width: 1,
                            label: Some(node_label(n.id, &n.name)),
                            ..Series::new(pts, colour(j))
                        }
                    })
                    .collect();
                let rotor_name = if rotor.is_empty() {
                    String::new()
                } else {
                    format!("{rotor} rotor, ")
                };
                panels.push(Chart {
                    title: format!(
                        "{rotor_name}peak at {} (point {})",
                        omega_at(p.omega_rad_s),
                        p.index
                    ),
                    x_desc: "horizontal displacement y (µm)".into(),
                    y_desc: "vertical displacement x (µm)".into(),
                    series,
                    equal_aspect: true,
                    font_px: 14,
                    title_px: 16,
                    ..Chart::default()
                });
            }
        }
        let legend = Figure::legend_from_series(&panels);
        let (rows, cols) = (peaks.len(), rotors.len().max(1));
        self.write(
            "orbits_peaks",
            &Figure {
                title: format!(
                    "Orbits at the resonant peaks of {}",
                    node_label(run.nodes[k].id, &run.nodes[k].name)
                ),
                grid: Some((rows, cols)),
                panels,
                legend,
                legend_at: LegendAt::Right,
                size: (520 * cols as u32 + 220, 430 * rows as u32 + 20),
            },
        )
    }

    fn bearing_loads(&mut self, point: Option<&PointRecord>) -> anyhow::Result<()> {
        let rec = self.rec;
        // the chosen point's branch gives the basis
        let branch = point.map_or(0, |p| p.branch);
        let own = rec
            .run_of(branch)
            .ok_or_else(|| anyhow::anyhow!("branch {branch} is not described"))?;
        let run = &*own;
        if run.bearings.is_empty() {
            return Ok(());
        }
        let hooks = rederivers_for(run);
        if let Some(p) = point {
            self.bearing_loads_at(run, &hooks, p)?;
        }
        self.bearing_loads_mean(run, &hooks)
    }

    /// `bearing_loads_point<N>`: the radial load of each bearing over one response period
    /// at point `p` (re-derived through the embedded model, else the recorded samples).
    fn bearing_loads_at(
        &mut self,
        run: &RunInfo,
        hooks: &derive::Rederivers,
        p: &PointRecord,
    ) -> anyhow::Result<()> {
        let loads = match &hooks.model {
            Some(model) => Some(model.bearings(p, period_samples(run))?.loads),
            None => {
                let recorded = p.bearing_loads.iter().any(|l| !l.radial_n.is_empty());
                self.notes.push(format!(
                    "bearing loads of point {} {}: {}",
                    p.index,
                    if recorded {
                        "drawn from the recorded samples"
                    } else {
                        "not drawn"
                    },
                    hooks.unavailable_reason
                ));
                recorded.then(|| p.bearing_loads.clone())
            }
        };
        if let Some(loads) = loads {
            let series: Vec<Series> = loads
                .iter()
                .zip(&run.bearings)
                .enumerate()
                .map(|(b, (l, info))| {
                    let n = l.radial_n.len().max(1) as f64;
                    let revs = period_revolutions(run);
                    let mut pts: Vec<(f64, f64)> = l
                        .radial_n
                        .iter()
                        .enumerate()
                        .map(|(k, f)| (revs * k as f64 / n, *f))
                        .collect();
                    if let Some(&(_, f)) = pts.first() {
                        pts.push((revs, f));
                    }
                    Series {
                        label: Some(format!("bearing {}", info.name)),
                        ..Series::new(pts, colour(b))
                    }
                })
                .collect();
            let chart = Chart {
                x_desc: "revolutions, ωt / 2π (one response period)".into(),
                y_desc: "radial bearing load (N)".into(),
                series,
                x_range: Some((0.0, period_revolutions(run))),
                ..Chart::default()
            };
            let legend = Figure::legend_from_series(std::slice::from_ref(&chart));
            self.write(
                &format!("bearing_loads_point{}", p.index),
                &Figure {
                    title: format!(
                        "Radial bearing loads over one period, point {}, {}",
                        p.index,
                        omega_at(p.omega_rad_s)
                    ),
                    panels: vec![chart],
                    legend,
                    size: SIZE,
                    ..Figure::default()
                },
            )?;
        }
        Ok(())
    }

    /// `bearing_loads_mean`: the mean radial load of each bearing against ω (stability
    /// colours) with its range over a period: recorded, else re-derived.
    fn bearing_loads_mean(
        &mut self,
        run: &RunInfo,
        hooks: &derive::Rederivers,
    ) -> anyhow::Result<()> {
        let rec = self.rec;
        let recorded = rec
            .points
            .iter()
            .all(|p| p.bearing_loads.len() == run.bearings.len());
        let stats: Vec<Vec<(f64, f64, f64)>> = if recorded {
            rec.points
                .iter()
                .map(|p| load_stats(&p.bearing_loads))
                .collect()
        } else if let Some(model) = &hooks.model {
            self.notes.push(
                "bearing_loads_mean: the recording has no bearing loads; re-derived through the embedded model".into(),
            );
            rec.points
                .iter()
                .map(|p| Ok(load_stats(&model.bearings(p, 64)?.loads)))
                .collect::<anyhow::Result<_>>()?
        } else {
            self.notes.push(format!(
                "bearing_loads_mean not written: no bearing loads recorded and {}",
                hooks.unavailable_reason
            ));
            return Ok(());
        };
        let mut panels = Vec::new();
        for (b, info) in run.bearings.iter().enumerate() {
            let mut series = branch_series(
                per_branch(rec, |i, p| {
                    (p.omega_rad_s, stats[i].get(b).map(|s| s.0), p.stable)
                }),
                BranchStyle::Colours,
            );
            // the lowest, then the highest load over a period: one legend entry
            for k in [1, 2] {
                let label = "lowest and highest over one period";
                series.push(Series {
                    width: 1,
                    label: Some(label.into()),
                    ..Series::new(
                        rec.points
                            .iter()
                            .enumerate()
                            .filter_map(|(i, p)| {
                                let s = stats[i].get(b)?;
                                Some((p.omega_rad_s, if k == 1 { s.1 } else { s.2 }))
                            })
                            .collect(),
                        figure::lighter(figure::REFERENCE, 0.4),
                    )
                });
            }
            panels.push(Chart {
                title: format!("bearing {}", info.name),
                x_desc: OMEGA.into(),
                y_desc: "radial load (N)".into(),
                series,
                font_px: 14,
                title_px: 16,
                ..Chart::default()
            });
        }
        let legend = Figure::legend_from_series(&panels);
        self.write(
            "bearing_loads_mean",
            &Figure {
                title: "Mean radial bearing loads".into(),
                panels,
                legend,
                legend_at: LegendAt::Below,
                size: (1200, 800),
                ..Figure::default()
            },
        )
    }
}

/// Mean, lowest and highest radial load of each bearing.
fn load_stats(loads: &[BearingLoad]) -> Vec<(f64, f64, f64)> {
    loads
        .iter()
        .map(|l| {
            let lo = l.radial_n.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = l.radial_n.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (l.mean_n, lo, hi)
        })
        .collect()
}

/// The legend entries saying how stability is drawn in figures of several coloured curves.
fn dashes_entry(rec: &Recording) -> Vec<LegendEntry> {
    let grey = RGBColor(90, 90, 90);
    if rec.points.iter().any(|p| p.stable == Some(false)) {
        vec![
            LegendEntry {
                sample: LegendSample::Line(grey, LineStyle::Solid),
                text: "stable".into(),
            },
            LegendEntry {
                sample: LegendSample::Line(figure::unstable_of(grey), LineStyle::Dashed),
                text: "unstable".into(),
            },
        ]
    } else {
        Vec::new()
    }
}

/// The thermal node of `temperature_node<id>` when none is asked for: 58 (the paper's
/// Fig. 15) in the built-in dual rotor, else the hottest at the last point.
fn default_thermal_node(rec: &Recording) -> usize {
    let run = &rec.run;
    if run.model_name == "dual_rotor"
        && let Some(t) = run.thermal_nodes.iter().position(|n| n.id == 58)
    {
        return t;
    }
    rec.points
        .iter()
        .rev()
        .find(|p| !p.temperatures.is_empty())
        .and_then(|p| {
            p.temperatures
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.mean_c.total_cmp(&b.1.mean_c))
                .map(|(t, _)| t)
        })
        .unwrap_or(0)
}

/// Mean temperatures against ω, a panel per group of [`thermal_groups`], one y range.
fn temperature_groups(rec: &Recording) -> Figure {
    let run = &rec.run;
    let names: Vec<(u32, &str)> = run
        .thermal_nodes
        .iter()
        .map(|n| (n.id, n.name.as_str()))
        .collect();
    let bearings: Vec<&str> = run.bearings.iter().map(|b| b.name.as_str()).collect();
    let panels = node_temperature_panels(&names, &bearings, |t| {
        per_branch(rec, |_, p| {
            (
                p.omega_rad_s,
                p.temperatures.get(t).map(|s| s.mean_c),
                p.stable,
            )
        })
    });
    let several = panels.len() > 1;
    let mut legend = Figure::legend_from_series(&panels);
    legend.extend(dashes_entry(rec));
    Figure {
        title: "Mean temperatures of the thermal nodes".into(),
        size: if several { (1300, 850) } else { SIZE },
        legend_at: if several {
            LegendAt::Below
        } else {
            LegendAt::Right
        },
        panels,
        legend,
        ..Figure::default()
    }
}

/// Writes the figures into `dir` and lists them on `out`, notes on `err`.
pub fn run(
    rec: &Recording,
    dir: &Path,
    options: &PlotOptions,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    crate::input::ensure_dir(dir).with_context(|| format!("output directory {}", dir.display()))?;
    if rec.points.is_empty() {
        anyhow::bail!("{} has no points to plot", rec.file.display());
    }
    if font().is_none() {
        writeln!(
            err,
            "note: no TrueType font found (set TMROTOR_FONT to a .ttf file); figures have no text"
        )?;
    }
    let node = chosen_node(&rec.run, options.node)?;
    let point = match options.point {
        Some(n) => Some(rec.point(n).with_context(|| {
            let last = rec.points.last().map_or(0, |p| p.index);
            format!(
                "{} has no point {n} (points 0 to {last}; `replay branch` lists them)",
                rec.file.display()
            )
        })?),
        None => node.and_then(|k| {
            rec.points.iter().max_by(|a, b| {
                let a = a.amplitude_rms_m.get(k).copied().unwrap_or(f64::NAN);
                let b = b.amplitude_rms_m.get(k).copied().unwrap_or(f64::NAN);
                a.total_cmp(&b)
            })
        }),
    };
    let mut plotter = Plotter {
        rec,
        dir,
        options,
        written: Vec::new(),
        notes: Vec::new(),
    };
    plotter.amplitudes()?;
    plotter.clearance()?;
    plotter.temperatures()?;
    plotter.multipliers(point)?;
    if let Some(k) = node {
        plotter.orbits(k)?;
    }
    plotter.bearing_loads(point)?;
    if options.point.is_none()
        && let Some(p) = point
    {
        writeln!(
            err,
            "note: point {} ({}, the highest amplitude) is the point of the multiplier and \
             bearing-load figures; --point N chooses another",
            p.index,
            tick(&p.omega_rad_s)
        )?;
    }
    for note in &plotter.notes {
        writeln!(err, "note: {note}")?;
    }
    for p in plotter.written {
        writeln!(out, "wrote {}", p.display())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{BLACK, FLAGGED, branch_figure, resonant_peaks};
    use crate::record::reader::read_recording;
    use crate::record::synthetic::{SyntheticOptions, write_mcap};

    #[test]
    fn amplitude_figures_flag_unconfirmed_bifurcations() {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let path = dir.path().join("s.mcap");
        write_mcap(&path, &SyntheticOptions::default(), true).expect("a synthetic recording");
        let mut rec = read_recording(&path).expect("it reads back");
        assert!(rec.bifurcations.len() >= 2, "{}", rec.bifurcations.len());
        rec.bifurcations[0].confirmed = false;
        let y = |p: &crate::record::PointRecord| p.amplitude_rms_m.first().copied();
        let fig = branch_figure(&rec, "t".into(), "y".into(), y, |b| {
            Some(b.omega_rad_s * 0.0)
        });
        let markers = &fig.panels[0].markers;
        assert_eq!(markers.len(), rec.bifurcations.len());
        assert!(markers[0].label.ends_with('?') && markers[0].colour == FLAGGED);
        assert!(!markers[1].label.ends_with('?') && markers[1].colour == BLACK);
        assert!(
            fig.legend
                .iter()
                .any(|e| e.text.contains("? not confirmed by the multipliers")),
            "{:?}",
            fig.legend.iter().map(|e| &e.text).collect::<Vec<_>>()
        );
    }

    #[test]
    fn peaks_are_prominent_local_maxima() {
        let y = [1.0, 3.0, 2.0, 2.05, 2.0, 8.0, 4.0, 5.0, 1.0];
        // 3.0 stands out by 1.0 (≥ 10 % of 3.0), 2.05 by 0.05 (no), 8.0 is the highest,
        // 5.0 stands out by 1.0
        assert_eq!(resonant_peaks(&y, 4), vec![1, 5, 7]);
        assert_eq!(resonant_peaks(&y, 2), vec![5, 7]);
        assert!(resonant_peaks(&[1.0, 1.0, 1.0], 3).is_empty());
    }
}
