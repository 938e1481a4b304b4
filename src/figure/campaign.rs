//! Figures of a campaign: the runs of an output directory overlaid on common axes, like the
//! paper's figures (`tmrotor campaign plot DIR`, and at the end of `tmrotor campaign FILE`).
//!
//! [`plot_campaign`] reads `DIR/manifest.toml` and every run's recording and writes, each
//! in the formats of [`FigureOptions::output`] (PNG and SVG by default, no title):
//!
//! | file | what | paper |
//! |---|---|---|
//! | `amplitude_node8` | RMS amplitude of dynamic node 8 against ω, one colour per run; period-doubled points (`ω/2` share ≥ 5 %) dotted | Figs. 8a, 9a, 10a, 21a |
//! | `amplitude_node8_per_run` | the same, a panel per run on shared axes ([`FigureOptions::per_run`]) | |
//! | `clearance_variation` | RC variation δv against ω, a panel per bearing | Figs. 8b, 9b, 10b, 21b |
//! | `effective_clearance` | effective clearance δe = δ0 + δv against ω, δ0 as a dashed line | section 5.2, Fig. 9b (δe of 2#, 4# above 5 δ0 near 620 rad/s) |
//! | `bearing_loads_mean` | mean radial load of each bearing against ω, a panel per bearing | Fig. 16 (averages) |
//! | `rolling_element_temperatures` | mean temperature of each bearing's rolling elements against ω | Fig. 14c |
//! | `temperature_node58` (and `_per_run`) | mean temperature of one thermal node against ω, bifurcations circled | Fig. 15 |
//! | `node_temperatures_<run>` | mean temperature of every thermal node against ω, a panel per bearing and one of the shafts and disks ([`figure::thermal_groups`]) | Figs. 14a, 14b |
//! | `temperature_extremes` | highest and lowest mean node temperature against ω | Figs. 14a, 14b, 22a |
//! | `bearing_temperatures_omega620` | rolling elements, rings, lubricant and housing of each bearing at the recorded point nearest to ω = 620 rad/s | Figs. 14d, 14e |
//!
//! On every curve, parts recorded as unstable are dashed and lighter; stable and
//! not-assessed parts are solid (the legend says which applies). Bifurcations are circled
//! in the run's colour and labelled SN / PD / NS with their number along the branch.
//! Legends give each run's name, lubricant flow rate and cooling temperature; a run that
//! did not complete (manifest status, or a recording cut short) is drawn as far as it goes
//! and marked "(incomplete)". A run the manifest lists as `pending` or `failed: …` whose
//! recording does not exist (not started, or failed before recording) stays in the legend
//! marked "(incomplete: no recording)"; any other missing or unreadable recording is an
//! error naming the file.
//!
//! Thermal nodes are found by the names the thermal network gives them (`"1# rolling
//! elements"`, `"1# inner ring"`, `"1# outer ring"`, `"1# lubricant"`, `"1# housing
//! seat"`), so any model file with a `[thermal]` section works; figures whose data no run
//! recorded are skipped with a note.

use std::path::{Path, PathBuf};

use plotters::style::{BLACK, RGBColor};
use rayon::prelude::*;

use crate::campaign::{CampaignError, ManifestEntry, read_manifest_file, sha256_file};
use crate::derive::{PERIOD_DOUBLED_SHARE, is_period_doubled};
use crate::figure::{
    self, BranchStyle, Chart, Figure, LegendAt, LegendEntry, LegendSample, LineStyle, Marker,
    OMEGA, Output, Series, share_axes, tick,
};
use crate::record::{ReadError, RunInfo, read_recording};
use crate::stability::BifurcationKind;
use crate::study::StudySettings;

/// What [`plot_campaign`] draws.
#[derive(Clone, Debug)]
pub struct FigureOptions {
    /// Dynamic nodes whose amplitude–frequency curves are drawn (one file each). Empty:
    /// node 8 (the paper's Fig. 8a) when recorded, else the first recorded node.
    pub nodes: Vec<u32>,
    /// ω of the bearing-position temperature chart, rad/s (default 620, the paper's
    /// Figs. 14d–e).
    pub omega_rad_s: f64,
    /// How far a run's nearest recorded point may lie from [`Self::omega_rad_s`] to be
    /// shown there, rad/s (default 10).
    pub omega_tolerance_rad_s: f64,
    /// Thermal node of `temperature_node<id>` (default: 58, the paper's Fig. 15, when
    /// every run has it and the model is the built-in dual rotor; else none is drawn).
    pub thermal_node: Option<u32>,
    /// Also draw the amplitude and node-temperature figures as small multiples, one panel
    /// per run on shared axes (`…_per_run`; default false).
    pub per_run: bool,
    /// Formats and title (default PNG and SVG, no title).
    pub output: Output,
    /// Size of every figure, pixels (default 1200 × 800).
    pub size: (u32, u32),
}

