//! Sweep campaigns: several studies from one TOML file, run in parallel, one recording per
//! run plus a manifest.
//!
//! ```toml
//! output_dir = "campaign-out"        # relative to the campaign file
//! [defaults]                         # StudySettings keys applied to every run
//! order = 3
//! [[runs]]
//! name = "q20"
//! flow_l_min = 20.0
//! [[runs]]
//! name = "q2-50C"
//! flow_l_min = 2.0
//! cooling_temp_c = 50.0
//! ```
//!
//! or a grid, every combination of the values one run (named `q20-25C`, … by the
//! template; without one, `cooling_temp_c=25_flow_l_min=20`, …), before any `[[runs]]`:
//!
//! ```toml
//! [grid]
//! name = "q{flow_l_min}-{cooling_temp_c}C"
//! flow_l_min = [20.0, 10.0, 5.0, 2.0, 1.0]
//! cooling_temp_c = [25.0, 50.0]
//! ```
//!
//! Any value of the model file can be set by its path, in `[defaults]`, a run or the grid
//! (`set` tables merge path by path: defaults, then grid, then run; see
//! [`crate::model::set`] for the paths); each run's edited model is validated before
//! anything runs, and the values are recorded in the manifest's settings, the
//! recording's settings and its embedded model:
//!
//! ```toml
//! [grid]
//! name = "fv{thermal.bearings[2#].f_v}"
//! set."thermal.bearings[2#].f_v" = [2.0, 3.0, 4.0]
//! ```
//!
//! * runs execute in parallel, `threads` at a time (default: one per core), each on its
//!   own thread with its own rayon pool of `threads / concurrent runs` threads (one each
//!   when there are at least as many runs as threads), so that one run's parallel parts
//!   never wait behind another's; a campaign of one run uses the global pool;
//! * `manifest.toml` in the output directory lists every run: settings, status, points,
//!   wall time, the recording's file name and SHA-256; it is rewritten after each run;
//! * resumable: a run whose recording exists with the checksum the manifest recorded and a
//!   `completed` status is skipped; anything else (missing, interrupted, failed, changed)
//!   is run again;
//! * interrupt (`interrupt` set, Ctrl-C on the command line): the runs under way stop and
//!   record what they computed (`interrupted`), no further run starts; a run not started
//!   keeps its earlier manifest entry (and recording), or is listed `pending`;
//! * `shard = (i, n)` runs only the runs whose position `p` satisfies `p mod n = i`
//!   (deterministic, so a cluster scheduler can split a campaign into `n` jobs), writing
//!   `manifest-shard-i-of-n.toml`; [`merge_manifests`] joins the shard manifests;
//! * the figure module's `plot_campaign` (one layer up) overlays the runs' recordings in
//!   PNG figures like the paper's (amplitude of node 8, clearances, temperatures).

pub mod map;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::AtomicBool;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use thiserror::Error;

use crate::record::{McapOptions, McapSink, ReadError};
use crate::sweep::{CurrentPool, Progress, StepPools, StudySettings, SweepProblem};

/// The lock file of a campaign's output directory, held while a campaign runs there.
pub const CAMPAIGN_LOCK: &str = "campaign.lock";

/// A campaign file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignFile {
    /// Output directory, relative to the campaign file (default: `<file stem>-out`).
    pub output_dir: Option<PathBuf>,
    /// Lean recordings: without `/orbits` and `/scene`, which replay re-derives from
    /// `/harmonics` ([`McapOptions::lean`]). Default false.
    #[serde(default)]
    pub lean: bool,
    /// Settings shared by all runs (keys of [`StudySettings`]).
    #[serde(default)]
    pub defaults: toml::Table,
    /// A grid of runs: each key a [`StudySettings`] key with an array of values, every
    /// combination one run (see [`expand_grid`]); optional `name`, a template such as
    /// `"q{flow_l_min}-{cooling_temp_c}C"`.
    #[serde(default)]
    pub grid: Option<toml::Table>,
    /// The runs: a unique `name` plus any [`StudySettings`] keys (after the grid's).
    #[serde(default)]
    pub runs: Vec<toml::Table>,
}

/// One run of a campaign, resolved.
#[derive(Clone, Debug)]
pub struct CampaignRun {
    pub name: String,
    pub settings: StudySettings,
    /// SHA-256 of the run's model text after `set` (filled when the runs are checked
    /// before a campaign starts; empty from [`load`]).
    pub model_sha256: String,
    /// Write a lean recording (the campaign file's `lean`).
    pub lean: bool,
    /// A transient run instead of a sweep (the run's `transient` table).
    pub transient: Option<TransientRun>,
}

/// A campaign run integrated in time instead of swept (`transient = { … }` in a run):
/// the coupled rotor from a cold start (temperatures at ambient, the static equilibrium)
/// over a speed profile, as `tmrotor transient --speed` or `--ramp` runs it, written to
/// the run's recording on the simulated time axis.
///
/// ```toml
/// [[runs]]
/// name = "runup-1"
/// flow_l_min = 1.0
/// transient = { ramp = "400:650", accel = 1.0 }
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransientRun {
    /// A fixed speed, rad/s.
    pub speed: Option<f64>,
    /// A linear run-up (`"START:END"`, START < END) or coast-down, rad/s.
    pub ramp: Option<String>,
    /// The ramp's acceleration magnitude, rad/s² (default 10).
    pub accel: Option<f64>,
    /// Simulated time, s (default: the ramp's end plus 1 s; 100 revolutions at a fixed
    /// speed).
    pub duration_s: Option<f64>,
    /// Relative local error tolerance of the mechanical integrator (default 1e-4, as
    /// `tmrotor transient`).
    pub rtol: Option<f64>,
    /// Displacement samples per revolution on `/transient/samples` (default 16).
    pub samples_per_rev: Option<u32>,
    /// Start on a point of this sweep run of the campaign instead of a cold start (with
    /// `point`); the run then takes that run's model and settings, and starts once it has
    /// ended.
    pub from: Option<String>,
    /// Index of the point of `from`'s recording to start on.
    pub point: Option<u64>,
    /// With `from`: scale the start's vibration by 1 + `perturb`; with `perturb_mode`, the
    /// size of the step along that Floquet mode (as `tmrotor transient --perturb`).
    pub perturb: Option<f64>,
    /// With `from`: perturb along the K-th Floquet mode nearest zero (0: the largest real
    /// part of its exponent), by `perturb` of the orbit's vibration.
    pub perturb_mode: Option<usize>,
}

