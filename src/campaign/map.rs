//! Operating maps: the bifurcations of a campaign's sweeps over one parameter `p` (a flow
//! rate, a cooling temperature, any value of the model file) joined into curves in (p, ω),
//! with the regions where several stable responses coexist or none is stable
//! (`tmrotor campaign map DIR`).
//!
//! Method: location on a parameter grid with tracking. Each run of the campaign is one
//! sweep in ω at one value of `p`; its saddle-node, Neimark–Sacker and period-doubling
//! points are located on the branch to the ω resolution of the sweep. Points of one kind
//! at neighbouring values of `p` are joined into a curve when they are nearest to each
//! other (greedy, closest pairs first) and closer than a tolerance
//! ([`MapOptions::omega_tolerance`], default 25 % of the swept ω range; points are
//! joined in order of ω, so two curves never cross between neighbouring values). Two saddle-nodes
//! that follow each other along a branch bound a hysteresis interval (a fold pair); where
//! a pair is present at one value of `p` and both its curves end before the next, the pair
//! dies (or is born) between the two values: a cusp lies in that interval, reported with
//! the bracket and the pair's mean ω. Why a grid and not continuation of the curves: on
//! the coupled rotor (2 346 harmonic-balance unknowns at order 3) the dense extended
//! systems of [`crate::continuation::fold`] would cost several large factorizations per
//! step, while the grid reuses the campaign's parallel, resumable sweeps, and every curve
//! point is a located bifurcation of a sweep. Between grid values the curves are straight
//! lines: a finer grid, or a second campaign over a narrower range, refines them.
//!
//! Coexisting responses: at each `p` the ω axis is cut at the ω of every branch point;
//! each branch segment over an interval counts as a stable response when both its ends
//! are stable, unstable when either is not. Intervals with two
//! or more stable responses (hysteresis) and cells with none (every response unstable) are
//! drawn as bands; the counts are in `map_regions.csv`.

use std::path::{Path, PathBuf};

use super::CampaignError;
use super::read_manifest_file;
use crate::record::map::{MapRecord, MapRun};
use crate::record::read_recording;
use crate::stability::BifurcationKind;

/// What [`operating_map`] reads and computes.
#[derive(Clone)]
pub struct MapOptions {
    /// The parameter (a settings key such as `flow_l_min`, or `set.<path>` for a value of
    /// the model file); `None`: the one numeric setting that differs between the runs.
    pub param: Option<String>,
    /// Largest ω distance (rad/s) of two points joined into a curve; `None`: 25 % of the
    /// swept ω range.
    pub omega_tolerance: Option<f64>,
    /// Bisection sweeps per fold-pair end (0: the grid's brackets; each halves one).
    pub refine: usize,
    /// Hears of each refined fold-pair end.
    pub progress: &'static (dyn Fn(&PairEnd) + Sync),
}

impl std::fmt::Debug for MapOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MapOptions")
            .field("param", &self.param)
            .field("omega_tolerance", &self.omega_tolerance)
            .field("refine", &self.refine)
            .finish_non_exhaustive()
    }
}

impl Default for MapOptions {
    fn default() -> Self {
        Self {
            param: None,
            omega_tolerance: None,
            refine: 0,
            progress: &|_| {},
        }
    }
}

/// One sweep of the map: the value of the parameter, its located bifurcations in branch
/// order, and its branch as (ω, stable) in branch order.
#[derive(Clone, Debug)]
pub struct MapSlice {
    pub run: String,
    pub p: f64,
    /// The run's recording, relative to the campaign directory.
    pub recording: String,
    /// The run's settings as the manifest lists them (empty when the slice is not from a
    /// campaign): what [`refine_pair_ends`] sweeps again.
    pub settings: toml::Table,
    pub bifurcations: Vec<(BifurcationKind, f64)>,
    pub branch: Vec<(f64, Option<bool>)>,
}

pub use crate::record::map::{MapCurve, PairEnd, Region};

