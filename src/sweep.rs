//! One continuation sweep of a coupled rotor model, from study settings to a recording.
//!
//! This is the driver behind `tmrotor sweep`: it builds the [`CoupledRotor`] from a model
//! file and the study parameters, traces the branch with [`Continuation`] (Floquet
//! stability per point unless switched off: by default the exponential-split SIP product
//! [`ExpSip`] on a Craig–Bampton reduction of the rotor, see [`StabilityChoice`]), converts
//! every accepted point
//! and every located bifurcation into the recording's domain types and hands them to a
//! [`Sink`] as they come, so that an interrupted or failed sweep keeps what it computed.
//!
//! Defaults (the paper's default study, section 5): q_l = 2 L/min, cooling and ambient
//! 25 °C, ω from 300 to 700 rad/s, truncation order 3 (paper Eq. 34 with λ = 6/5 from the
//! model's rotor speed ratios).

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::continuation::{
    BranchPoint, Continuation, ContinuationError, ContinuationOptions, DriveEnd, FinishReason,
    StepOutcome, Timings,
};
use crate::coupled::{CoupledError, CoupledRotor, CouplingOptions, StudyOverrides};
use crate::hb::{Basis, HarmonicBalance, Ratio};
use crate::model::{Dir, Model};
use crate::record::derive::{Stretch, period_doubled_stretches, point_half_order_share};
use crate::record::types::{
    BearingInfo, BearingLoad, BifurcationRecord, ClearanceVariation, DynamicNode, PointRecord,
    RunInfo, RunStatus, ThermalForces, ThermalNode,
};
use crate::record::{RecordError, Sink};
use crate::stability::{
    CraigBampton, ExpSip, IntervalMap, Reduced, ReductionSettings, Sip, StabilityError,
    StabilityMethod,
};

/// Samples per period used for the recorded orbits, bearing loads and temperature ranges.
pub const RECORD_SAMPLES: usize = 128;

/// Everything a sweep needs besides the model file. Every default is the paper's default
/// study (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StudySettings {
    /// Model file; `None` is the built-in dual rotor.
    pub model: Option<PathBuf>,
    /// Lubricant flow rate per bearing `q_l` (L/min).
    pub flow_l_min: f64,
    /// Lubricant cooling temperature `T_L∞` (°C).
    pub cooling_temp_c: f64,
    /// Ambient temperature `T_∞` (°C).
    pub ambient_temp_c: f64,
    /// Truncation order `k` of the basis (Eq. 34).
    pub order: u32,
    /// Sweep start and end (rad/s).
    pub omega_start: f64,
    pub omega_end: f64,
    /// Largest continuation step (scaled arclength; see [`ContinuationOptions`]).
    ///
    /// Default 0.15. Why: on the default study, 0.05, 0.10 and 0.15 give the same
    /// ω-turning points (to 0.1 rad/s, the 0.05 run adds one pair of tiny zigzags) and the
    /// same node-8 peaks (to 0.2 rad/s and 0.01 µm), with 958, 460 and 314 points; the
    /// step control shortens the step where the branch bends, so the cap mostly sets
    /// the spacing on the flat parts.
    pub ds_max: f64,
    /// Maximum number of points.
    pub max_points: usize,
    /// Solve the thermal network together with the vibration (two-way coupling).
    pub thermal: bool,
    /// Compute Floquet multipliers at every point (and locate the Neimark–Sacker and
    /// period-doubling points; saddle-nodes, the folds of the branch, are located either
    /// way).
    pub stability: bool,
    /// Floquet method (see [`StabilityChoice`]).
    pub stability_method: StabilityChoice,
    /// Intervals per period of the SIP product (Eq. 33), default 512. `exp-sip`: the fine
    /// product of the extrapolation (even), the start of the refinement near the unit
    /// circle (doubled up to 4096); the explicit `sip` method raises it automatically for
    /// stiff systems.
    pub sip_intervals: usize,
    /// Interval map of the `exp-sip` product: `exponential` (default) or `strang`, the
    /// map of earlier versions (see [`IntervalMap`]). Recordings whose embedded settings
    /// lack this field were made with `strang`, and are re-derived with it.
    pub interval_map: IntervalMap,
    /// Cut-off (rad/s) of the Craig–Bampton reduction the stability is computed on
    /// (interior modes of the rotor with its bearing DoFs held, up to this frequency);
    /// 0 computes on the full model.
    pub reduction_cutoff_rad_s: f64,
    /// AFT samples per period; `None` chooses from the basis.
    pub aft_samples: Option<usize>,
}

impl Default for StudySettings {
    fn default() -> Self {
        Self {
            model: None,
            flow_l_min: 2.0,
            cooling_temp_c: 25.0,
            ambient_temp_c: 25.0,
            order: 3,
            omega_start: 300.0,
            omega_end: 700.0,
            ds_max: 0.15,
            max_points: 2000,
            thermal: true,
            stability: true,
            stability_method: StabilityChoice::ExpSip,
            sip_intervals: DEFAULT_INTERVALS,
            interval_map: IntervalMap::Exponential,
            reduction_cutoff_rad_s: ReductionSettings::default().cutoff_rad_s,
            aft_samples: None,
        }
    }
}

/// How one lead-in continuation (see `SweepProblem::run`) ended.
enum LeadIn {
    /// At the sweep's start: the lead-in's start speed and the coefficients there.
    Reached {
        from: f64,
        coeffs: Vec<f64>,
    },
    /// Why this lead-in did not get there.
    Failed(String),
    Interrupted,
}