impl TransientRun {
    /// The integrator's settings, checked; the error says which key and why. `start_speed`
    /// is the speed of the point a run `from` a sweep starts on: without `speed` or `ramp`
    /// the run holds it.
    pub fn settings(
        &self,
        start_speed: Option<f64>,
    ) -> Result<crate::transient::TransientSettings, String> {
        use crate::integrate::{SpeedProfile, TransientOptions};
        self.check_start()?;
        let profile = match (
            &self.ramp,
            self.speed.or(start_speed.filter(|_| self.ramp.is_none())),
        ) {
            (Some(_), Some(_)) => return Err("transient: give speed or ramp, not both".into()),
            (Some(r), None) => {
                let parsed = r
                    .split_once(':')
                    .and_then(|(a, b)| Some((a.trim().parse().ok()?, b.trim().parse().ok()?)));
                let Some((from, to)) = parsed else {
                    return Err(format!(
                        "transient.ramp {r:?}: must be \"START:END\" in rad/s"
                    ));
                };
                if from == to {
                    return Err(format!(
                        "transient.ramp {r:?}: START and END are equal; use speed"
                    ));
                }
                SpeedProfile::Ramp {
                    from,
                    to,
                    accel: self.accel.unwrap_or(10.0),
                }
            }
            (None, Some(w)) => {
                if self.accel.is_some() {
                    return Err("transient.accel: only with a ramp".into());
                }
                SpeedProfile::Constant(w)
            }
            (None, None) => {
                return Err(
                    "transient: give speed (rad/s) or ramp (\"START:END\"), or from and point \
                     (the point's speed)"
                        .into(),
                );
            }
        };
        profile.check().map_err(|e| {
            format!(
                "transient.{}: {e}",
                if self.ramp.is_some() {
                    "ramp/accel"
                } else {
                    "speed"
                }
            )
        })?;
        let duration_s = self
            .duration_s
            .unwrap_or_else(|| profile.default_duration());
        if !(duration_s.is_finite() && duration_s > 0.0 && duration_s <= 1e6) {
            return Err(format!(
                "transient.duration_s {duration_s}: the simulated time must lie in (0, 1e6] s"
            ));
        }
        let rtol = self.rtol.unwrap_or(crate::transient::DEFAULT_RTOL);
        if !(rtol.is_finite() && rtol > 0.0 && rtol < 1.0) {
            return Err(format!("transient.rtol {rtol}: must lie in (0, 1)"));
        }
        let samples_per_revolution = self
            .samples_per_rev
            .unwrap_or(crate::transient::DEFAULT_SAMPLES_PER_REVOLUTION);
        if samples_per_revolution > 4096 {
            return Err(format!(
                "transient.samples_per_rev {samples_per_revolution}: at most 4096"
            ));
        }
        Ok(crate::transient::TransientSettings {
            profile,
            duration_s,
            options: TransientOptions {
                rtol,
                ..TransientOptions::default()
            },
            samples_per_revolution,
        })
    }
}

impl TransientRun {
    /// The start keys together: `from` with `point`, perturbations only from a point.
    fn check_start(&self) -> Result<(), String> {
        match (&self.from, self.point) {
            (Some(_), None) => {
                return Err("transient.from: give the point to start on (point = INDEX)".into());
            }
            (None, Some(_)) => {
                return Err(
                    "transient.point: give the sweep run it belongs to (from = \"RUN\")".into(),
                );
            }
            (Some(run), _) if run.is_empty() => {
                return Err("transient.from: name a sweep run of this campaign".into());
            }
            _ => {}
        }
        if self.from.is_none() && (self.perturb.is_some() || self.perturb_mode.is_some()) {
            return Err(
                "transient.perturb: only with from and point (a cold start has no orbit to perturb)"
                    .into(),
            );
        }
        if let Some(f) = self.perturb
            && !(f.is_finite() && f > -1.0 && f.abs() <= 10.0)
        {
            return Err(format!("transient.perturb {f}: must lie in (-1, 10]"));
        }
        if let Some(k) = self.perturb_mode
            && self.perturb.is_none_or(|f| f == 0.0)
        {
            return Err(format!(
                "transient.perturb_mode {k}: give the size with perturb (a fraction of the \
                 orbit's vibration, e.g. 0.01)"
            ));
        }
        Ok(())
    }

    /// The run's start state: a cold start, or the point of `from`'s recording at
    /// `source` (perturbed as asked), with the problem to integrate and the start's speed.
    fn start(
        &self,
        run: &CampaignRun,
        source: &Path,
    ) -> Result<(SweepProblem, crate::transient::StartState, Option<f64>), String> {
        let Some(point) = self.point else {
            let problem = SweepProblem::new(&run.settings).map_err(|e| e.to_string())?;
            let start = crate::transient::StartState::cold(&problem);
            return Ok((problem, start, None));
        };
        let recorded =
            crate::transient::RecordedStart::read(source, point).map_err(|e| e.to_string())?;
        let perturb = self.perturb.unwrap_or(0.0);
        let start = match self.perturb_mode {
            None => recorded.on_orbit(perturb, 0.0),
            Some(k) => {
                recorded
                    .along_mode(k, perturb, 0.0)
                    .map_err(|e| e.to_string())?
                    .0
            }
        };
        Ok((recorded.problem, start, Some(recorded.omega)))
    }
}