/// The map built from the slices.
#[derive(Clone, Debug)]
pub struct OperatingMap {
    pub param: String,
    /// Largest ω distance of two points joined into a curve (rad/s).
    pub omega_tolerance: f64,
    pub slices: Vec<MapSlice>,
    pub curves: Vec<MapCurve>,
    pub pair_ends: Vec<PairEnd>,
    pub regions: Vec<Region>,
}

/// Builds the map from slices (any order; sorted by `p`): curves by kind, fold-pair ends
/// and coexistence regions (see the module docs).
pub fn build_map(
    param: &str,
    mut slices: Vec<MapSlice>,
    omega_tolerance: Option<f64>,
) -> OperatingMap {
    slices.sort_by(|a, b| a.p.total_cmp(&b.p));
    let (lo, hi) = omega_span(&slices);
    let tol = omega_tolerance.unwrap_or(0.25 * (hi - lo).abs().max(1e-12));
    // Curves: per slice, the curve id of each bifurcation (same index as `bifurcations`).
    let mut curves: Vec<MapCurve> = Vec::new();
    let mut ids_of: Vec<Vec<usize>> = Vec::new();
    for (k, s) in slices.iter().enumerate() {
        let mut ids = vec![usize::MAX; s.bifurcations.len()];
        if let (Some(prev), Some(ids_prev)) = (k.checked_sub(1).map(|i| &slices[i]), ids_of.last())
        {
            match_points(prev, s, tol, ids_prev, &mut ids);
        }
        for (j, (kind, omega)) in s.bifurcations.iter().enumerate() {
            if ids[j] == usize::MAX {
                ids[j] = curves.len();
                curves.push(MapCurve {
                    id: curves.len(),
                    kind: *kind,
                    points: Vec::new(),
                });
            }
            curves[ids[j]].points.push((s.p, *omega));
        }
        ids_of.push(ids);
    }
    let pair_ends = pair_ends(&slices, &ids_of);
    let regions = slices.iter().flat_map(|s| regions(s, lo, hi)).collect();
    OperatingMap {
        param: param.to_string(),
        omega_tolerance: tol,
        slices,
        curves,
        pair_ends,
        regions,
    }
}

/// Joins the bifurcations of `cur` to those of `prev` (curve ids `ids_prev`), kind by
/// kind: the matching in order of ω (so curves never cross between two slices) with the
/// least total distance, each joined pair within `tol`, a point left unjoined costing
/// `tol` (dynamic programming over the two sorted lists).
fn match_points(prev: &MapSlice, cur: &MapSlice, tol: f64, ids_prev: &[usize], ids: &mut [usize]) {
    for kind in [
        BifurcationKind::SaddleNode,
        BifurcationKind::NeimarkSacker,
        BifurcationKind::PeriodDoubling,
    ] {
        let of = |s: &MapSlice| {
            let mut v: Vec<(usize, f64)> = s
                .bifurcations
                .iter()
                .enumerate()
                .filter(|(_, (k, _))| *k == kind)
                .map(|(i, (_, w))| (i, *w))
                .collect();
            v.sort_by(|a, b| a.1.total_cmp(&b.1));
            v
        };
        let (a, b) = (of(prev), of(cur));
        let (n, m) = (a.len(), b.len());
        // cost[i][j]: best matching of a[..i] with b[..j]
        let mut cost = vec![vec![0.0f64; m + 1]; n + 1];
        for i in 0..=n {
            for j in 0..=m {
                if i == 0 || j == 0 {
                    cost[i][j] = (i + j) as f64 * tol;
                    continue;
                }
                let d = (a[i - 1].1 - b[j - 1].1).abs();
                let mut best = (cost[i - 1][j] + tol).min(cost[i][j - 1] + tol);
                if d <= tol {
                    best = best.min(cost[i - 1][j - 1] + d);
                }
                cost[i][j] = best;
            }
        }
        let (mut i, mut j) = (n, m);
        while i > 0 && j > 0 {
            let d = (a[i - 1].1 - b[j - 1].1).abs();
            if d <= tol && cost[i][j] == cost[i - 1][j - 1] + d {
                ids[b[j - 1].0] = ids_prev[a[i - 1].0];
                i -= 1;
                j -= 1;
            } else if cost[i][j] == cost[i - 1][j] + tol {
                i -= 1;
            } else {
                j -= 1;
            }
        }
    }
}