impl Default for FigureOptions {
    fn default() -> Self {
        Self {
            nodes: Vec::new(),
            omega_rad_s: 620.0,
            omega_tolerance_rad_s: 10.0,
            thermal_node: None,
            per_run: false,
            output: Output::default(),
            size: (1200, 800),
        }
    }
}

/// What [`plot_campaign`] did.
#[derive(Clone, Debug, Default)]
pub struct CampaignFigures {
    /// The files written (each figure in every format asked for), in the order of the
    /// module table.
    pub written: Vec<PathBuf>,
    /// Where each figure's panels, marker labels and legend went, by file stem.
    pub layouts: Vec<(String, figure::Layout)>,
    /// Things the user should know: incomplete runs, skipped figures, missing font.
    pub notes: Vec<String>,
    /// The legend label of every run, in manifest order (ends with `(incomplete)` for a
    /// run that did not complete).
    pub legends: Vec<String>,
}

/// One recorded point, reduced to what the figures use.
struct PointData {
    omega_rad_s: f64,
    stable: Option<bool>,
    /// The response is period-doubled: its `ω/2` share reaches [`PERIOD_DOUBLED_SHARE`].
    period_doubled: bool,
    amplitude_m: Vec<f64>,
    delta_v_m: Vec<f64>,
    effective_m: Vec<f64>,
    temp_c: Vec<f64>,
    load_n: Vec<f64>,
}

struct BifurcationData {
    kind: BifurcationKind,
    number: u32,
    /// [`figure::bifurcation_flag`]: `?`, `~`, `!` or none.
    flag: Option<char>,
    omega_rad_s: f64,
    amplitude_m: Vec<f64>,
    /// Mean temperature per thermal node at the located point (from its coefficients, else
    /// interpolated between the points on either side); empty when unknown.
    temp_c: Vec<f64>,
}

impl BifurcationData {
    /// Its label on a figure: kind and number, then its flag.
    fn label(&self) -> String {
        let mut label = figure::bifurcation_label(self.kind, self.number);
        label.extend(self.flag);
        label
    }
}

/// One run, reduced to what the figures use (a recording holds far more).
struct RunData {
    name: String,
    model: String,
    legend: String,
    colour: RGBColor,
    node_ids: Vec<u32>,
    bearings: Vec<(String, f64)>,
    thermal: Vec<(u32, String)>,
    points: Vec<PointData>,
    bifurcations: Vec<BifurcationData>,
}

impl RunData {
    fn node(&self, id: u32) -> Option<usize> {
        self.node_ids.iter().position(|&n| n == id)
    }

    fn bearing(&self, name: &str) -> Option<usize> {
        self.bearings.iter().position(|(n, _)| n == name)
    }

    fn thermal_node(&self, name: &str) -> Option<(usize, u32)> {
        self.thermal
            .iter()
            .position(|(_, n)| n == name)
            .map(|k| (k, self.thermal[k].0))
    }
}

/// The settings of a run: the manifest's, else the recording's embedded ones.
fn run_settings(entry: &ManifestEntry, run: Option<&RunInfo>) -> Option<StudySettings> {
    let manifest = (!entry.settings.is_empty())
        .then(|| StudySettings::from_table(&entry.settings).ok())
        .flatten();
    manifest.or_else(|| StudySettings::from_run(run?).ok())
}

/// Legend label of a run from its settings (manifest first, then the recording's).
fn run_label(entry: &ManifestEntry, run: Option<&RunInfo>) -> String {
    match run_settings(entry, run) {
        Some(s) => {
            let base = if s.operating.thermal {
                format!(
                    "{}: flow {} L/min, cooling {} °C",
                    entry.name,
                    tick(&s.operating.flow_l_min),
                    tick(&s.operating.cooling_temp_c)
                )
            } else {
                format!("{}: no thermal coupling", entry.name)
            };
            match s.set_summary() {
                set if set.is_empty() => base,
                set => format!("{base}, {set}"),
            }
        }
        None => entry.name.clone(),
    }
}

/// The colour of run `k` in the overlays: [`figure::colour`] (the ten colours of tab10,
/// then the ten of tab20's light set, then again).
pub fn run_colour(k: usize) -> RGBColor {
    figure::colour(k)
}