/// Errors of a campaign.
#[derive(Debug, Error)]
pub enum CampaignError {
    #[error("{file}: {reason}")]
    File { file: String, reason: String },
    #[error("{file}: runs[{index}]: {reason}")]
    Run {
        file: String,
        index: usize,
        reason: String,
    },
    /// A run's settings are refused by the sweep (checked before any run starts).
    #[error("{file}: run {run}: {reason}")]
    Invalid {
        file: String,
        run: String,
        reason: String,
    },
    /// A run of the grid (named by its values) is not a valid study.
    #[error("{file}: grid run {run}: {reason}")]
    GridRun {
        file: String,
        run: String,
        reason: String,
    },
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    /// A run's recording cannot be read (the error names the file).
    #[error("run {run} (manifest status {status:?}): {error}")]
    Recording {
        run: String,
        status: String,
        error: ReadError,
    },
    /// A figure could not be drawn or written (the figures' own error, whose message
    /// names the file).
    #[error(transparent)]
    Figure(Box<dyn std::error::Error + Send + Sync>),
    /// A recording the record layer refused (its message names the file).
    #[error(transparent)]
    Record(#[from] crate::record::RecordError),
    /// A file the record layer could not read (its message names the file).
    #[error(transparent)]
    Read(#[from] ReadError),
}

/// One line of the manifest.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ManifestEntry {
    pub name: String,
    /// `completed`, `interrupted`, `failed: …`, or `pending`.
    pub status: String,
    /// How a completed run's branch ended (`reached ω = 700.000 rad/s`, or why it stopped
    /// before: the maximum number of points, a step below `ds_min`, a closed curve).
    #[serde(default)]
    pub ended: String,
    pub points: usize,
    /// Continuation steps refused and retried with half the step (see
    /// [`crate::sweep::SweepReport::rejected_steps`]); absent in older manifests.
    #[serde(default)]
    pub refused_steps: usize,
    pub seconds: f64,
    /// Where the run's time went ([`crate::sweep::SweepReport::time_summary`]); absent in
    /// older manifests and for runs that did not finish their sweep.
    #[serde(default)]
    pub time: String,
    pub recording: String,
    pub sha256: String,
    pub bifurcations: Vec<String>,
    pub settings: toml::Table,
    /// SHA-256 of the model file the run used, after its `set` values (the text its
    /// recording embeds): a run is complete only for this model; absent in older manifests,
    /// whose runs are therefore run again.
    #[serde(default)]
    pub model_sha256: String,
}

/// The manifest file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub campaign: String,
    pub tool_version: String,
    #[serde(default)]
    pub runs: Vec<ManifestEntry>,
}

/// Reads and resolves a campaign file.
pub fn load(path: &Path) -> Result<(CampaignFile, Vec<CampaignRun>, PathBuf), CampaignError> {
    let file = path.display().to_string();
    let text = crate::input::read_text(path, crate::input::MAX_INPUT_BYTES).map_err(|source| {
        CampaignError::Io {
            path: file.clone(),
            source,
        }
    })?;
    let spec: CampaignFile = toml::from_str(&text).map_err(|e| CampaignError::File {
        file: file.clone(),
        reason: e.to_string().trim_end().to_string(),
    })?;
    let grid = match &spec.grid {
        Some(g) => expand_grid(g).map_err(|reason| CampaignError::File {
            file: file.clone(),
            reason,
        })?,
        None => Vec::new(),
    };
    if spec.runs.is_empty() && grid.is_empty() {
        return Err(CampaignError::File {
            file,
            reason: "no runs: give [[runs]] tables, a [grid], or both".into(),
        });
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let mut runs: Vec<CampaignRun> = Vec::new();
    // where a run came from, for its errors
    enum Origin<'a> {
        Grid(&'a str),
        Runs(usize),
    }
    let error = |origin: &Origin<'_>, reason: String| match origin {
        Origin::Grid(run) => CampaignError::GridRun {
            file: file.clone(),
            run: run.to_string(),
            reason,
        },
        Origin::Runs(index) => CampaignError::Run {
            file: file.clone(),
            index: *index,
            reason,
        },
    };
    let listed = spec.runs.iter().enumerate().map(|(index, table)| {
        let name = table
            .get("name")
            .and_then(toml::Value::as_str)
            .map(str::to_string);
        (Origin::Runs(index), name, table)
    });
    let gridded = grid
        .iter()
        .map(|(name, table)| (Origin::Grid(name), Some(name.clone()), table));
    for (origin, name, table) in gridded.chain(listed) {
        let mut merged = spec.defaults.clone();
        for (k, v) in table.iter().filter(|(k, _)| k.as_str() != "name") {
            // `set` tables merge path by path (defaults, then grid, then run)
            match (merged.get_mut(k), v) {
                (Some(toml::Value::Table(base)), toml::Value::Table(more)) if k == "set" => {
                    base.extend(more.iter().map(|(p, x)| (p.clone(), x.clone())));
                }
                _ => {
                    merged.insert(k.clone(), v.clone());
                }
            }
        }
        let transient = match merged.remove("transient") {
            None => None,
            Some(v) => {
                let t: TransientRun = v.try_into().map_err(|e: toml::de::Error| {
                    error(&origin, format!("transient: {}", e.to_string().trim_end()))
                })?;
                // a run from a point holds that point's speed unless told otherwise, known
                // once its sweep has run: any speed checks the other keys now
                t.settings(t.from.as_ref().map(|_| 1.0))
                    .map_err(|e| error(&origin, e))?;
                if t.from.is_some()
                    && let Some(key) = table
                        .keys()
                        .find(|k| !matches!(k.as_str(), "name" | "transient"))
                {
                    return Err(error(
                        &origin,
                        format!(
                            "{key}: a transient run from a recorded point takes the model and \
                             settings of its sweep run (transient.from); leave {key} out"
                        ),
                    ));
                }
                Some(t)
            }
        };
        let name = name.ok_or_else(|| error(&origin, "missing `name` (a string)".into()))?;
        if name.is_empty() || name.contains(['/', '\\']) || runs.iter().any(|r| r.name == name) {
            return Err(error(
                &origin,
                format!("name {name:?} must be unique, non-empty and contain no path separator"),
            ));
        }
        let mut settings: StudySettings = toml::Value::Table(merged)
            .try_into()
            .map_err(|e: toml::de::Error| error(&origin, e.to_string().trim_end().to_string()))?;
        if let Some(m) = &settings.model
            && m.is_relative()
        {
            settings.model = Some(base.join(m));
        }
        runs.push(CampaignRun {
            name,
            settings,
            model_sha256: String::new(),
            lean: spec.lean,
            transient,
        });
    }
    from_sweep_runs(&file, &mut runs)?;
    let out = match &spec.output_dir {
        Some(d) if d.is_relative() => base.join(d),
        Some(d) => d.clone(),
        None => base.join(format!(
            "{}-out",
            path.file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("campaign")
        )),
    };
    Ok((spec, runs, out))
}

/// The values of one grid axis with their text for run names.
type Axis = Vec<(toml::Value, String)>;

/// Most runs a grid may expand to: 10 000 (a campaign of sweeps of seconds to minutes
/// each; more is a typo, or several campaigns).
pub const MAX_GRID_RUNS: usize = 10_000;