/// The smallest and largest ω of the slices' branches.
fn omega_span(slices: &[MapSlice]) -> (f64, f64) {
    let omegas = || {
        slices
            .iter()
            .flat_map(|s| s.branch.iter().map(|b| b.0))
            .filter(|w| w.is_finite())
    };
    (
        omegas().fold(f64::INFINITY, f64::min),
        omegas().fold(f64::NEG_INFINITY, f64::max),
    )
}

/// Fold pairs that end between a slice and a neighbour: the saddle-nodes of the slice
/// whose curves have no point at the neighbour, taken in branch order two by two (a pair
/// nested in another ends as a pair of its own).
fn pair_ends(slices: &[MapSlice], ids_of: &[Vec<usize>]) -> Vec<PairEnd> {
    let mut out = Vec::new();
    for (k, s) in slices.iter().enumerate() {
        for n in [k.checked_sub(1), Some(k + 1)].into_iter().flatten() {
            let Some(other) = ids_of.get(n) else { continue };
            let ending: Vec<f64> = s
                .bifurcations
                .iter()
                .enumerate()
                .filter(|(i, (kind, _))| {
                    *kind == BifurcationKind::SaddleNode && !other.contains(&ids_of[k][*i])
                })
                .map(|(_, (_, w))| *w)
                .collect();
            for pair in ending.chunks_exact(2) {
                out.push(PairEnd {
                    p_with: s.p,
                    p_without: slices[n].p,
                    omega: 0.5 * (pair[0] + pair[1]),
                    run: s.run.clone(),
                    refined: 0,
                });
            }
        }
    }
    out
}

/// The coexistence regions of one slice over `[lo, hi]`: the counts are constant between
/// the ω of consecutive branch points, so they are taken at the middle of each interval
/// between the sorted ω of all points, and equal neighbours merged.
fn regions(s: &MapSlice, lo: f64, hi: f64) -> Vec<Region> {
    let mut cuts: Vec<f64> = s
        .branch
        .iter()
        .map(|b| b.0)
        .filter(|w| w.is_finite() && *w > lo && *w < hi)
        .collect();
    cuts.push(lo);
    cuts.push(hi);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut out: Vec<Region> = Vec::new();
    for w2 in cuts.windows(2) {
        let w = 0.5 * (w2[0] + w2[1]);
        let (mut stable, mut unstable) = (0, 0);
        for seg in s.branch.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            if (a.0 - w) * (b.0 - w) > 0.0 || a.0 == b.0 {
                continue;
            }
            match (a.1, b.1) {
                (Some(true), Some(true)) => stable += 1,
                (Some(false), _) | (_, Some(false)) => unstable += 1,
                _ => {}
            }
        }
        match out.last_mut() {
            Some(r) if r.stable == stable && r.unstable == unstable => r.omega_to = w2[1],
            _ => out.push(Region {
                p: s.p,
                omega_from: w2[0],
                omega_to: w2[1],
                stable,
                unstable,
            }),
        }
    }
    out
}

/// The numeric settings of a manifest entry as (key, value): the flat keys, and the
/// model-file values as `set.<path>`.
fn numeric_settings(settings: &toml::Table) -> Vec<(String, f64)> {
    let number = |v: &toml::Value| match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let mut out = Vec::new();
    for (k, v) in settings {
        if k == "set" {
            if let toml::Value::Table(t) = v {
                for (path, v) in t {
                    if let Some(x) = number(v) {
                        out.push((format!("set.{path}"), x));
                    }
                }
            }
        } else if let Some(x) = number(v) {
            out.push((k.clone(), x));
        }
    }
    out
}