fn load_run(
    dir: &Path,
    entry: &ManifestEntry,
    k: usize,
) -> Result<(RunData, Vec<String>), CampaignError> {
    let file = if entry.recording.is_empty() {
        format!("{}.mcap", entry.name)
    } else {
        entry.recording.clone()
    };
    let path = dir.join(&file);
    let colour = run_colour(k);
    let rec = match read_recording(&path) {
        Ok(rec) => rec.own_branch(),
        // A run that has not started, or failed before it could record, has no file:
        // it stays in the legend with nothing drawn.
        Err(ReadError::Io { source, .. })
            if source.kind() == std::io::ErrorKind::NotFound
                && (entry.status == "pending" || entry.status.starts_with("failed")) =>
        {
            let note = format!(
                "run {} has no recording yet ({} missing, manifest status {:?}): \
                 listed in the legends with nothing drawn",
                entry.name,
                path.display(),
                entry.status
            );
            let data = RunData {
                name: entry.name.clone(),
                model: String::new(),
                legend: format!("{} (incomplete: no recording)", run_label(entry, None)),
                colour,
                node_ids: Vec::new(),
                bearings: Vec::new(),
                thermal: Vec::new(),
                points: Vec::new(),
                bifurcations: Vec::new(),
            };
            return Ok((data, vec![note]));
        }
        Err(error) => {
            return Err(CampaignError::Recording {
                run: entry.name.clone(),
                status: entry.status.clone(),
                error,
            });
        }
    };
    let mut notes = Vec::new();
    let incomplete = entry.status != "completed" || !rec.complete;
    if incomplete {
        let mut why = vec![format!("manifest status {:?}", entry.status)];
        why.extend(rec.notes.iter().cloned());
        notes.push(format!(
            "run {} is incomplete ({} points readable; {}): plotted as far as it goes",
            entry.name,
            rec.points.len(),
            why.join("; ")
        ));
    }
    if !entry.sha256.is_empty()
        && sha256_file(&path).is_ok_and(|sum| !sum.eq_ignore_ascii_case(&entry.sha256))
    {
        notes.push(format!(
            "{} differs from the SHA-256 in the manifest (changed since the run finished?)",
            path.display()
        ));
    }
    let mut legend = run_label(entry, Some(&rec.run));
    if incomplete {
        legend.push_str(" (incomplete)");
    }
    let run = &rec.run;
    let nc = run.n_coeffs();
    let data = RunData {
        name: entry.name.clone(),
        model: run.model_name.clone(),
        legend,
        colour,
        node_ids: run.nodes.iter().map(|n| n.id).collect(),
        bearings: run
            .bearings
            .iter()
            .map(|b| (b.name.clone(), b.initial_clearance_m))
            .collect(),
        thermal: run
            .thermal_nodes
            .iter()
            .map(|t| (t.id, t.name.clone()))
            .collect(),
        points: rec
            .points
            .iter()
            .map(|p| PointData {
                omega_rad_s: p.omega_rad_s,
                stable: p.stable,
                period_doubled: is_period_doubled(&rec.run, p),
                amplitude_m: p.amplitude_rms_m.clone(),
                delta_v_m: p.clearances.iter().map(|c| c.delta_v_m).collect(),
                effective_m: p.clearances.iter().map(|c| c.effective_m).collect(),
                temp_c: p.temperatures.iter().map(|t| t.mean_c).collect(),
                load_n: p.bearing_loads.iter().map(|l| l.mean_n).collect(),
            })
            .collect(),
        bifurcations: rec
            .bifurcations
            .iter()
            .map(|b| BifurcationData {
                kind: b.kind,
                number: b.number,
                flag: figure::bifurcation_flag(&rec, b),
                omega_rad_s: b.omega_rad_s,
                amplitude_m: b.amplitude_rms_m.clone(),
                temp_c: bifurcation_temperatures(&rec, b, nc),
            })
            .collect(),
    };
    Ok((data, notes))
}

/// Draws a run's branch as polylines in its colour: solid where stable or not assessed,
/// dashed and lighter where recorded as unstable. Points where `y` has no value break the
/// line.
fn branch_series(run: &RunData, y: impl Fn(&PointData) -> Option<f64>) -> Vec<Series> {
    figure::branch_series(
        run.points.iter().map(|p| (p.omega_rad_s, y(p), p.stable)),
        BranchStyle::Dashes(run.colour),
    )
}

/// Mean temperatures at a located bifurcation: the constant coefficients of its recorded
/// thermal coefficients, else interpolated on the arc length between the points on either
/// side.
fn bifurcation_temperatures(
    rec: &crate::record::Recording,
    b: &crate::record::BifurcationRecord,
    nc: usize,
) -> Vec<f64> {
    if !b.coeffs_therm.is_empty() {
        return rec
            .run
            .thermal_nodes
            .iter()
            .filter_map(|n| b.coeffs_therm.get(n.dof * nc).copied())
            .collect();
    }
    let (Some(p), Some(q)) = (rec.point(b.after_point), rec.point(b.after_point + 1)) else {
        return Vec::new();
    };
    let span = q.arc_length - p.arc_length;
    let t = if span.abs() > 0.0 {
        ((b.arc_length - p.arc_length) / span).clamp(0.0, 1.0)
    } else {
        0.5
    };
    p.temperatures
        .iter()
        .zip(&q.temperatures)
        .map(|(a, c)| a.mean_c + t * (c.mean_c - a.mean_c))
        .collect()
}