/// Start speeds of the lead-in continuation that reaches a sweep start inside a nonlinear
/// range, as fractions of the start speed (their inverses for a sweep down), tried in
/// order. Why: a response is closer to linear away from the resonance; 0.9 covers a start
/// just past a fold, 0.5 one in the middle of the paper's range (300–700 rad/s).
pub const LEAD_IN_FRACTIONS: [f64; 5] = [0.9, 0.8, 0.7, 0.6, 0.5];

/// Bracket tolerance (scaled arclength) of the crossing search that locates bifurcations
/// in a sweep.
pub const BIFURCATION_TOL_ARCLENGTH: f64 = 1e-4;

/// Crossing-multiplier modulus tolerance for locating bifurcations in a sweep: the search
/// stops when the crossing multiplier is within 1e-4 of the unit circle, below the
/// accuracy of the default product on the dual rotor (3e-3 on an unstable multiplier,
/// see [`ExpSip::default`]).
pub const BIFURCATION_TOL_MODULUS: f64 = 1e-4;

/// ω resolution (rad/s) of a located Neimark–Sacker or period-doubling point in a sweep:
/// the crossing search also stops once its bracket spans less than this in ω on a step
/// without a fold. Why: the points are reported to 1e-3 rad/s (`tmrotor sweep`'s summary)
/// and 1e-4 (`replay info`), and on refined products the crossing modulus is noisier
/// than the modulus tolerance (about 3e-4 from trial to trial on 4096 intervals on the
/// 20 L/min run), so that the searches there went on to the arclength tolerance, moving
/// the point by less than 1e-3 rad/s with each trial of 0.4 s.
pub const BIFURCATION_TOL_OMEGA: f64 = 1e-3;

/// Default SIP intervals per period of a sweep: [`ExpSip`]'s default, 512 extrapolated
/// with 256 and refined up to 4096 intervals near the unit circle (the reason, with the
/// measured errors, is on [`ExpSip::default`]).
pub const DEFAULT_INTERVALS: usize = 512;

/// Which Floquet method a sweep uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StabilityChoice {
    /// Exponential-split SIP ([`ExpSip`]): the orbit-mean state matrix taken exactly, the
    /// fluctuation through the exponential interval map; works for stiff finite-element
    /// models. Default.
    ExpSip,
    /// The paper's explicit SIP product ([`Sip`], Eq. 33), with the interval count raised
    /// until `Δ·ρ(B) ≤ 1`; refuses models that would need more than 200 000 intervals.
    Sip,
}

impl StabilityChoice {
    /// Name used in settings files and on the command line.
    pub fn label(self) -> &'static str {
        match self {
            Self::ExpSip => "exp-sip",
            Self::Sip => "sip",
        }
    }
}

/// The stability method of `settings` for `system`: the chosen product, on a
/// Craig–Bampton reduction built at `omega_ref` unless the cut-off is 0.
pub fn stability_method(
    settings: &StudySettings,
    system: &CoupledRotor,
    omega_ref: f64,
) -> Result<Box<dyn StabilityMethod>, StabilityError> {
    let exp = ExpSip {
        intervals: settings.sip_intervals,
        interval_map: settings.interval_map,
        ..ExpSip::default()
    };
    let sip = Sip {
        intervals: settings.sip_intervals,
        ..Sip::default()
    };
    if settings.reduction_cutoff_rad_s == 0.0 {
        return Ok(match settings.stability_method {
            StabilityChoice::ExpSip => Box::new(exp),
            StabilityChoice::Sip => Box::new(sip),
        });
    }
    let reduction = CraigBampton::new(
        system,
        omega_ref,
        ReductionSettings {
            cutoff_rad_s: settings.reduction_cutoff_rad_s,
            max_modes: usize::MAX,
        },
    )?;
    Ok(match settings.stability_method {
        StabilityChoice::ExpSip => Box::new(Reduced {
            reduction,
            method: exp,
        }),
        StabilityChoice::Sip => Box::new(Reduced {
            reduction,
            method: sip,
        }),
    })
}