/// The runs of a `[grid]` table: `(name, settings)` for every combination of the values
/// of its keys, the keys in alphabetical order with the first varying slowest. Each key is
/// a [`StudySettings`] key with a non-empty array of numbers, strings or booleans; the
/// optional `name` is a template whose `{key}` parts are replaced by that run's values
/// (default: `key=value` parts joined by `_`, e.g. `cooling_temp_c=25_flow_l_min=2`).
/// Numbers print without a trailing `.0` (20.0 → `20`, 2.5 → `2.5`). A `set` table in the
/// grid gives one axis per model-file path (`set."thermal.bearings[2#].f_v" = [2.0, 3.0]`,
/// template part `{thermal.bearings[2#].f_v}`), set on the run's model file (see
/// [`crate::model::set`]). The error names the key.
pub fn expand_grid(grid: &toml::Table) -> Result<Vec<(String, toml::Table)>, String> {
    let template = match grid.get("name") {
        None => None,
        Some(toml::Value::String(t)) => Some(t.as_str()),
        Some(_) => return Err("grid.name: must be a string (a template)".into()),
    };
    // `set."path" = [..]`: one axis per path of the model file, named by the path
    let set_axes = match grid.get("set") {
        None => Vec::new(),
        Some(toml::Value::Table(t)) => t.iter().map(|(p, v)| (p.as_str(), v, true)).collect(),
        Some(_) => {
            return Err(
                "grid.set: must be a table of model-file paths, each with an array of values"
                    .into(),
            );
        }
    };
    let study_axes = grid
        .iter()
        .filter(|(k, _)| k.as_str() != "name" && k.as_str() != "set")
        .map(|(k, v)| (k.as_str(), v, false));
    // (key, is a model-file path, values with their text)
    let mut axes: Vec<(&str, bool, Axis)> = Vec::new();
    for (key, values, is_set) in study_axes.chain(set_axes) {
        let key_text = if is_set {
            format!("set.\"{key}\"")
        } else {
            key.to_string()
        };
        let toml::Value::Array(values) = values else {
            return Err(format!("grid.{key_text}: must be an array of values"));
        };
        if values.is_empty() {
            return Err(format!("grid.{key_text}: has no values"));
        }
        let mut axis = Vec::with_capacity(values.len());
        for v in values {
            let text = match v {
                toml::Value::Float(x) if x.fract() == 0.0 && x.abs() < 1e15 => format!("{x:.0}"),
                toml::Value::Float(x) => x.to_string(),
                toml::Value::Integer(i) => i.to_string(),
                toml::Value::String(s) => s.clone(),
                toml::Value::Boolean(b) => b.to_string(),
                _ => {
                    return Err(format!(
                        "grid.{key_text}: values must be numbers, strings or booleans"
                    ));
                }
            };
            axis.push((v.clone(), text));
        }
        axes.push((key, is_set, axis));
    }
    if axes.is_empty() {
        return Err("grid: no keys with values".into());
    }
    if let Some(t) = template {
        // every `{…}` in the template must name a key of the grid
        let mut rest = t;
        while let Some(open) = rest.find('{') {
            let Some(close) = rest[open..].find('}') else {
                return Err(format!("grid.name: unclosed `{{` in {t:?}"));
            };
            let key = &rest[open + 1..open + close];
            if !axes.iter().any(|(k, _, _)| *k == key) {
                return Err(format!(
                    "grid.name: {{{key}}} in {t:?} is not a key of the grid"
                ));
            }
            rest = &rest[open + close + 1..];
        }
    }
    // Checked before anything is allocated: a typo in a grid (a range of a million values)
    // must not become a million runs, or an overflow.
    let sizes: Vec<String> = axes.iter().map(|(_, _, a)| a.len().to_string()).collect();
    let count = axes
        .iter()
        .try_fold(1usize, |n, (_, _, a)| n.checked_mul(a.len()))
        .filter(|&n| n <= MAX_GRID_RUNS)
        .ok_or_else(|| {
            format!(
                "grid: {} runs is more than the {MAX_GRID_RUNS} a campaign takes (split it \
                 into several campaigns)",
                sizes.join(" × ")
            )
        })?;
    let mut runs = Vec::with_capacity(count);
    for mut index in (0..count).rev() {
        // mixed radix, the last key fastest; built backwards, reversed below
        let mut table = toml::Table::new();
        let mut picked = Vec::with_capacity(axes.len());
        for (key, is_set, axis) in axes.iter().rev() {
            let (value, text) = &axis[index % axis.len()];
            index /= axis.len();
            if *is_set {
                if let toml::Value::Table(set) = table
                    .entry("set")
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                {
                    set.insert((*key).to_string(), value.clone());
                }
            } else {
                table.insert((*key).to_string(), value.clone());
            }
            picked.push((*key, text.as_str()));
        }
        picked.reverse();
        let name = match template {
            Some(t) => picked
                .iter()
                .fold(t.to_string(), |n, (k, v)| n.replace(&format!("{{{k}}}"), v)),
            None => picked
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join("_"),
        };
        runs.push((name, table));
    }
    runs.reverse();
    Ok(runs)
}

/// SHA-256 of a file, hex.
pub fn sha256_file(path: &Path) -> Result<String, std::io::Error> {
    let bytes = std::fs::read(path)?;
    let digest = Sha256::digest(&bytes);
    Ok(digest.iter().map(|b| format!("{b:02x}")).collect())
}

/// Reads `path` as a campaign manifest; errors name the file and the reason.
pub fn parse_manifest(path: &Path) -> Result<Manifest, CampaignError> {
    let file = path.display().to_string();
    let text = crate::input::read_text(path, crate::input::MAX_INPUT_BYTES).map_err(|e| {
        CampaignError::File {
            file: file.clone(),
            reason: format!("cannot read the campaign manifest: {e}"),
        }
    })?;
    toml::from_str(&text).map_err(|e| CampaignError::File {
        file,
        reason: format!(
            "not a campaign manifest: {}",
            e.to_string().trim_end().replace('\n', " ")
        ),
    })
}

fn write_manifest(path: &Path, m: &Manifest) -> Result<(), CampaignError> {
    let text = toml::to_string(m).map_err(|e| CampaignError::File {
        file: path.display().to_string(),
        reason: e.to_string(),
    })?;
    let tmp = path.with_extension("toml.tmp");
    std::fs::write(&tmp, text)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|source| CampaignError::Io {
            path: path.display().to_string(),
            source,
        })
}

/// Manifest file name for a shard (`manifest.toml` without sharding).
pub fn manifest_name(shard: Option<(usize, usize)>) -> String {
    match shard {
        Some((i, n)) => format!("manifest-shard-{i}-of-{n}.toml"),
        None => "manifest.toml".into(),
    }
}