/// Legend entries: one per run, then how stability and bifurcations are drawn.
fn run_legend(runs: &[RunData], with_markers: bool) -> Vec<LegendEntry> {
    let mut entries: Vec<LegendEntry> = runs
        .iter()
        .map(|r| LegendEntry {
            sample: LegendSample::Line(r.colour, LineStyle::Solid),
            text: r.legend.clone(),
        })
        .collect();
    entries.extend(style_legend(runs, with_markers));
    entries
}

/// Legend entries saying how stability and bifurcations are drawn.
fn style_legend(runs: &[RunData], with_markers: bool) -> Vec<LegendEntry> {
    let mut entries = Vec::new();
    let points = || runs.iter().flat_map(|r| &r.points);
    let grey = RGBColor(90, 90, 90);
    if points().any(|p| p.stable == Some(false)) {
        let assessed_all = points().all(|p| p.stable.is_some());
        entries.push(LegendEntry {
            sample: LegendSample::Line(grey, LineStyle::Solid),
            text: if assessed_all {
                "stable".into()
            } else {
                "stable or not assessed".into()
            },
        });
        entries.push(LegendEntry {
            sample: LegendSample::Line(figure::unstable_of(grey), LineStyle::Dashed),
            text: "unstable".into(),
        });
    } else if points().all(|p| p.stable.is_none()) {
        entries.push(LegendEntry {
            sample: LegendSample::None,
            text: "stability not assessed".into(),
        });
    }
    if with_markers && points().any(|p| p.period_doubled) {
        entries.push(LegendEntry {
            sample: LegendSample::Line(grey, LineStyle::Points),
            text: format!(
                "period-doubled response (ω/2 share ≥ {:.0} %)",
                100.0 * PERIOD_DOUBLED_SHARE
            ),
        });
    }
    let mut kinds: Vec<&str> = Vec::new();
    for b in runs.iter().flat_map(|r| &r.bifurcations) {
        let name = match b.kind {
            BifurcationKind::SaddleNode => "SN saddle-node",
            BifurcationKind::PeriodDoubling => "PD period doubling",
            BifurcationKind::NeimarkSacker => "NS Neimark–Sacker",
        };
        if !kinds.contains(&name) {
            kinds.push(name);
        }
    }
    if with_markers && !kinds.is_empty() {
        entries.push(LegendEntry {
            sample: LegendSample::Marker(BLACK),
            text: format!("bifurcation: {}", kinds.join(", ")),
        });
        let flags = runs
            .iter()
            .flat_map(|r| &r.bifurcations)
            .filter_map(|b| b.flag);
        if let Some(text) = figure::flag_legend_text(flags) {
            entries.push(LegendEntry {
                sample: LegendSample::None,
                text,
            });
        }
    }
    entries
}

/// A figure of `panels` with the legend below.
fn figure_of(
    title: &str,
    panels: Vec<Chart>,
    legend: Vec<LegendEntry>,
    size: (u32, u32),
) -> Figure {
    Figure {
        title: title.into(),
        panels,
        legend,
        legend_at: LegendAt::Below,
        size,
        ..Figure::default()
    }
}

/// Panel style: small title and fonts when several panels share a figure.
fn panel(title: String, x_desc: &str, y_desc: &str, several: bool) -> Chart {
    Chart {
        title,
        x_desc: x_desc.into(),
        y_desc: y_desc.into(),
        title_px: if several { 16 } else { 18 },
        font_px: if several { 14 } else { 16 },
        ..Chart::default()
    }
}

/// One y-range for all panels so that they compare directly.
fn share_y(panels: &mut [Chart]) {
    share_axes(panels, false, true);
}

/// Small multiples: one panel per run with `draw(run, chart)` on shared axes.
fn per_run_panels(
    runs: &[RunData],
    x_desc: &str,
    y_desc: &str,
    draw: impl Fn(&RunData, &mut Chart),
) -> Vec<Chart> {
    let mut panels: Vec<Chart> = runs
        .iter()
        .map(|r| {
            let mut chart = panel(r.legend.clone(), x_desc, y_desc, true);
            chart.title_px = 14;
            draw(r, &mut chart);
            chart
        })
        .collect();
    share_axes(&mut panels, true, true);
    panels
}

/// Names and labels of a figure of runs against ω: [`overlay_and_per_run`].
struct OverlayText {
    /// File stem of the overlay; the per-run figure adds `_per_run`.
    stem: String,
    title: String,
    /// y label of the overlay.
    y_desc: String,
    /// Shorter y label of the small panels.
    y_short: &'static str,
    /// First legend line of the per-run figure (what its panels show).
    heading: String,
}