/// Errors of a sweep.
#[derive(Debug, Error)]
pub enum SweepError {
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    #[error(transparent)]
    Coupled(#[from] CoupledError),
    #[error(transparent)]
    Basis(#[from] crate::hb::BasisError),
    #[error(transparent)]
    Hb(#[from] crate::hb::HbError),
    #[error(transparent)]
    Continuation(#[from] crate::continuation::ContinuationError),
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error("recorded quantity could not be derived: {0}")]
    Derive(String),
    #[error(
        "no start solution at ω = {omega} rad/s, neither from the linear response nor by \
         continuation from a lower speed ({tried}); start the sweep where the response is \
         nearly linear, e.g. below the resonances"
    )]
    LeadIn { omega: f64, tried: String },
    #[error("study setting {field} = {value}: {reason}")]
    Setting {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
}

/// Progress of a running sweep, reported after every step.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    pub points: usize,
    pub omega_rad_s: f64,
    pub bifurcations: usize,
    pub rejected_steps: usize,
    /// Fraction of the ω range covered so far (0–1; not monotone through folds).
    pub fraction: f64,
    /// While the start is reached by a lead-in continuation (see `SweepProblem::run`):
    /// `omega_rad_s` is the lead-in's current speed, and nothing is recorded yet.
    pub lead_in: bool,
}

/// What a finished sweep reports.
#[derive(Clone, Debug)]
pub struct SweepReport {
    pub points: usize,
    pub bifurcations: Vec<(f64, String)>,
    pub status: RunStatus,
    /// How the continuation ended, when it did (`None` when interrupted or failed).
    pub finish: Option<FinishReason>,
    pub total_seconds: f64,
    /// Why stability was not assessed, when it was switched off during the sweep.
    pub stability_note: Option<String>,
    /// Continuation steps refused and retried with half the step (a failed or laboured
    /// corrector, a sharp turn, a fold pair inside the step).
    pub rejected_steps: usize,
    /// Stretches of points whose response is period-doubled (an `ω/2` share of at least
    /// [`crate::record::derive::PERIOD_DOUBLED_SHARE`]).
    pub period_doubled: Vec<Stretch>,
    /// The speed a lead-in continuation started from, when the start could not be solved
    /// from the linear response (see `SweepProblem::run`).
    pub lead_in_from: Option<f64>,
    /// Where the recorded continuation's time went (the lead-in not included).
    pub timings: Timings,
    /// Time spent deriving the recorded quantities of the points and writing them.
    pub record_seconds: f64,
}

impl SweepReport {
    /// Where the sweep's time went, one line (`corrector … s (… steps, … ms each),
    /// stability …, bifurcation location …, recording … s`), each part summed over its
    /// calls (see [`Timings`]); the stability part names the instruction set of the
    /// Floquet kernel ([`crate::stability::panel_kernel_isa`]), which sets its speed.
    pub fn time_summary(&self) -> String {
        let t = &self.timings;
        let per = |secs: f64, n: usize| {
            if n > 0 {
                format!(", {:.0} ms each", 1e3 * secs / n as f64)
            } else {
                String::new()
            }
        };
        let mut line = format!(
            "corrector {:.1} s ({} steps{})",
            t.step_seconds,
            t.steps,
            per(t.step_seconds, t.steps)
        );
        if t.evaluations > 0 {
            line += &format!(
                ", stability {:.1} s ({} evaluations{}, beside the corrector, {} kernel)",
                t.stability_seconds,
                t.evaluations,
                per(t.stability_seconds, t.evaluations),
                crate::stability::panel_kernel_isa()
            );
        }
        if t.searches > 0 {
            line += &format!(
                ", bifurcation location {:.1} s ({} searches)",
                t.search_seconds, t.searches
            );
        }
        line + &format!(", recording {:.1} s", self.record_seconds)
    }
}

/// A stability method that stops trying after a *setting* error (a system too stiff for
/// the method is too stiff at every point): the first reason is kept for the report and
/// every later point is left unassessed at no cost, instead of failing the same way a
/// thousand times.
///
/// A method that could not be set up at all (e.g. a reduction of a model whose rotor is
/// free when its bearings are held) is reported the same way from the first point on.
struct GivingUp {
    inner: Option<Box<dyn StabilityMethod>>,
    reason: std::sync::Mutex<Option<String>>,
}

impl GivingUp {
    fn new(inner: Result<Box<dyn StabilityMethod>, StabilityError>) -> Self {
        match inner {
            Ok(m) => Self {
                inner: Some(m),
                reason: std::sync::Mutex::new(None),
            },
            Err(e) => Self {
                inner: None,
                reason: std::sync::Mutex::new(Some(e.to_string())),
            },
        }
    }

    fn reason(&self) -> Option<String> {
        self.reason.lock().ok().and_then(|r| r.clone())
    }
}

impl GivingUp {
    /// Runs `evaluate` with the inner method unless it has given up; a setting error
    /// makes it give up for the rest of the sweep.
    fn guarded(
        &self,
        evaluate: impl FnOnce(
            &dyn StabilityMethod,
        ) -> Result<
            crate::stability::FloquetResult,
            crate::stability::StabilityError,
        >,
    ) -> Result<crate::stability::FloquetResult, crate::stability::StabilityError> {
        if let Some(r) = self.reason() {
            return Err(crate::stability::StabilityError::Setting {
                field: "stability",
                value: "off".into(),
                reason: if r.is_empty() {
                    "disabled"
                } else {
                    "disabled earlier in this sweep"
                },
            });
        }
        let Some(inner) = self.inner.as_ref() else {
            return Err(crate::stability::StabilityError::Setting {
                field: "stability",
                value: "off".into(),
                reason: "the stability method could not be set up",
            });
        };
        let out = evaluate(inner.as_ref());
        if let Err(e @ crate::stability::StabilityError::Setting { .. }) = &out {
            if let Ok(mut g) = self.reason.lock() {
                *g = Some(e.to_string());
            }
        }
        out
    }
}

impl StabilityMethod for GivingUp {
    fn multipliers(
        &self,
        system: &dyn crate::system::System,
        orbit: &dyn crate::system::PeriodicOrbit,
    ) -> Result<crate::stability::FloquetResult, crate::stability::StabilityError> {
        self.guarded(|m| m.multipliers(system, orbit))
    }

    fn search_multipliers(
        &self,
        system: &dyn crate::system::System,
        orbit: &dyn crate::system::PeriodicOrbit,
        ends: [&crate::stability::FloquetResult; 2],
    ) -> Result<crate::stability::FloquetResult, crate::stability::StabilityError> {
        self.guarded(|m| m.search_multipliers(system, orbit, ends))
    }
}

/// Which rayon pool a sweep's next continuation step runs in (see
/// [`SweepProblem::run_in`]); asked before every step, so that a campaign can widen the
/// pool of its last running sweep once the others are done.
pub trait StepPools: Sync {
    /// The pool for the next step; `None`: the pool the sweep was called from.
    fn for_next_step(&self) -> Option<&rayon::ThreadPool>;
}

/// Every step in the pool the sweep was called from.
pub struct CurrentPool;

impl StepPools for CurrentPool {
    fn for_next_step(&self) -> Option<&rayon::ThreadPool> {
        None
    }
}

/// One continuation step in the pool `pools` names for it.
fn step_in(
    pools: &dyn StepPools,
    cont: &mut Continuation<'_>,
) -> Result<StepOutcome, ContinuationError> {
    match pools.for_next_step() {
        Some(pool) => pool.install(|| cont.step()),
        None => cont.step(),
    }
}

/// A built sweep problem: model, coupled system, basis and the run description.
pub struct SweepProblem {
    pub settings: StudySettings,
    pub model: Model,
    pub system: CoupledRotor,
    pub basis: Basis,
    pub run: RunInfo,
}

impl SweepProblem {
    /// Builds the problem from settings (reads the model file if one is given).
    pub fn new(settings: &StudySettings) -> Result<Self, SweepError> {
        let model = match &settings.model {
            Some(path) => Model::from_file(path)?,
            None => Model::builtin()?,
        };
        Self::with_model(settings, model)
    }