/// What a campaign reports while it runs (to [`run`]'s `progress`), in this order for each
/// run: [`Event::Skipped`], or [`Event::Point`]s then [`Event::Finished`].
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// Before anything starts: the names of the runs this invocation covers (its shard's),
    /// in file order.
    Plan { runs: &'a [String] },
    /// A run completed by an earlier invocation, whose recording is unchanged: not redone.
    Skipped {
        run: &'a str,
        entry: &'a ManifestEntry,
    },
    /// A run's continuation accepted a point (or is leading in to its start).
    Point {
        run: &'a str,
        progress: &'a Progress,
    },
    /// A run ended (completed, interrupted or failed), with its manifest entry.
    Finished {
        run: &'a str,
        entry: &'a ManifestEntry,
    },
}

/// What an invocation of a campaign starts from: this shard's runs (checked), the
/// manifest of an earlier invocation, where everything goes.
struct Prepared {
    runs: Vec<CampaignRun>,
    previous: Manifest,
    out: PathBuf,
    manifest_path: PathBuf,
}

/// Loads the campaign file, selects the shard's runs, checks each with the sweep's own
/// check (a run the sweep would refuse stops everything before anything is computed: a bad
/// value in a grid is found now, not hours later) and reads the earlier manifest. Writes
/// nothing.
fn prepare(campaign_path: &Path, shard: Option<(usize, usize)>) -> Result<Prepared, CampaignError> {
    let (_, runs, out) = load(campaign_path)?;
    let manifest_path = out.join(manifest_name(shard));
    // An unreadable manifest stops the campaign: taking it as empty would run every run
    // again and overwrite recordings that may be complete.
    let previous = if manifest_path.exists() {
        parse_manifest(&manifest_path).map_err(|e| match e {
            CampaignError::File { file, reason } => CampaignError::File {
                file,
                reason: format!(
                    "{reason}; nothing was run and the recordings beside it are kept: repair \
                     the manifest, or move it away to run every run again"
                ),
            },
            other => other,
        })?
    } else {
        Manifest::default()
    };
    let runs: Vec<CampaignRun> = runs
        .into_iter()
        .enumerate()
        .filter(|(p, _)| shard.is_none_or(|(i, n)| p % n == i))
        .map(|(_, r)| r)
        .collect();
    let mut runs = runs;
    for r in &mut runs {
        let problem = SweepProblem::new(&r.settings).map_err(|e| CampaignError::Invalid {
            file: campaign_path.display().to_string(),
            run: r.name.clone(),
            reason: e.to_string(),
        })?;
        r.model_sha256 = crate::record::convert::sha256_hex(&problem.model.text);
    }
    Ok(Prepared {
        runs,
        previous,
        out,
        manifest_path,
    })
}

/// The earlier manifest's entry of run `name`, if it lists the run.
fn previous_entry<'m>(previous: &'m Manifest, name: &str) -> Option<&'m ManifestEntry> {
    previous.runs.iter().find(|e| e.name == name)
}

/// The runs that start from a recorded point (`transient.from`): each names a sweep run of
/// the campaign, and takes its settings (what ran is what the manifest lists).
fn from_sweep_runs(file: &str, runs: &mut [CampaignRun]) -> Result<(), CampaignError> {
    for k in 0..runs.len() {
        let Some(source) = runs[k].transient.as_ref().and_then(|t| t.from.clone()) else {
            continue;
        };
        let fail = |reason: String| CampaignError::Invalid {
            file: file.to_string(),
            run: runs[k].name.clone(),
            reason,
        };
        let Some(src) = runs.iter().find(|r| r.name == source) else {
            return Err(fail(format!(
                "transient.from {source:?}: the campaign has no run of that name"
            )));
        };
        if src.transient.is_some() {
            return Err(fail(format!(
                "transient.from {source:?}: that run is a transient run; start from a sweep run"
            )));
        }
        runs[k].settings = src.settings.clone();
    }
    Ok(())
}

/// The earlier entry `prev` when its run is complete and need not run again: status
/// `completed`, the same `settings`, the same model text (`model_sha256`: an edited model
/// file runs again), and its recording at `rec_path` unchanged (the checksum the manifest
/// recorded).
fn completed_before<'m>(
    prev: Option<&'m ManifestEntry>,
    settings: &toml::Table,
    model_sha256: &str,
    rec_path: &Path,
) -> Option<&'m ManifestEntry> {
    let prev = prev?;
    (prev.status == "completed"
        && prev.settings == *settings
        && prev.model_sha256 == model_sha256
        && sha256_file(rec_path).ok().as_deref() == Some(prev.sha256.as_str()))
    .then_some(prev)
}

/// How the runs of one invocation ended, by name, for the runs waiting on them.
#[derive(Default)]
struct Ended {
    status: Mutex<BTreeMap<String, String>>,
    changed: std::sync::Condvar,
}

impl Ended {
    fn set(&self, run: &str, status: &str) {
        if let Ok(mut m) = self.status.lock() {
            m.insert(run.to_string(), status.to_string());
        }
        self.changed.notify_all();
    }

    /// Waits until `run` has ended (its status) or `stop` says so (`None`).
    fn wait_for(&self, run: &str, stop: &dyn Fn() -> bool) -> Option<String> {
        let mut m = self.status.lock().ok()?;
        loop {
            if let Some(s) = m.get(run) {
                return Some(s.clone());
            }
            if stop() {
                return None;
            }
            m = self
                .changed
                .wait_timeout(m, std::time::Duration::from_millis(200))
                .ok()?
                .0;
        }
    }
}

/// Adds the checksum of sweep run `source`'s recording in `out` to a transient run's
/// manifest settings: a run from a recorded point is complete only for the recording it
/// started from (empty when the recording cannot be read; the run then fails saying why).
fn with_source_checksum(settings: &mut toml::Table, out: &Path, source: &str) {
    let sha = sha256_file(&out.join(format!("{source}.mcap"))).unwrap_or_default();
    if let Some(toml::Value::Table(t)) = settings.get_mut("transient") {
        t.insert("from_sha256".into(), toml::Value::String(sha));
    }
}

/// Where run `r`'s recording goes in `out`, and its settings as a manifest table.
fn recording_and_settings(r: &CampaignRun, out: &Path) -> (PathBuf, toml::Table) {
    let mut table = toml::Table::try_from(&r.settings).unwrap_or_default();
    if let Some(t) = &r.transient
        && let Ok(v) = toml::Value::try_from(t)
    {
        table.insert("transient".into(), v);
    }
    (out.join(format!("{}.mcap", r.name)), table)
}