/// Reads a campaign directory's manifest and recordings into slices over `param` (or the
/// one numeric setting that differs between the runs). Errors name the manifest or the
/// recording; a run without a recording is left out with a note.
pub fn read_slices(
    dir: &Path,
    param: Option<&str>,
) -> Result<(String, Vec<MapSlice>, Vec<String>), CampaignError> {
    let manifest_path = dir.join("manifest.toml");
    let manifest = read_manifest_file(&manifest_path)?;
    let file_err = |reason: String| CampaignError::File {
        file: manifest_path.display().to_string(),
        reason,
    };
    let settings: Vec<Vec<(String, f64)>> = manifest
        .runs
        .iter()
        .map(|r| numeric_settings(&r.settings))
        .collect();
    let param = match param {
        Some(p) => p.to_string(),
        None => {
            let mut varying: Vec<String> = Vec::new();
            if let Some(first) = settings.first() {
                for (k, v) in first {
                    let differs = settings.iter().any(|s| {
                        s.iter()
                            .find(|(k2, _)| k2 == k)
                            .is_none_or(|(_, v2)| v2 != v)
                    });
                    if differs {
                        varying.push(k.clone());
                    }
                }
            }
            match varying.len() {
                1 => varying.remove(0),
                0 => {
                    return Err(file_err(
                        "no numeric setting differs between the runs: a map needs runs over \
                         one parameter (a [grid] with one key)"
                            .into(),
                    ));
                }
                _ => {
                    return Err(file_err(format!(
                        "several settings differ between the runs ({}): choose the map's \
                         parameter with --param",
                        varying.join(", ")
                    )));
                }
            }
        }
    };
    let mut slices = Vec::new();
    let mut notes = Vec::new();
    for (entry, s) in manifest.runs.iter().zip(&settings) {
        let Some(&(_, p)) = s.iter().find(|(k, _)| *k == param) else {
            return Err(file_err(format!(
                "run {} has no numeric setting {param:?}",
                entry.name
            )));
        };
        let file = if entry.recording.is_empty() {
            format!("{}.mcap", entry.name)
        } else {
            entry.recording.clone()
        };
        let path = dir.join(&file);
        if !path.exists() {
            notes.push(format!(
                "run {} has no recording ({} missing): left out of the map",
                entry.name,
                path.display()
            ));
            continue;
        }
        let rec = read_recording(&path)
            .map_err(|error| CampaignError::Recording {
                run: entry.name.clone(),
                status: entry.status.clone(),
                error,
            })?
            .own_branch();
        if !rec.complete {
            notes.push(format!(
                "run {}: the recording is incomplete; mapped as far as it goes",
                entry.name
            ));
        }
        let mut bifs: Vec<_> = rec.bifurcations.iter().collect();
        bifs.sort_by(|a, b| a.arc_length.total_cmp(&b.arc_length));
        slices.push(MapSlice {
            run: entry.name.clone(),
            p,
            recording: file.clone(),
            settings: entry.settings.clone(),
            bifurcations: bifs.iter().map(|b| (b.kind, b.omega_rad_s)).collect(),
            branch: rec
                .points
                .iter()
                .map(|q| (q.omega_rad_s, q.stable))
                .collect(),
        });
    }
    if slices.is_empty() {
        return Err(file_err("no run has a recording to map".into()));
    }
    Ok((param, slices, notes))
}

/// The files written by [`write_map`] and its notes.
#[derive(Clone, Debug, Default)]
pub struct MapFiles {
    pub written: Vec<PathBuf>,
    pub notes: Vec<String>,
}

/// Narrows the bracket of a fold pair's end by `steps` bisections. `pairs_near(p, ω)`
/// computes the branch at `p` around ω and returns the mean ω of each fold pair near ω;
/// the pair is present at `p` when there are at least `n_with` of them, the number beside
/// it where the bracket has it (a pair nested in another ends while the outer one goes on).
/// The bracket keeps a value with the pair and one without; with one pair, its ω follows
/// the value with it. A pair narrower than the sweep resolves counts as absent, so the
/// bracket can end short of the cusp on the side with the pair.
pub fn refine_pair_end<E>(
    end: &PairEnd,
    n_with: usize,
    steps: usize,
    pairs_near: impl Fn(f64, f64) -> Result<Vec<f64>, E>,
) -> Result<PairEnd, E> {
    let mut out = end.clone();
    for _ in 0..steps {
        let mid = 0.5 * (out.p_with + out.p_without);
        let found = pairs_near(mid, out.omega)?;
        if found.len() >= n_with.max(1) {
            out.p_with = mid;
            if let [only] = found[..] {
                out.omega = only;
            }
        } else {
            out.p_without = mid;
        }
        out.refined += 1;
    }
    Ok(out)
}