    /// Builds the problem for an already parsed model.
    pub fn with_model(settings: &StudySettings, model: Model) -> Result<Self, SweepError> {
        check_settings(settings)?;
        let study = StudyOverrides {
            flow_l_min: Some(settings.flow_l_min),
            cooling_temp_c: Some(settings.cooling_temp_c),
            ambient_temp_c: Some(settings.ambient_temp_c),
        };
        let system = CoupledRotor::new(
            &model,
            &study,
            CouplingOptions {
                thermal: settings.thermal,
                frozen_clearance: false,
            },
        )?;
        let lambda = speed_ratio(&model);
        let basis = if lambda == (Ratio { num: 1, den: 1 }) {
            Basis::integer(settings.order)?
        } else {
            Basis::paper(settings.order, lambda)?
        };
        let run = run_info(&model, &system, &basis, lambda, settings);
        Ok(Self {
            settings: settings.clone(),
            model,
            system,
            basis,
            run,
        })
    }

    /// The continuation this problem's sweep runs (settings' range, step limits, AFT
    /// samples and the model's static start guess), with `stability` per point or none.
    /// [`Self::run`] drives it into a sink; other drivers (the truncation study) step it
    /// themselves.
    pub fn continuation<'s>(
        &'s self,
        stability: Option<&'s dyn StabilityMethod>,
    ) -> Result<Continuation<'s>, SweepError> {
        let s = &self.settings;
        self.continuation_over(s.omega_start, s.omega_end, None, stability, s.max_points)
    }

    /// A continuation from `from` to `to` with the study's settings, started from `guess`
    /// (default: the system's initial guess), of at most `max_points` points.
    fn continuation_over<'s>(
        &'s self,
        from: f64,
        to: f64,
        guess: Option<Vec<f64>>,
        stability: Option<&'s dyn StabilityMethod>,
        max_points: usize,
    ) -> Result<Continuation<'s>, SweepError> {
        let s = &self.settings;
        let hb = HarmonicBalance::new(&self.system, &self.basis, s.aft_samples)?;
        let mut opts = ContinuationOptions::new(from, to);
        opts.ds_max = s.ds_max;
        opts.ds_initial = opts.ds_initial.min(s.ds_max);
        opts.max_points = max_points;
        opts.initial_guess =
            Some(guess.unwrap_or_else(|| self.system.initial_guess(self.basis.n_coeffs())));
        // The crossing search stops at a bracket of 1e-4 in scaled arclength (≈ 0.04 rad/s
        // on the default range), a crossing modulus within 1e-4 of the circle, or (on a
        // step without a fold) a bracket 1e-3 rad/s wide: finer cannot place a crossing
        // better than the multipliers' own accuracy, and each search step costs a Newton
        // solve plus a stability evaluation.
        opts.bifurcation_tol_arclength = BIFURCATION_TOL_ARCLENGTH;
        opts.bifurcation_tol_modulus = BIFURCATION_TOL_MODULUS;
        opts.bifurcation_tol_omega = BIFURCATION_TOL_OMEGA;
        Ok(Continuation::new(hb, opts, stability)?)
    }

    /// The solution at the sweep's start reached by continuation, for a start whose Newton
    /// solve from the system's initial guess (the linear response) fails: that happens
    /// inside a strongly nonlinear range. The lead-in starts at [`LEAD_IN_FRACTIONS`] of
    /// the start speed on the side away from the sweep (below it for a sweep up), tried in
    /// order, and follows the branch to the start speed without stability or recording;
    /// a lead-in whose own start does not converge, or whose branch turns back out of its
    /// range or stops, gives way to the next. `at` hears the lead-in's speed after each
    /// point. Its steps run in the pools `pools` names, as the sweep's do.
    fn lead_in(
        &self,
        interrupted: &dyn Fn() -> bool,
        at: &mut dyn FnMut(f64),
        pools: &dyn StepPools,
    ) -> Result<LeadIn, SweepError> {
        let s = &self.settings;
        let up = s.omega_end >= s.omega_start;
        let mut tried = Vec::new();
        for frac in LEAD_IN_FRACTIONS {
            let from = if up {
                s.omega_start * frac
            } else {
                s.omega_start / frac
            };
            match self.lead_in_from(from, interrupted, at, pools)? {
                LeadIn::Failed(why) => tried.push(format!("from {from:.3} rad/s: {why}")),
                done => return Ok(done),
            }
        }
        Err(SweepError::LeadIn {
            omega: s.omega_start,
            tried: tried.join("; "),
        })
    }

    /// One lead-in from `from` (see [`Self::lead_in`]).
    fn lead_in_from(
        &self,
        from: f64,
        interrupted: &dyn Fn() -> bool,
        at: &mut dyn FnMut(f64),
        pools: &dyn StepPools,
    ) -> Result<LeadIn, SweepError> {
        let target = self.settings.omega_start;
        // not recorded: the sweep's own point budget does not apply
        let budget = StudySettings::default().max_points;
        let mut cont = self.continuation_over(from, target, None, None, budget)?;
        let mut last = None;
        loop {
            if interrupted() {
                return Ok(LeadIn::Interrupted);
            }
            match step_in(pools, &mut cont) {
                Ok(StepOutcome::Accepted { point, .. }) => {
                    at(point.solution.omega);
                    last = Some(point);
                }
                Ok(StepOutcome::Rejected(_)) => {}
                Ok(StepOutcome::Finished(f)) => {
                    return Ok(match last.filter(|p| p.solution.omega == target) {
                        Some(p) => LeadIn::Reached {
                            from,
                            coeffs: p.solution.unknowns(),
                        },
                        None => LeadIn::Failed(format!("the branch {f} before reaching the start")),
                    });
                }
                Err(e @ ContinuationError::Start { .. }) => {
                    return Ok(LeadIn::Failed(e.to_string()));
                }
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// Runs the sweep, writing into `sink` as it goes, polling `interrupt` between steps
    /// and calling `progress` after every step.
    pub fn run(
        &self,
        sink: &mut dyn Sink,
        interrupt: Option<Arc<AtomicBool>>,
        progress: impl FnMut(&Progress),
    ) -> Result<SweepReport, SweepError> {
        self.run_in(sink, interrupt, progress, &CurrentPool)
    }

    /// [`Self::run`] with every continuation step (corrector, tangent, the previous
    /// point's stability beside it, bifurcation searches) run in the rayon pool that
    /// `pools` names at that step.
    pub fn run_in(
        &self,
        sink: &mut dyn Sink,
        interrupt: Option<Arc<AtomicBool>>,
        mut progress: impl FnMut(&Progress),
        pools: &dyn StepPools,
    ) -> Result<SweepReport, SweepError> {
        let start = std::time::Instant::now();
        let s = &self.settings;
        let sip = GivingUp::new(if s.stability {
            stability_method(s, &self.system, s.omega_start)
        } else {
            Ok(Box::new(ExpSip::default()) as Box<dyn StabilityMethod>)
        });
        let stab: Option<&dyn StabilityMethod> = if s.stability { Some(&sip) } else { None };
        let mut cont = self.continuation(stab)?;

        sink.begin_run(&self.run)?;
        let mut prog = Progress::default();
        let mut bifs = Vec::new();
        let mut n_bif = 0u32;
        let mut finish = None;
        let mut lead_in_from = None;
        let mut record_seconds = 0.0;
        // (index, ω, ω/2 share) per point, for the period-doubled stretches
        let mut shares = Vec::new();
        let interrupted = || {
            interrupt
                .as_ref()
                .is_some_and(|f| f.load(Ordering::Relaxed))
        };
        // the pool a drive runs in; a campaign's last run is moved to a wider one
        let same_pool = |a: Option<&rayon::ThreadPool>, b: Option<&rayon::ThreadPool>| match (a, b)
        {
            (Some(a), Some(b)) => std::ptr::eq(a, b),
            (None, None) => true,
            _ => false,
        };
        let result: Result<RunStatus, SweepError> = (|| loop {
            if interrupted() {
                return Ok(RunStatus::Interrupted);
            }
            let pool = pools.for_next_step();
            let mut failure: Option<SweepError> = None;
            let mut observe = |out: StepOutcome| -> Result<(), SweepError> {
                match out {
                    StepOutcome::Accepted {
                        point,
                        bifurcations,
                    } => {
                        for b in &bifurcations {
                            if let Some(kind) = b.bifurcation {
                                let rec = BifurcationRecord {
                                    // 0, 1, … (the schema's running number)
                                    number: n_bif,
                                    kind,
                                    omega_rad_s: b.solution.omega,
                                    arc_length: b.arclength,
                                    after_point: prog.points.saturating_sub(1) as u64,
                                    amplitude_rms_m: amplitudes(&self.run, &b.solution.mech),
                                    multipliers: b
                                        .stability
                                        .as_ref()
                                        .map(|f| f.multipliers.clone())
                                        .unwrap_or_default(),
                                };
                                sink.write_bifurcation(&rec)?;
                                n_bif += 1;
                                bifs.push((b.solution.omega, kind.label().to_string()));
                            }
                        }
                        let recording = std::time::Instant::now();
                        let rec = self.point_record(prog.points as u64, &point)?;
                        shares.push((
                            rec.index,
                            rec.omega_rad_s,
                            point_half_order_share(&self.run, &rec),
                        ));
                        sink.write_point(&rec)?;
                        record_seconds += recording.elapsed().as_secs_f64();
                        prog.points += 1;
                        prog.omega_rad_s = point.solution.omega;
                        prog.bifurcations = bifs.len();
                        prog.fraction = ((point.solution.omega - s.omega_start)
                            / (s.omega_end - s.omega_start))
                            .clamp(0.0, 1.0);
                        progress(&prog);
                    }
                    StepOutcome::Rejected(_) => {
                        prog.rejected_steps += 1;
                        progress(&prog);
                    }
                    StepOutcome::Finished(f) => finish = Some(f),
                }
                Ok(())
            };
            let mut observer = |out: StepOutcome| {
                if failure.is_none()
                    && let Err(e) = observe(out)
                {
                    failure = Some(e);
                }
                if failure.is_some() || interrupted() || !same_pool(pools.for_next_step(), pool) {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            };
            let end = cont.drive(pool, &mut observer);
            if let Some(e) = failure {
                return Err(e);
            }
            match end {
                Ok(DriveEnd::Finished(_)) => return Ok(RunStatus::Completed),
                // interrupted (checked above) or moved to another pool
                Ok(DriveEnd::Paused) => continue,
                Err(ContinuationError::Start { .. }) if lead_in_from.is_none() => {
                    // reach the start by continuation from where the response is milder
                    prog.lead_in = true;
                    let mut at = |w: f64| {
                        prog.omega_rad_s = w;
                        progress(&prog);
                    };
                    let found = self.lead_in(&interrupted, &mut at, pools)?;
                    prog.lead_in = false;
                    let (from, guess) = match found {
                        LeadIn::Reached { from, coeffs } => (from, coeffs),
                        // (`lead_in` hands out only a reached start or an interruption)
                        _ => return Ok(RunStatus::Interrupted),
                    };
                    lead_in_from = Some(from);
                    cont = self.continuation_over(
                        s.omega_start,
                        s.omega_end,
                        Some(guess),
                        stab,
                        s.max_points,
                    )?;
                }
                Err(e) => return Err(e.into()),
            }
        })();
        match result {
            Ok(status) => {
                sink.finish(status.clone())?;
                Ok(SweepReport {
                    points: prog.points,
                    bifurcations: bifs,
                    status,
                    finish,
                    total_seconds: start.elapsed().as_secs_f64(),
                    stability_note: None,
                    rejected_steps: prog.rejected_steps,
                    period_doubled: period_doubled_stretches(shares),
                    lead_in_from,
                    timings: cont.timings(),
                    record_seconds,
                })
            }
            Err(e) => {
                let _ = sink.finish(RunStatus::Failed(e.to_string()));
                Err(e)
            }
        }
        .map(|mut r| {
            r.stability_note = sip.reason();
            r
        })
    }

    /// Converts one branch point into the recorded form, with bearing loads, clearances
    /// and thermal forces evaluated through the model over one period.
    pub fn point_record(&self, index: u64, p: &BranchPoint) -> Result<PointRecord, SweepError> {
        let sol = &p.solution;
        let mut rec = crate::record::derive::point_from_coefficients(
            &self.run,
            index,
            sol.omega,
            sol.mech.clone(),
            sol.therm.clone(),
            RECORD_SAMPLES,
        )
        .map_err(|e| SweepError::Derive(e.to_string()))?;
        rec.arc_length = p.arclength;
        rec.stable = p.stable();
        rec.bifurcation = p.bifurcation;
        rec.residual_mech = sol.residual.mech;
        rec.residual_therm = sol.residual.therm;
        rec.newton_iterations = sol.iterations as u32;
        rec.multipliers = p
            .stability
            .as_ref()
            .map(|f| f.multipliers.clone())
            .unwrap_or_default();
        let derived = bearing_quantities(&self.system, sol, RECORD_SAMPLES);
        rec.bearing_loads = derived.loads;
        rec.clearances = derived.clearances;
        rec.thermal_forces = derived.thermal_forces;
        Ok(rec)
    }
}

/// Bearing loads, clearances and thermal forces over one period of a solution.
pub fn bearing_quantities(
    system: &CoupledRotor,
    sol: &crate::hb::HbSolution,
    samples: usize,
) -> crate::record::derive::RederivedBearings {
    use crate::system::PeriodicOrbit;
    let n = system.assembly().n_dof;
    let nt = sol.n_therm();
    let period = sol.period();
    let nb = system.bearing_ids().len();
    let mut loads = vec![
        BearingLoad {
            mean_n: 0.0,
            radial_n: Vec::with_capacity(samples),
        };
        nb
    ];
    let mut clear = vec![ClearanceVariation::default(); nb];
    let mut forces = vec![ThermalForces::default(); nb];
    let (mut x, mut v, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; nt]);
    let inv = 1.0 / samples as f64;
    for j in 0..samples {
        let time = period * j as f64 * inv;
        sol.state_at(time, &mut x, &mut v, &mut t);
        let states = system.bearing_states(sol.omega, time, &x, &t);
        for (k, st) in states.iter().enumerate() {
            loads[k].radial_n.push(st.fb_n);
            loads[k].mean_n += st.fb_n * inv;
            clear[k].delta_v_m += st.delta_v_m * inv;
            clear[k].ub_m += st.u_b_m * inv;
            clear[k].ui_m += st.u_i_m * inv;
            clear[k].uo_m += st.u_o_m * inv;
        }
        for (k, out) in system
            .thermal_outputs_from_states(sol.omega, &states, &t)
            .iter()
            .enumerate()
            .take(nb)
        {
            forces[k].bearing_w += out.f_bear_b_w * inv;
            forces[k].lubricant_w += out.f_lub_l_w * inv;
            forces[k].generation_w += out.q_g_w * inv;
            forces[k].dissipation_w += out.q_d_w * inv;
        }
    }
    let initial = system.initial_clearances_m();
    for (c, d0) in clear.iter_mut().zip(initial) {
        c.effective_m = d0 + c.delta_v_m;
    }
    crate::record::derive::RederivedBearings {
        loads,
        clearances: clear,
        thermal_forces: if system.network().is_some() {
            forces
        } else {
            Vec::new()
        },
    }
}

fn amplitudes(run: &RunInfo, mech: &[f64]) -> Vec<f64> {
    crate::record::derive::amplitude_rms(run, mech).unwrap_or_default()
}

fn check_settings(s: &StudySettings) -> Result<(), SweepError> {
    let bad = |field: &'static str, value: String, reason: &'static str| {
        Err(SweepError::Setting {
            field,
            value,
            reason,
        })
    };
    if !(s.omega_start.is_finite() && s.omega_start > 0.0) {
        return bad(
            "omega_start",
            s.omega_start.to_string(),
            "must be positive (rad/s)",
        );
    }
    if !(s.omega_end.is_finite() && s.omega_end > 0.0 && s.omega_end != s.omega_start) {
        return bad(
            "omega_end",
            s.omega_end.to_string(),
            "must be positive and differ from omega_start",
        );
    }
    if s.order == 0 || s.order > 12 {
        return bad("order", s.order.to_string(), "must be between 1 and 12");
    }
    if !(s.ds_max.is_finite() && s.ds_max > 0.0) {
        return bad("ds_max", s.ds_max.to_string(), "must be positive");
    }
    if s.max_points == 0 {
        return bad("max_points", "0".into(), "must be at least 1");
    }
    if !(s.reduction_cutoff_rad_s.is_finite() && s.reduction_cutoff_rad_s >= 0.0) {
        return bad(
            "reduction_cutoff_rad_s",
            s.reduction_cutoff_rad_s.to_string(),
            "must be 0 (full model) or a positive frequency in rad/s",
        );
    }
    if s.sip_intervals < 8 {
        return bad(
            "sip_intervals",
            s.sip_intervals.to_string(),
            "must be at least 8",
        );
    }
    if s.stability_method == StabilityChoice::ExpSip && s.sip_intervals % 2 != 0 {
        return bad(
            "sip_intervals",
            s.sip_intervals.to_string(),
            "must be even for exp-sip (its product is extrapolated from N and N/2 intervals)",
        );
    }
    Ok(())
}

/// λ: the speed ratio of the second rotor (1 for a single rotor). Ratios are rational by
/// model validation.
fn speed_ratio(model: &Model) -> Ratio {
    model
        .speed_ratios()
        .iter()
        .copied()
        .find(|r| *r != Ratio { num: 1, den: 1 })
        .unwrap_or(Ratio { num: 1, den: 1 })
}

/// Axial position of every node: cumulative element lengths along each rotor, later rotors
/// shifted so that an inter-shaft bearing's two nodes line up.
fn axial_positions(model: &Model) -> Vec<f64> {
    let ids = model.node_ids();
    let mut pos: Vec<Option<f64>> = vec![None; ids.len()];
    let idx = |id: u32| model.node_index(id);
    for rotor in &model.spec.rotors {
        let Some(&first) = rotor.nodes.first() else {
            continue;
        };
        // offset from an inter-shaft bearing to an already placed node
        let mut offset = 0.0;
        let mut local: std::collections::BTreeMap<u32, f64> = Default::default();
        local.insert(first, 0.0);
        // walk shafts repeatedly (elements may be listed in any order)
        for _ in 0..rotor.nodes.len() {
            for sh in &model.spec.shafts {
                if sh.nodes.len() != 2 {
                    continue;
                }
                let (a, b) = (sh.nodes[0], sh.nodes[1]);
                if let (Some(&pa), None) = (local.get(&a), local.get(&b)) {
                    local.insert(b, pa + sh.length_m);
                } else if let (None, Some(&pb)) = (local.get(&a), local.get(&b)) {
                    local.insert(a, pb - sh.length_m);
                }
            }
        }
        for b in &model.spec.bearings {
            if let Some(o) = b.outer_node {
                for (mine, other) in [(o, b.inner_node), (b.inner_node, o)] {
                    if let (Some(&lm), Some(io)) = (local.get(&mine), idx(other)) {
                        if let Some(po) = pos[io] {
                            offset = po - lm;
                        }
                    }
                }
            }
        }
        for (id, p) in local {
            if let Some(i) = idx(id) {
                pos[i] = Some(p + offset);
            }
        }
    }
    pos.into_iter().map(|p| p.unwrap_or(0.0)).collect()
}

fn run_info(
    model: &Model,
    system: &CoupledRotor,
    basis: &Basis,
    lambda: Ratio,
    settings: &StudySettings,
) -> RunInfo {
    let axial = axial_positions(model);
    let nodes = model
        .node_ids()
        .iter()
        .enumerate()
        .map(|(i, &id)| DynamicNode {
            id,
            name: format!("node {id}"),
            dof_x: model.dof(id, Dir::X).unwrap_or(0),
            dof_y: model.dof(id, Dir::Y).unwrap_or(0),
            axial_position_m: axial[i],
            rotor: model.spec.rotors[model.rotor_of(i)].id.clone(),
        })
        .collect();
    let thermal_nodes = system
        .network()
        .map(|net| {
            net.names()
                .iter()
                .enumerate()
                .map(|(p, name)| ThermalNode {
                    id: (p + 1) as u32,
                    name: name.clone(),
                    dof: p,
                })
                .collect()
        })
        .unwrap_or_default();
    let bearings = system
        .bearing_ids()
        .iter()
        .zip(system.initial_clearances_m())
        .map(|(name, d0)| BearingInfo {
            name: name.to_string(),
            initial_clearance_m: d0,
        })
        .collect();
    let settings_toml = toml::to_string(settings).unwrap_or_default();
    let mut kv = vec![
        ("flow_l_min".to_string(), settings.flow_l_min.to_string()),
        (
            "cooling_temp_c".to_string(),
            settings.cooling_temp_c.to_string(),
        ),
        (
            "ambient_temp_c".to_string(),
            settings.ambient_temp_c.to_string(),
        ),
        ("order".to_string(), settings.order.to_string()),
        ("omega_start".to_string(), settings.omega_start.to_string()),
        ("omega_end".to_string(), settings.omega_end.to_string()),
        ("thermal".to_string(), settings.thermal.to_string()),
        ("stability".to_string(), settings.stability.to_string()),
        (
            "stability_method".to_string(),
            settings.stability_method.label().to_string(),
        ),
        (
            "sip_intervals".to_string(),
            settings.sip_intervals.to_string(),
        ),
        (
            "interval_map".to_string(),
            settings.interval_map.label().to_string(),
        ),
        (
            "reduction_cutoff_rad_s".to_string(),
            settings.reduction_cutoff_rad_s.to_string(),
        ),
    ];
    kv.push((
        "model".to_string(),
        settings
            .model
            .as_ref()
            .map_or("built-in".to_string(), |p| p.display().to_string()),
    ));
    let model_text = match &settings.model {
        Some(path) => std::fs::read_to_string(path).unwrap_or_default(),
        None => crate::model::BUILTIN_TOML.to_string(),
    };
    RunInfo {
        tool_name: "tmrotor".to_string(),
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        model_name: model.spec.name.clone(),
        model_text,
        settings: kv,
        settings_toml,
        harmonics: basis.harmonics().to_vec(),
        lambda,
        n_mech: system.assembly().n_dof,
        n_therm: crate::system::System::n_therm(system),
        nodes,
        thermal_nodes,
        bearings,
    }
}

/// Re-derivation of bearing quantities and stability for `replay`, from a recording's
/// embedded model text and settings.
pub struct CoupledRederive {
    problem: SweepProblem,
}

impl CoupledRederive {
    /// Rebuilds the sweep problem from a recording's run description.
    pub fn from_run(run: &RunInfo) -> Result<Self, SweepError> {
        Self::from_run_with_intervals(run, None)
    }

    /// [`CoupledRederive::from_run`] with the SIP intervals of the stability method
    /// replaced (`sip_intervals`, checked like a study setting): to audit a recording's
    /// stability with a finer product.
    pub fn from_run_with_intervals(
        run: &RunInfo,
        sip_intervals: Option<usize>,
    ) -> Result<Self, SweepError> {
        let mut settings: StudySettings =
            toml::from_str(&run.settings_toml).map_err(|e| SweepError::Setting {
                field: "settings_toml",
                value: "(embedded)".into(),
                reason: if e.message().is_empty() {
                    "unreadable"
                } else {
                    "embedded settings are not readable by this version"
                },
            })?;
        // settings embedded before the interval map was a setting: Strang's map, the only
        // one then
        let has_map = run
            .settings_toml
            .parse::<toml::Table>()
            .is_ok_and(|t| t.contains_key("interval_map"));
        if !has_map {
            settings.interval_map = IntervalMap::Strang;
        }
        let model = Model::from_str(&run.model_text, &run.model_name)?;
        settings.model = None;
        if let Some(n) = sip_intervals {
            settings.sip_intervals = n;
        }
        Ok(Self {
            problem: SweepProblem::with_model(&settings, model)?,
        })
    }

    fn solution(&self, point: &PointRecord) -> crate::hb::HbSolution {
        crate::hb::HbSolution {
            omega: point.omega_rad_s,
            basis: self.problem.basis.clone(),
            mech: point.coeffs_mech.clone(),
            therm: point.coeffs_therm.clone(),
            residual: Default::default(),
            relative_residual: Default::default(),
            iterations: point.newton_iterations as usize,
        }
    }
}

impl crate::record::derive::ModelRederive for CoupledRederive {
    fn bearings(
        &self,
        point: &PointRecord,
        samples: usize,
    ) -> Result<crate::record::derive::RederivedBearings, crate::record::derive::DeriveError> {
        Ok(bearing_quantities(
            &self.problem.system,
            &self.solution(point),
            samples,
        ))
    }
}

impl crate::record::derive::StabilityRederive for CoupledRederive {
    fn multipliers(
        &self,
        point: &PointRecord,
    ) -> Result<Vec<Complex64>, crate::record::derive::DeriveError> {
        let s = &self.problem.settings;
        let derive_err =
            |e: StabilityError| crate::record::derive::DeriveError::Model(e.to_string());
        let method =
            stability_method(s, &self.problem.system, s.omega_start).map_err(derive_err)?;
        method
            .multipliers(&self.problem.system, &self.solution(point))
            .map(|f| f.multipliers)
            .map_err(derive_err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(timings: Timings) -> SweepReport {
        SweepReport {
            points: 3,
            bifurcations: Vec::new(),
            status: RunStatus::Completed,
            finish: None,
            total_seconds: 1.0,
            stability_note: None,
            rejected_steps: 0,
            period_doubled: Vec::new(),
            lead_in_from: None,
            timings,
            record_seconds: 0.25,
        }
    }

    #[test]
    fn the_time_summary_names_the_floquet_kernel_when_stability_ran() {
        let with = report(Timings {
            steps: 4,
            step_seconds: 0.08,
            evaluations: 3,
            stability_seconds: 0.09,
            searches: 0,
            search_seconds: 0.0,
        });
        let kernel = crate::stability::panel_kernel_isa();
        assert_eq!(
            with.time_summary(),
            format!(
                "corrector 0.1 s (4 steps, 20 ms each), stability 0.1 s (3 evaluations, 30 ms \
                 each, beside the corrector, {kernel} kernel), recording 0.2 s"
            )
        );
        // without stability there is no kernel to name
        let without = report(Timings {
            steps: 4,
            step_seconds: 0.08,
            ..Timings::default()
        });
        assert_eq!(
            without.time_summary(),
            "corrector 0.1 s (4 steps, 20 ms each), recording 0.2 s"
        );
    }
}