impl ManifestEntry {
    /// A transient run (its settings hold a `transient` table): a recording on the time
    /// axis, which the campaign figures and the report leave out.
    pub fn is_transient(&self) -> bool {
        self.settings.contains_key("transient")
    }

    /// `13 points`, or `78 revolutions` for a transient run.
    pub fn count_text(&self) -> String {
        let (one, many) = if self.is_transient() {
            ("revolution", "revolutions")
        } else {
            ("point", "points")
        };
        format!(
            "{} {}",
            self.points,
            if self.points == 1 { one } else { many }
        )
    }
}

/// One run of a campaign as its next invocation would take it ([`plan`]).
#[derive(Clone, Debug)]
pub struct PlannedRun {
    pub run: CampaignRun,
    /// Its position in the campaign file's run list (grid first), which decides its shard.
    pub position: usize,
    /// What the earlier manifest says of it (`completed`, `interrupted`, `failed: …`,
    /// `pending`), if it lists it.
    pub previous: Option<String>,
    /// Complete and unchanged: it would be skipped.
    pub skip: bool,
}

/// What `run` would do, without running or writing anything: this shard's runs (checked
/// like [`run`] checks them), with their positions and whether each would be skipped; and
/// the output directory.
pub fn plan(
    campaign_path: &Path,
    shard: Option<(usize, usize)>,
) -> Result<(Vec<PlannedRun>, PathBuf), CampaignError> {
    let p = prepare(campaign_path, shard)?;
    let mut planned: Vec<PlannedRun> = p
        .runs
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let prev = previous_entry(&p.previous, &r.name);
            let (rec_path, mut settings) = recording_and_settings(r, &p.out);
            if let Some(source) = r.transient.as_ref().and_then(|t| t.from.as_deref()) {
                with_source_checksum(&mut settings, &p.out, source);
            }
            PlannedRun {
                run: r.clone(),
                position: shard.map_or(k, |(i, n)| i + k * n),
                previous: prev.map(|e| e.status.clone()),
                skip: completed_before(prev, &settings, &r.model_sha256, &rec_path).is_some(),
            }
        })
        .collect();
    // a run from a point of a sweep that runs again runs again too
    let rerun: Vec<String> = planned
        .iter()
        .filter(|r| !r.skip)
        .map(|r| r.run.name.clone())
        .collect();
    for r in &mut planned {
        if r.run
            .transient
            .as_ref()
            .and_then(|t| t.from.as_ref())
            .is_some_and(|s| rerun.contains(s))
        {
            r.skip = false;
        }
    }
    Ok((planned, p.out))
}

/// Runs a campaign. `progress` is told what happens ([`Event`]), from the worker threads.
pub fn run(
    campaign_path: &Path,
    threads: Option<usize>,
    shard: Option<(usize, usize)>,
    interrupt: Option<Arc<AtomicBool>>,
    progress: &(dyn Fn(Event<'_>) + Sync),
) -> Result<Manifest, CampaignError> {
    let Prepared {
        runs: selected,
        previous,
        out,
        manifest_path,
    } = prepare(campaign_path, shard)?;
    let _lock = lock_output(campaign_path, &out)?;
    let names: Vec<String> = selected.iter().map(|r| r.name.clone()).collect();
    progress(Event::Plan { runs: &names });
    let manifest = Mutex::new(pending_manifest(campaign_path, &selected, &out));
    // One OS thread per concurrent run, taking runs from a shared counter in file order;
    // each run's own parallel parts (Floquet products, orbit sampling, condensed blocks)
    // go to a rayon pool of its own. Running the runs themselves as rayon tasks would let
    // a thread waiting inside one run's parallel section pick up a whole other run and
    // leave the first one stalled behind it (measured: 119 % CPU on 2 cores). Sharing the
    // global pool between the concurrent runs kept both cores busy, but their fine-grained
    // parallel sections spent the CPU on splitting, spinning and waking each other: on the
    // paper campaign (2 cores, two runs at a time, three pairs back to back) 206–215 s
    // wall and 380–398 s CPU against 175–209 s and 317–380 s with one single-thread pool
    // per run, the same results.
    let workers = threads.filter(|&t| t > 0).unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    let slots = workers.min(selected.len().max(1));
    let run_pool = run_pool(workers, slots);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let tail = Tail {
        runs: selected.len(),
        next: &next,
        active: std::sync::atomic::AtomicUsize::new(0),
        workers,
        wide: std::sync::OnceLock::new(),
    };
    // how each run of this invocation ended, for the runs that start from its points
    let ended = Ended::default();
    // After an interrupt no further run is started (it would only write an empty recording
    // over whatever an earlier attempt left).
    let interrupted = || {
        interrupt
            .as_ref()
            .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
    };
    let finish = |k: usize, r: &CampaignRun, entry: ManifestEntry| {
        if let Ok(mut m) = manifest.lock() {
            m.runs[k] = entry.clone();
            let _ = write_manifest(&manifest_path, &m);
        }
        ended.set(&r.name, &entry.status);
        progress(Event::Finished {
            run: &r.name,
            entry: &entry,
        });
    };
    let work = |k: usize, r: &CampaignRun| {
        let (rec_path, mut settings_table) = recording_and_settings(r, &out);
        if let Some(source) = r.transient.as_ref().and_then(|t| t.from.as_deref()) {
            let in_this = selected.iter().any(|s| s.name == source);
            let status = if in_this {
                ended.wait_for(source, &interrupted)
            } else {
                None
            };
            if interrupted() {
                return;
            }
            if let Some(status) = status.filter(|s| s != "completed") {
                let entry = ManifestEntry {
                    status: format!(
                        "failed: its sweep run {source} ended {status:?}; nothing was started"
                    ),
                    ..manifest
                        .lock()
                        .map(|m| m.runs[k].clone())
                        .unwrap_or_default()
                };
                finish(k, r, entry);
                return;
            }
            with_source_checksum(&mut settings_table, &out, source);
        }
        // Resume: skip a completed run whose recording is unchanged.
        let prev = previous_entry(&previous, &r.name);
        if let Some(prev) = completed_before(prev, &settings_table, &r.model_sha256, &rec_path) {
            if let Ok(mut m) = manifest.lock() {
                m.runs[k] = prev.clone();
            }
            ended.set(&r.name, &prev.status);
            progress(Event::Skipped {
                run: &r.name,
                entry: prev,
            });
            return;
        }
        let entry = run_in_pool(run_pool, &tail, r, &rec_path, interrupt.clone(), progress);
        let entry = ManifestEntry {
            settings: settings_table,
            model_sha256: r.model_sha256.clone(),
            ..entry
        };
        finish(k, r, entry);
    };
    let order = run_order(&selected);
    std::thread::scope(|scope| {
        for _ in 0..slots {
            scope.spawn(|| {
                while !interrupted() {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&k) = order.get(i) else { break };
                    work(k, &selected[k]);
                }
            });
        }
    });
    let mut m = manifest.into_inner().unwrap_or_default();
    // A run not started this time keeps what the manifest said of its recording before.
    for entry in m.runs.iter_mut().filter(|e| e.status == "pending") {
        if let Some(prev) = previous.runs.iter().find(|p| p.name == entry.name) {
            *entry = prev.clone();
        }
    }
    write_manifest(&manifest_path, &m)?;
    Ok(m)
}

/// Creates the output directory `out` and takes its lock: one campaign per output
/// directory at a time (the lock is released when the guard drops, or by the OS when the
/// process dies).
fn lock_output(
    campaign_path: &Path,
    out: &Path,
) -> Result<crate::record::output::WriterLock, CampaignError> {
    crate::input::ensure_dir(out).map_err(|source| CampaignError::Io {
        path: out.display().to_string(),
        source,
    })?;
    crate::record::output::lock(
        &out.join(CAMPAIGN_LOCK),
        &format!("campaign directory {}", out.display()),
    )
    .map_err(|e| CampaignError::File {
        file: campaign_path.display().to_string(),
        reason: e.to_string(),
    })
}

/// The manifest before any run starts: every selected run pending, with its recording's
/// name and its settings.
fn pending_manifest(campaign_path: &Path, selected: &[CampaignRun], out: &Path) -> Manifest {
    Manifest {
        campaign: campaign_path.display().to_string(),
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        runs: selected
            .iter()
            .map(|r| ManifestEntry {
                name: r.name.clone(),
                status: "pending".into(),
                recording: format!("{}.mcap", r.name),
                settings: recording_and_settings(r, out).1,
                ..Default::default()
            })
            .collect(),
    }
}

/// The order in which the runs are taken: file order, with the runs that start from
/// another run's points last, so that every run they wait for has started before them (no
/// slot waits on a run that has no slot).
fn run_order(selected: &[CampaignRun]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..selected.len()).collect();
    order.sort_by_key(|&k| {
        selected[k]
            .transient
            .as_ref()
            .is_some_and(|t| t.from.is_some())
    });
    order
}