/// The mean ω of each fold pair (two saddle-nodes in a row along the branch) within
/// `window` of `omega`, from bifurcations in branch order.
pub fn pairs_near(bifurcations: &[(BifurcationKind, f64)], omega: f64, window: f64) -> Vec<f64> {
    let folds: Vec<f64> = bifurcations
        .iter()
        .filter(|(k, _)| *k == BifurcationKind::SaddleNode)
        .map(|(_, w)| *w)
        .collect();
    folds
        .chunks_exact(2)
        .map(|w| 0.5 * (w[0] + w[1]))
        .filter(|m| (m - omega).abs() <= window)
        .collect()
}

/// Refines every fold-pair end of `map` by `steps` bisections (see [`refine_pair_end`]),
/// each a sweep without stability over ω ± `window` of the run that has the pair, with the
/// parameter set to the bisection's value; the pair ends are refined in parallel.
/// `progress` hears of each finished end.
pub fn refine_pair_ends(
    map: &mut OperatingMap,
    steps: usize,
    window: f64,
    progress: &(dyn Fn(&PairEnd) + Sync),
) -> Result<(), CampaignError> {
    use rayon::prelude::*;
    let param = map.param.clone();
    let refined: Vec<PairEnd> =
        map.pair_ends
            .par_iter()
            .map(|end| {
                let slice = map
                    .slices
                    .iter()
                    .find(|s| s.run == end.run)
                    .ok_or_else(|| CampaignError::File {
                        file: end.run.clone(),
                        reason: "the run of a fold pair is not in the map".into(),
                    })?;
                let n_with = pairs_near(&slice.bifurcations, end.omega, 0.5 * window).len();
                let sweep = |p: f64, omega: f64| -> Result<Vec<f64>, CampaignError> {
                    let bifs = sweep_window(&slice.settings, &param, p, omega, window).map_err(
                        |reason| CampaignError::Invalid {
                            file: "manifest.toml".into(),
                            run: format!("{} at {param} = {p}", slice.run),
                            reason,
                        },
                    )?;
                    Ok(pairs_near(&bifs, omega, 0.5 * window))
                };
                let done = refine_pair_end(end, n_with, steps, sweep)?;
                progress(&done);
                Ok(done)
            })
            .collect::<Result<_, CampaignError>>()?;
    map.pair_ends = refined;
    Ok(())
}

/// The located bifurcations, in branch order, of a sweep without stability over
/// `omega ± window` of the run with `settings` and the parameter set to `p`.
fn sweep_window(
    settings: &toml::Table,
    param: &str,
    p: f64,
    omega: f64,
    window: f64,
) -> Result<Vec<(BifurcationKind, f64)>, String> {
    use crate::sweep::{StudySettings, SweepProblem};
    let mut table = settings.clone();
    match param.strip_prefix("set.") {
        Some(path) => {
            let set = table
                .entry("set")
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            match set {
                toml::Value::Table(t) => {
                    t.insert(path.to_string(), toml::Value::Float(p));
                }
                _ => return Err("the run's `set` is not a table".into()),
            }
        }
        None => {
            table.insert(param.to_string(), toml::Value::Float(p));
        }
    }
    table.insert("omega_start".into(), toml::Value::Float(omega - window));
    table.insert("omega_end".into(), toml::Value::Float(omega + window));
    table.insert("stability".into(), toml::Value::Boolean(false));
    let settings = StudySettings::from_table(&table).map_err(|e| e.to_string())?;
    let problem = SweepProblem::new(&settings).map_err(|e| e.to_string())?;
    let mut sink = crate::record::MemorySink::new();
    problem
        .run(&mut sink, None, |_| {})
        .map_err(|e| e.to_string())?;
    let mut bifs = sink.bifurcations;
    bifs.sort_by(|a, b| a.arc_length.total_cmp(&b.arc_length));
    Ok(bifs.iter().map(|b| (b.kind, b.omega_rad_s)).collect())
}