/// The runs drawn by `draw` into one panel against ω, and with `per_run` also one panel
/// per run on shared axes.
fn overlay_and_per_run(
    sink: &mut FigureSink,
    text: &OverlayText,
    runs: &[RunData],
    draw: impl Fn(&RunData, &mut Chart),
) -> Result<(), CampaignError> {
    let size = sink.options.size;
    let mut chart = panel(String::new(), OMEGA, &text.y_desc, false);
    for r in runs {
        draw(r, &mut chart);
    }
    let overlay = figure_of(&text.title, vec![chart], run_legend(runs, true), size);
    sink.write(&text.stem, overlay)?;
    if sink.options.per_run {
        let panels = per_run_panels(runs, OMEGA, text.y_short, draw);
        let mut legend = vec![LegendEntry {
            sample: LegendSample::None,
            text: text.heading.clone(),
        }];
        legend.extend(style_legend(runs, true));
        let stem = format!("{}_per_run", text.stem);
        sink.write(&stem, figure_of(&text.title, panels, legend, size))?;
    }
    Ok(())
}

/// Reads `dir/manifest.toml` and every run's recording and writes the campaign figures
/// (see the module docs) into `out`, which is created if missing.
///
/// Errors: an unreadable or invalid manifest, an unreadable or damaged recording (a file
/// cut short is read as far as it goes, and a run not started yet has none: neither is an
/// error), a requested node no run recorded, a figure that cannot be written; each names
/// the file.
pub fn plot_campaign(
    dir: &Path,
    out: &Path,
    options: &FigureOptions,
) -> Result<CampaignFigures, CampaignError> {
    let manifest = read_manifest_file(&dir.join("manifest.toml"))?;
    // transient runs are recordings on the time axis: `replay plot` draws them
    let swept: Vec<&ManifestEntry> = manifest.runs.iter().filter(|e| !e.is_transient()).collect();
    let loaded = swept
        .par_iter()
        .enumerate()
        .map(|(k, e)| load_run(dir, e, k))
        .collect::<Result<Vec<_>, _>>()?;
    let mut sink = FigureSink {
        out,
        options,
        result: CampaignFigures::default(),
    };
    let mut runs = Vec::new();
    for (run, notes) in loaded {
        sink.result.notes.extend(notes);
        sink.result.legends.push(run.legend.clone());
        runs.push(run);
    }
    crate::input::ensure_dir(out).map_err(|source| CampaignError::Io {
        path: out.display().to_string(),
        source,
    })?;
    if figure::font().is_none() {
        sink.result.notes.push(
            "no TrueType font found (set TMROTOR_FONT to a .ttf file): figures have no text".into(),
        );
    }
    // The bearings of the first run that has any.
    let bearings: Vec<(String, f64)> = runs
        .iter()
        .find(|r| !r.bearings.is_empty())
        .map(|r| r.bearings.clone())
        .unwrap_or_default();

    amplitude_figures(&mut sink, dir, &runs)?;
    clearance_figures(&mut sink, &runs, &bearings)?;
    load_figure(&mut sink, &runs, &bearings)?;
    let has_temps = runs
        .iter()
        .any(|r| r.points.iter().any(|p| !p.temp_c.is_empty()));
    if !has_temps {
        sink.result.notes.push(
            "no run recorded temperatures: rolling_element_temperatures, \
             temperature_extremes and the bearing-position chart not written"
                .into(),
        );
        return Ok(sink.result);
    }
    element_temperature_figure(&mut sink, &runs, &bearings)?;
    thermal_node_figures(&mut sink, &runs)?;
    node_temperature_figures(&mut sink, &runs)?;
    temperature_extremes_figure(&mut sink, &runs)?;
    bearing_positions(&mut sink, &runs, &bearings)?;
    Ok(sink.result)
}

/// Where the figures go, how they are drawn, and what has been written so far.
struct FigureSink<'a> {
    out: &'a Path,
    options: &'a FigureOptions,
    result: CampaignFigures,
}

impl FigureSink<'_> {
    /// Writes one figure (all formats) and records its files and layout.
    fn write(&mut self, stem: &str, fig: Figure) -> Result<(), CampaignError> {
        let written = figure::write_figure(&self.out.join(stem), &fig, &self.options.output)?;
        self.result.written.extend(written.files);
        self.result.layouts.push((stem.to_string(), written.layout));
        Ok(())
    }
}