/// Runs `r` ([`run_one`]) in a rayon pool of its own of `threads` threads (counted as
/// active in `tail` meanwhile), or on the calling thread when there is no such pool.
fn run_in_pool(
    threads: Option<usize>,
    tail: &Tail<'_>,
    r: &CampaignRun,
    rec_path: &Path,
    interrupt: Option<Arc<AtomicBool>>,
    progress: &(dyn Fn(Event<'_>) + Sync),
) -> ManifestEntry {
    let pool = threads.and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
    match pool {
        Some(pool) => {
            tail.active
                .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            let entry = pool.install(|| run_one(r, rec_path, interrupt, progress, tail));
            tail.active
                .fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
            entry
        }
        None => run_one(r, rec_path, interrupt, progress, &CurrentPool),
    }
}

/// The campaign's tail: once every run has started and only one is still running, that
/// run's steps go to a pool of all the workers instead of its own share of them, so the
/// cores the finished runs leave are not idle for the rest of it (on the paper campaign
/// the last run ran alone for about 24 s of 164 on one of two cores).
struct Tail<'a> {
    runs: usize,
    next: &'a std::sync::atomic::AtomicUsize,
    /// Runs executing now.
    active: std::sync::atomic::AtomicUsize,
    workers: usize,
    /// The pool of all workers, built when first needed (`None` if it could not be).
    wide: std::sync::OnceLock<Option<rayon::ThreadPool>>,
}

impl StepPools for Tail<'_> {
    fn for_next_step(&self) -> Option<&rayon::ThreadPool> {
        use std::sync::atomic::Ordering;
        let all_started = self.next.load(Ordering::SeqCst) >= self.runs;
        if !(all_started && self.active.load(Ordering::SeqCst) == 1) {
            return None;
        }
        self.wide
            .get_or_init(|| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(self.workers)
                    .build()
                    .ok()
            })
            .as_ref()
    }
}

/// Threads of each run's own rayon pool when the campaign's workers are shared out among
/// `slots` concurrent runs (`workers / slots`, at least one); `None`: one run at a time,
/// which uses the global pool.
fn run_pool(workers: usize, slots: usize) -> Option<usize> {
    (slots > 1).then(|| (workers / slots).max(1))
}