/// Reads `dir`, builds the map (refining its fold-pair ends when asked) and writes
/// `map_curves.csv`, `map_pair_ends.csv`, `map_regions.csv` and `operating_map.mcap` into
/// `out` ([`write_map`]); the command then draws its figure.
pub fn operating_map(
    dir: &Path,
    out: &Path,
    options: &MapOptions,
) -> Result<(OperatingMap, MapFiles), CampaignError> {
    let (param, slices, notes) = read_slices(dir, options.param.as_deref())?;
    let mut map = build_map(&param, slices, options.omega_tolerance);
    if options.refine > 0 {
        let (lo, hi) = omega_span(&map.slices);
        refine_pair_ends(&mut map, options.refine, 0.05 * (hi - lo), options.progress)?;
    }
    let mut files = write_map(&map, out)?;
    files.notes.splice(0..0, notes);
    Ok((map, files))
}

/// Column name of the parameter: the key with anything but letters, digits and `_`
/// replaced by `_`.
fn param_column(param: &str) -> String {
    param
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

impl OperatingMap {
    /// What the map's recording holds: the map with each slice's run, value and recording.
    pub fn record(&self) -> MapRecord {
        MapRecord {
            param: self.param.clone(),
            omega_tolerance: self.omega_tolerance,
            runs: self
                .slices
                .iter()
                .map(|s| MapRun {
                    name: s.run.clone(),
                    value: s.p,
                    recording: s.recording.clone(),
                })
                .collect(),
            curves: self.curves.clone(),
            pair_ends: self.pair_ends.clone(),
            regions: self.regions.clone(),
        }
    }
}

impl From<MapRecord> for OperatingMap {
    /// The map of a recording: slices with their run, value and recording name only.
    fn from(m: MapRecord) -> Self {
        Self {
            param: m.param,
            omega_tolerance: m.omega_tolerance,
            slices: m
                .runs
                .into_iter()
                .map(|r| MapSlice {
                    run: r.name,
                    p: r.value,
                    recording: r.recording,
                    settings: toml::Table::new(),
                    bifurcations: Vec::new(),
                    branch: Vec::new(),
                })
                .collect(),
            curves: m.curves,
            pair_ends: m.pair_ends,
            regions: m.regions,
        }
    }
}

/// Writes `map` as an MCAP file (topics [`crate::record::schema::MAP_TOPICS`], see
/// `schemas/README.md`) through the record layer ([`crate::record::map::write_map`]).
pub fn write_map_mcap(map: &OperatingMap, path: &Path) -> Result<(), CampaignError> {
    Ok(crate::record::map::write_map(&map.record(), path)?)
}

/// An operating map read back from its MCAP file: the map without the branches (the
/// slices carry their run, value and recording name only).
pub fn read_map_mcap(path: &Path) -> Result<OperatingMap, CampaignError> {
    Ok(crate::record::map::read_map(path)?.into())
}

/// Writes `map_curves.csv`, `map_pair_ends.csv` and `map_regions.csv` of `map` into `out`
/// (which must exist); returns their paths.
pub fn write_map_csvs(map: &OperatingMap, out: &Path) -> Result<Vec<PathBuf>, CampaignError> {
    let mut written = Vec::new();
    let pc = param_column(&map.param);
    let mut write = |name: &str, text: String| -> Result<(), CampaignError> {
        let path = out.join(name);
        crate::record::output::write_atomic(&path, text.as_bytes()).map_err(|source| {
            CampaignError::Io {
                path: path.display().to_string(),
                source,
            }
        })?;
        written.push(path);
        Ok(())
    };
    let mut text = format!("curve,kind,{pc},omega_rad_s\n");
    for c in &map.curves {
        for (p, w) in &c.points {
            text += &format!("{},{},{p},{w}\n", c.id, c.kind.key());
        }
    }
    write("map_curves.csv", text)?;
    let mut text = format!("{pc}_with_pair,{pc}_without_pair,omega_rad_s,run,bisections\n");
    for e in &map.pair_ends {
        text += &format!(
            "{},{},{},{},{}\n",
            e.p_with, e.p_without, e.omega, e.run, e.refined
        );
    }
    write("map_pair_ends.csv", text)?;
    let mut text =
        format!("{pc},omega_from_rad_s,omega_to_rad_s,stable_responses,unstable_responses\n");
    for r in &map.regions {
        text += &format!(
            "{},{},{},{},{}\n",
            r.p, r.omega_from, r.omega_to, r.stable, r.unstable
        );
    }
    write("map_regions.csv", text)?;
    Ok(written)
}

/// Writes the CSVs and the MCAP file of `map` into `out` (created if missing); its figure
/// is drawn by the application's figure module, above this one.
pub fn write_map(map: &OperatingMap, out: &Path) -> Result<MapFiles, CampaignError> {
    crate::input::ensure_dir(out).map_err(|source| CampaignError::Io {
        path: out.display().to_string(),
        source,
    })?;
    let mut files = MapFiles {
        written: write_map_csvs(map, out)?,
        notes: Vec::new(),
    };
    let mcap_path = out.join("operating_map.mcap");
    write_map_mcap(map, &mcap_path)?;
    files.written.push(mcap_path);

    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice(p: f64, bifs: &[(BifurcationKind, f64)], branch: &[(f64, bool)]) -> MapSlice {
        MapSlice {
            run: format!("p{p}"),
            p,
            recording: String::new(),
            settings: toml::Table::new(),
            bifurcations: bifs.to_vec(),
            branch: branch.iter().map(|&(w, s)| (w, Some(s))).collect(),
        }
    }

    /// A fold pair that narrows with p and is gone at the last value: two curves, one
    /// pair end between the last two values, and hysteresis cells where the branch folds
    /// back.
    #[test]
    fn a_fold_pair_is_tracked_and_its_end_bracketed() {
        use BifurcationKind::SaddleNode as SN;
        let folded = |p: f64, a: f64, b: f64| {
            slice(
                p,
                &[(SN, b), (SN, a)],
                &[
                    (0.0, true),
                    (b, true),
                    (b - 0.1, false),
                    (a + 0.1, false),
                    (a, true),
                    (10.0, true),
                ],
            )
        };
        let slices = vec![
            folded(1.0, 4.0, 6.0),
            folded(2.0, 4.5, 5.5),
            slice(3.0, &[], &[(0.0, true), (10.0, true)]),
        ];
        let map = build_map("q", slices, None);
        assert_eq!(map.curves.len(), 2, "{:?}", map.curves);
        assert_eq!(map.curves[0].points, vec![(1.0, 6.0), (2.0, 5.5)]);
        assert_eq!(map.curves[1].points, vec![(1.0, 4.0), (2.0, 4.5)]);
        assert_eq!(
            map.pair_ends,
            vec![PairEnd {
                p_with: 2.0,
                p_without: 3.0,
                omega: 5.0,
                run: "p2".into(),
                refined: 0,
            }]
        );
        // at p = 1, ω = 4.5 is covered by three segments: 0→6 (stable), 5.9→4.1
        // (unstable), 4→10 (stable)
        let r = map
            .regions
            .iter()
            .find(|r| r.p == 1.0 && r.omega_from <= 4.5 && 4.5 <= r.omega_to)
            .expect("a region");
        assert_eq!((r.stable, r.unstable), (2, 1), "{r:?}");
        assert!(
            map.regions
                .iter()
                .filter(|r| r.p == 3.0)
                .all(|r| r.stable == 1)
        );
    }

    /// Points of different kinds are never joined, nor points further apart than the
    /// tolerance.
    #[test]
    fn kinds_and_distances_keep_curves_apart() {
        use BifurcationKind::{NeimarkSacker as NS, SaddleNode as SN};
        let slices = vec![
            slice(1.0, &[(SN, 5.0)], &[(0.0, true), (10.0, true)]),
            slice(2.0, &[(NS, 5.0)], &[(0.0, true), (10.0, true)]),
            slice(3.0, &[(NS, 9.0)], &[(0.0, true), (10.0, true)]),
        ];
        let map = build_map("q", slices, Some(1.0));
        assert_eq!(map.curves.len(), 3, "{:?}", map.curves);
    }
}