/// Amplitude–frequency curves of the requested dynamic nodes (node 8, or the first
/// recorded, by default); a node no run recorded is an error naming the manifest.
fn amplitude_figures(
    sink: &mut FigureSink,
    dir: &Path,
    runs: &[RunData],
) -> Result<(), CampaignError> {
    let nodes = if sink.options.nodes.is_empty() {
        let any = |id: u32| runs.iter().any(|r| r.node(id).is_some());
        let first = runs.iter().find_map(|r| r.node_ids.first().copied());
        match (any(8), first) {
            (true, _) => vec![8],
            (false, Some(id)) => vec![id],
            (false, None) => Vec::new(),
        }
    } else {
        sink.options.nodes.clone()
    };
    for &id in &nodes {
        if !runs.iter().any(|r| r.node(id).is_some()) {
            let recorded = runs
                .first()
                .map(|r| {
                    r.node_ids
                        .iter()
                        .map(u32::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                })
                .unwrap_or_default();
            return Err(CampaignError::File {
                file: dir.join("manifest.toml").display().to_string(),
                reason: format!(
                    "dynamic node {id} is not recorded in any run (recorded nodes: {recorded})"
                ),
            });
        }
        let y_desc = format!("RMS amplitude, node {id} (µm)");
        let draw = |r: &RunData, chart: &mut Chart| {
            let Some(k) = r.node(id) else { return };
            let amplitude = |p: &PointData| p.amplitude_m.get(k).map(|a| a * 1e6);
            chart.series.extend(branch_series(r, amplitude));
            let dots: Vec<(f64, f64)> = r
                .points
                .iter()
                .filter(|p| p.period_doubled)
                .filter_map(|p| Some((p.omega_rad_s, amplitude(p)?)))
                .collect();
            if !dots.is_empty() {
                chart.series.push(Series {
                    line: LineStyle::Points,
                    width: 3,
                    ..Series::new(dots, r.colour)
                });
            }
            chart.markers.extend(r.bifurcations.iter().filter_map(|b| {
                Some(Marker {
                    x: b.omega_rad_s,
                    y: b.amplitude_m.get(k)? * 1e6,
                    label: b.label(),
                    colour: r.colour,
                })
            }));
        };
        let text = OverlayText {
            stem: format!("amplitude_node{id}"),
            title: format!("Amplitude–frequency response of dynamic node {id}"),
            y_desc,
            y_short: "RMS amplitude (µm)",
            heading: format!("dynamic node {id}, a panel per run:"),
        };
        overlay_and_per_run(sink, &text, runs, draw)?;
    }
    Ok(())
}

/// RC variation and effective clearance, a panel per bearing (Figs. 8b–10b).
fn clearance_figures(
    sink: &mut FigureSink,
    runs: &[RunData],
    bearings: &[(String, f64)],
) -> Result<(), CampaignError> {
    let has_clearance = runs
        .iter()
        .any(|r| r.points.iter().any(|p| !p.delta_v_m.is_empty()));
    if bearings.is_empty() || !has_clearance {
        sink.result.notes.push(
            "no run recorded bearing clearances: clearance_variation and \
             effective_clearance not written"
                .into(),
        );
    } else {
        let several = bearings.len() > 1;
        for (file, title, y_desc, effective) in [
            (
                "clearance_variation",
                "Radial clearance (RC) variation δv of each bearing (δv > 0: the clearance grows)",
                "radial clearance variation δv (µm)",
                false,
            ),
            (
                "effective_clearance",
                "Effective radial clearance δe = δ0 + δv of each bearing (dashed: initial clearance δ0)",
                "effective radial clearance δe (µm)",
                true,
            ),
        ] {
            let mut panels = Vec::new();
            for (name, d0) in bearings {
                let mut chart = panel(format!("bearing {name}"), OMEGA, y_desc, several);
                chart.hlines.push(if effective { d0 * 1e6 } else { 0.0 });
                for r in runs {
                    let Some(b) = r.bearing(name) else { continue };
                    chart.series.extend(branch_series(r, |p| {
                        let v = if effective {
                            p.effective_m.get(b)
                        } else {
                            p.delta_v_m.get(b)
                        };
                        v.map(|v| v * 1e6)
                    }));
                }
                panels.push(chart);
            }
            // Each panel keeps its own y-range: the bearings' variations differ by an
            // order of magnitude, and the runs are compared within a bearing.
            let mut legend = run_legend(runs, false);
            if effective {
                legend.push(LegendEntry {
                    sample: LegendSample::Line(figure::REFERENCE, LineStyle::Dashed),
                    text: "initial clearance δ0".into(),
                });
            }
            sink.write(file, figure_of(title, panels, legend, sink.options.size))?;
        }
    }
    Ok(())
}

/// Mean bearing loads, a panel per bearing (Fig. 16, averages).
fn load_figure(
    sink: &mut FigureSink,
    runs: &[RunData],
    bearings: &[(String, f64)],
) -> Result<(), CampaignError> {
    let has_loads = runs
        .iter()
        .any(|r| r.points.iter().any(|p| !p.load_n.is_empty()));
    if !bearings.is_empty() && has_loads {
        let several = bearings.len() > 1;
        let panels = bearings
            .iter()
            .map(|(name, _)| {
                let mut chart = panel(
                    format!("bearing {name}"),
                    OMEGA,
                    "mean radial load (N)",
                    several,
                );
                for r in runs {
                    let Some(b) = r.bearing(name) else { continue };
                    chart
                        .series
                        .extend(branch_series(r, |p| p.load_n.get(b).copied()));
                }
                chart
            })
            .collect();
        sink.write(
            "bearing_loads_mean",
            figure_of(
                "Mean radial load of each bearing",
                panels,
                run_legend(runs, false),
                sink.options.size,
            ),
        )?;
    }
    Ok(())
}

/// Rolling-element temperature of each bearing, panels on one y-range (Fig. 14c).
fn element_temperature_figure(
    sink: &mut FigureSink,
    runs: &[RunData],
    bearings: &[(String, f64)],
) -> Result<(), CampaignError> {
    let element_panels: Vec<Chart> = bearings
        .iter()
        .filter_map(|(name, _)| {
            let label = format!("{name} rolling elements");
            let id = runs.iter().find_map(|r| r.thermal_node(&label))?.1;
            let mut chart = panel(
                format!("bearing {name}: rolling elements (thermal node {id})"),
                OMEGA,
                "mean temperature (°C)",
                bearings.len() > 1,
            );
            for r in runs {
                let Some((t, _)) = r.thermal_node(&label) else {
                    continue;
                };
                chart
                    .series
                    .extend(branch_series(r, |p| p.temp_c.get(t).copied()));
            }
            Some(chart)
        })
        .collect();
    if element_panels.is_empty() {
        sink.result.notes.push(
            "no thermal node is named \"<bearing> rolling elements\": \
             rolling_element_temperatures not written"
                .into(),
        );
    } else {
        let mut panels = element_panels;
        share_y(&mut panels);
        sink.write(
            "rolling_element_temperatures",
            figure_of(
                "Rolling-element temperature of each bearing",
                panels,
                run_legend(runs, false),
                sink.options.size,
            ),
        )?;
    }
    Ok(())
}

/// One thermal node against ω, runs overlaid (Fig. 15): the requested node, or node 58
/// when every run is of the built-in dual rotor.
fn thermal_node_figures(sink: &mut FigureSink, runs: &[RunData]) -> Result<(), CampaignError> {
    let thermal_node = sink.options.thermal_node.or_else(|| {
        let paper = runs
            .iter()
            .filter(|r| !r.points.is_empty())
            .all(|r| r.model == "dual_rotor" && r.thermal.iter().any(|(id, _)| *id == 58));
        paper.then_some(58)
    });
    if let Some(id) = thermal_node {
        let index = |r: &RunData| r.thermal.iter().position(|(n, _)| *n == id);
        let name = runs
            .iter()
            .find_map(|r| index(r).map(|t| r.thermal[t].1.clone()));
        match name {
            None => sink.result.notes.push(format!(
                "no run has thermal node {id}: temperature_node{id} not written"
            )),
            Some(name) => {
                let y_desc = format!("mean temperature, {name} (thermal node {id}) (°C)");
                let draw = |r: &RunData, chart: &mut Chart| {
                    let Some(t) = index(r) else { return };
                    chart
                        .series
                        .extend(branch_series(r, |p| p.temp_c.get(t).copied()));
                    chart.markers.extend(r.bifurcations.iter().filter_map(|b| {
                        Some(Marker {
                            x: b.omega_rad_s,
                            y: *b.temp_c.get(t)?,
                            label: b.label(),
                            colour: r.colour,
                        })
                    }));
                };
                let text = OverlayText {
                    stem: format!("temperature_node{id}"),
                    title: format!("Mean temperature of thermal node {id} ({name})"),
                    y_desc,
                    y_short: "mean temperature (°C)",
                    heading: format!("thermal node {id} ({name}), a panel per run:"),
                };
                overlay_and_per_run(sink, &text, runs, draw)?;
            }
        }
    }
    Ok(())
}

/// Every node's temperature, grouped by bearing, a figure per run (Figs. 14a–b).
fn node_temperature_figures(sink: &mut FigureSink, runs: &[RunData]) -> Result<(), CampaignError> {
    for r in runs
        .iter()
        .filter(|r| r.points.iter().any(|p| !p.temp_c.is_empty()))
    {
        let names: Vec<(u32, &str)> = r.thermal.iter().map(|(id, n)| (*id, n.as_str())).collect();
        let bearing_names: Vec<&str> = r.bearings.iter().map(|(n, _)| n.as_str()).collect();
        let panels = figure::node_temperature_panels(&names, &bearing_names, |t| {
            r.points
                .iter()
                .map(move |p| (p.omega_rad_s, p.temp_c.get(t).copied(), p.stable))
        });
        let mut legend = Figure::legend_from_series(&panels);
        legend.extend(style_legend(std::slice::from_ref(r), false));
        sink.write(
            &format!("node_temperatures_{}", file_safe(&r.name)),
            figure_of(
                &format!("Mean temperatures of the thermal nodes, {}", r.legend),
                panels,
                legend,
                sink.options.size,
            ),
        )?;
    }
    Ok(())
}

/// Highest and lowest mean temperature over the thermal network against ω.
fn temperature_extremes_figure(
    sink: &mut FigureSink,
    runs: &[RunData],
) -> Result<(), CampaignError> {
    let extreme = |max: bool| {
        move |p: &PointData| {
            let it = p.temp_c.iter().copied().filter(|t| t.is_finite());
            if max {
                it.reduce(f64::max)
            } else {
                it.reduce(f64::min)
            }
        }
    };
    let mut panels = vec![
        panel(
            "highest mean node temperature".into(),
            OMEGA,
            "highest mean temperature (°C)",
            true,
        ),
        panel(
            "lowest mean node temperature".into(),
            OMEGA,
            "lowest mean temperature (°C)",
            true,
        ),
    ];
    for r in runs {
        panels[0].series.extend(branch_series(r, extreme(true)));
        panels[1].series.extend(branch_series(r, extreme(false)));
    }
    sink.write(
        "temperature_extremes",
        figure_of(
            "Highest and lowest temperature over the thermal network",
            panels,
            run_legend(runs, false),
            sink.options.size,
        ),
    )?;
    Ok(())
}

/// A run name as part of a file name: letters, digits, `-`, `_` and `.` kept, anything
/// else `_`.
fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The dot chart of the bearing positions' temperatures at one ω (Figs. 14d–e).
fn bearing_positions(
    sink: &mut FigureSink,
    runs: &[RunData],
    bearings: &[(String, f64)],
) -> Result<(), CampaignError> {
    let options = sink.options;
    const PARTS: [(&str, &str); 5] = [
        ("rolling elements", "elements"),
        ("inner ring", "inner ring"),
        ("outer ring", "outer ring"),
        ("lubricant", "lubricant"),
        ("housing seat", "housing"),
    ];
    let target = options.omega_rad_s;
    // The recorded point nearest to the target ω, per run.
    let nearest: Vec<Option<&PointData>> = runs
        .iter()
        .map(|r| {
            r.points
                .iter()
                .filter(|p| !p.temp_c.is_empty())
                .min_by(|a, b| {
                    (a.omega_rad_s - target)
                        .abs()
                        .total_cmp(&(b.omega_rad_s - target).abs())
                })
                .filter(|p| (p.omega_rad_s - target).abs() <= options.omega_tolerance_rad_s)
        })
        .collect();
    let n = runs.len().max(1) as f64;
    let spread = (0.7 / n).min(0.12);
    let several = bearings.len() > 1;
    let mut panels = Vec::new();
    for (name, _) in bearings {
        // Parts of this bearing that some run names, with their node ids.
        let parts: Vec<(String, String)> = PARTS
            .iter()
            .filter_map(|(part, short)| {
                let label = format!("{name} {part}");
                let id = runs.iter().find_map(|r| r.thermal_node(&label))?.1;
                Some((label, format!("{short}\nnode {id}")))
            })
            .collect();
        if parts.is_empty() {
            continue;
        }
        let mut chart = panel(
            format!("bearing {name}"),
            "",
            "mean temperature (°C)",
            several,
        );
        chart.x_range = Some((-0.5, parts.len() as f64 - 0.5));
        chart.x_categories = parts.iter().map(|(_, c)| c.clone()).collect();
        for (k, (r, point)) in runs.iter().zip(&nearest).enumerate() {
            let Some(point) = point else { continue };
            let dx = (k as f64 - (n - 1.0) / 2.0) * spread;
            let points = parts
                .iter()
                .enumerate()
                .filter_map(|(i, (label, _))| {
                    let (t, _) = r.thermal_node(label)?;
                    Some((i as f64 + dx, *point.temp_c.get(t)?))
                })
                .collect();
            chart.series.push(Series {
                line: LineStyle::Points,
                width: 5,
                ..Series::new(points, r.colour)
            });
        }
        panels.push(chart);
    }
    let file = format!("bearing_temperatures_omega{}", tick(&target));
    if panels.is_empty() {
        sink.result.notes.push(format!(
            "no thermal node is named after a bearing part: {file} not written"
        ));
        return Ok(());
    }
    if nearest.iter().all(Option::is_none) {
        sink.result.notes.push(format!(
            "no run has a point within {} rad/s of ω = {} rad/s: {file} not written",
            tick(&options.omega_tolerance_rad_s),
            tick(&target)
        ));
        return Ok(());
    }
    share_y(&mut panels);
    let legend: Vec<LegendEntry> = runs
        .iter()
        .zip(&nearest)
        .map(|(r, p)| LegendEntry {
            sample: LegendSample::Line(r.colour, LineStyle::Points),
            text: match p {
                Some(p) => format!("{}, point at ω = {:.1} rad/s", r.legend, p.omega_rad_s),
                None => format!(
                    "{}: no point within {} rad/s",
                    r.legend,
                    tick(&options.omega_tolerance_rad_s)
                ),
            },
        })
        .collect();
    sink.write(&file,
        figure_of(
            &format!(
                "Temperatures of the bearing positions at ω = {} rad/s (nearest recorded point of each run)",
                tick(&target)
            ),
            panels,
            legend,
            options.size,
        ),
    )?;
    Ok(())
}