fn run_one(
    r: &CampaignRun,
    rec_path: &Path,
    interrupt: Option<Arc<AtomicBool>>,
    progress: &(dyn Fn(Event<'_>) + Sync),
    pools: &dyn StepPools,
) -> ManifestEntry {
    let start = std::time::Instant::now();
    let mut entry = ManifestEntry {
        name: r.name.clone(),
        recording: rec_path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or_default()
            .to_string(),
        ..Default::default()
    };
    if let Some(t) = &r.transient {
        run_transient_one(r, t, rec_path, interrupt, &mut entry);
        entry.seconds = start.elapsed().as_secs_f64();
        entry.sha256 = sha256_file(rec_path).unwrap_or_default();
        return entry;
    }
    let result = SweepProblem::new(&r.settings)
        .map_err(|e| e.to_string())
        .and_then(|problem| {
            let options = if r.lean {
                McapOptions::lean()
            } else {
                McapOptions::default()
            };
            let mut sink = McapSink::create(rec_path, options).map_err(|e| e.to_string())?;
            problem
                .run_in(
                    &mut sink,
                    interrupt,
                    |p| {
                        progress(Event::Point {
                            run: &r.name,
                            progress: p,
                        })
                    },
                    pools,
                )
                .map_err(|e| e.to_string())
        });
    entry.seconds = start.elapsed().as_secs_f64();
    match result {
        Ok(report) => {
            entry.time = report.time_summary();
            entry.points = report.points;
            entry.refused_steps = report.rejected_steps;
            entry.ended = report
                .finish
                .as_ref()
                .map(|f| f.to_string())
                .unwrap_or_default();
            entry.status = match report.status {
                crate::record::RunStatus::Completed => "completed".into(),
                crate::record::RunStatus::Interrupted => "interrupted".into(),
                ref other => format!("{other:?}").to_lowercase(),
            };
            // those that vanished at a higher truncation order are not results
            entry.bifurcations = report
                .checked_bifurcations()
                .filter(|(_, _, c)| c.is_none_or(|c| !c.verdict().vanished()))
                .map(|(w, k, c)| match c {
                    Some(c) => format!("{k} at {w:.3} rad/s; {}", c.verdict_text()),
                    None => format!("{k} at {w:.3} rad/s"),
                })
                .collect();
        }
        Err(e) => entry.status = format!("failed: {e}"),
    }
    // complete only once the recording reads back complete with every point
    if entry.status == "completed" {
        match crate::record::read_recording(rec_path) {
            Ok(rec) if rec.complete && rec.points.len() == entry.points => {}
            Ok(rec) => {
                entry.status = format!(
                    "failed: the recording read back holds {} of {} points{}",
                    rec.points.len(),
                    entry.points,
                    if rec.complete {
                        ""
                    } else {
                        " and is not complete"
                    }
                )
            }
            Err(e) => entry.status = format!("failed: the recording does not read back: {e}"),
        }
    }
    entry.sha256 = sha256_file(rec_path).unwrap_or_default();
    entry
}

/// Runs transient run `r` into `rec_path`, filling `entry`: status, revolutions as
/// `points`, how it ended.
fn run_transient_one(
    r: &CampaignRun,
    t: &TransientRun,
    rec_path: &Path,
    interrupt: Option<Arc<AtomicBool>>,
    entry: &mut ManifestEntry,
) {
    let source = rec_path.with_file_name(format!("{}.mcap", t.from.as_deref().unwrap_or_default()));
    let result = t.start(r, &source).and_then(|(problem, start, speed)| {
        let settings = t.settings(speed)?;
        let mut sink =
            McapSink::create(rec_path, McapOptions::default()).map_err(|e| e.to_string())?;
        crate::transient::run_transient(
            &problem,
            &start,
            &settings,
            &mut sink,
            &mut |_| {},
            interrupt,
        )
        .map_err(|e| e.to_string())
    });
    match result {
        Ok(report) => {
            entry.points = report.revolutions as usize;
            entry.status = if report.interrupted {
                "interrupted".into()
            } else {
                "completed".into()
            };
            entry.ended = format!(
                "{:.4} s simulated in {:.1} s ({:.3} simulated s per wall s){}",
                report.simulated_s,
                report.wall_s,
                report.speed(),
                report.last.as_ref().map_or(String::new(), |l| format!(
                    ", ω {:.3} rad/s at the end",
                    l.omega_rad_s
                ))
            );
            entry.time = format!(
                "{} steps ({} rejected), {} thermal steps",
                report.stats.accepted, report.stats.rejected, report.stats.thermal_steps
            );
        }
        Err(e) => entry.status = format!("failed: {e}"),
    }
}

/// Joins shard manifests (`manifest-shard-*-of-*.toml` in `dir`) into `manifest.toml`,
/// in run-name order; a run present in several shards keeps the completed entry.
pub fn merge_manifests(dir: &Path) -> Result<Manifest, CampaignError> {
    let rd = std::fs::read_dir(dir).map_err(|source| CampaignError::Io {
        path: dir.display().to_string(),
        source,
    })?;
    let mut merged = Manifest::default();
    let mut found = 0;
    for entry in rd.flatten() {
        let name = entry.file_name().to_string_lossy().to_string();
        if !(name.starts_with("manifest-shard-") && name.ends_with(".toml")) {
            continue;
        }
        let m = parse_manifest(&entry.path())?;
        found += 1;
        merged.campaign = m.campaign.clone();
        merged.tool_version = m.tool_version.clone();
        for run in m.runs {
            match merged.runs.iter_mut().find(|e| e.name == run.name) {
                Some(e) if e.status != "completed" => *e = run,
                Some(_) => {}
                None => merged.runs.push(run),
            }
        }
    }
    if found == 0 {
        return Err(CampaignError::File {
            file: dir.display().to_string(),
            reason: "no manifest-shard-*-of-*.toml files".into(),
        });
    }
    merged.runs.sort_by(|a, b| a.name.cmp(&b.name));
    write_manifest(&dir.join("manifest.toml"), &merged)?;
    Ok(merged)
}

/// Reads `path` as a campaign manifest; errors name the file.
pub fn read_manifest_file(path: &Path) -> Result<Manifest, CampaignError> {
    let file = path.display().to_string();
    let manifest = parse_manifest(path)?;
    if manifest.runs.is_empty() {
        return Err(CampaignError::File {
            file,
            reason: "the manifest lists no runs".into(),
        });
    }
    Ok(manifest)
}

#[cfg(test)]
mod tests {
    use super::{StepPools, Tail, run_pool};
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn only_the_last_running_run_gets_all_workers() {
        let next = AtomicUsize::new(1);
        let tail = Tail {
            runs: 3,
            next: &next,
            active: AtomicUsize::new(2),
            workers: 2,
            wide: std::sync::OnceLock::new(),
        };
        // runs still to start: every run keeps its share
        assert!(tail.for_next_step().is_none());
        tail.active.store(1, Ordering::SeqCst);
        assert!(tail.for_next_step().is_none());
        // all started, two running: still their shares
        next.store(3, Ordering::SeqCst);
        tail.active.store(2, Ordering::SeqCst);
        assert!(tail.for_next_step().is_none());
        // all started (the counter runs past the end as slots look for more), one running
        next.store(5, Ordering::SeqCst);
        tail.active.store(1, Ordering::SeqCst);
        let wide = tail.for_next_step().expect("the pool of all workers");
        assert_eq!(wide.current_num_threads(), 2);
    }

    #[test]
    fn concurrent_runs_share_the_workers_out() {
        // one run at a time: the global pool
        assert_eq!(run_pool(2, 1), None);
        assert_eq!(run_pool(1, 1), None);
        // two runs on two cores: one thread each, never more threads than workers
        assert_eq!(run_pool(2, 2), Some(1));
        assert_eq!(run_pool(8, 3), Some(2));
        assert_eq!(run_pool(8, 2), Some(4));
    }
}
