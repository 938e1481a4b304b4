//! One continuation sweep of a coupled rotor model, from study settings to a recording.
//!
//! This is the driver behind `tmrotor sweep`: it takes the problem a study builds
//! ([`SweepProblem`], see [`crate::study`]: the coupled rotor, the basis, the run
//! description and the stability method), traces the branch with [`Continuation`] (Floquet
//! stability per point unless switched off: by default the exponential-split SIP product
//! [`ExpSip`] on a Craig–Bampton reduction of the rotor, see [`StabilityChoice`]), converts
//! every accepted point
//! and every located bifurcation into the recording's domain types and hands them to a
//! [`Sink`] as they come, so that an interrupted or failed sweep keeps what it computed.
//! Each accepted point's recorded quantities (orbits, temperatures, bearing loads,
//! clearances, thermal forces) come from [`crate::derive::point_record`], the same
//! derivation replay uses.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use thiserror::Error;

use crate::continuation::switch::{SwitchOptions, half_order_share, switch_at_period_doubling};
use crate::continuation::{
    BranchPoint, Continuation, ContinuationError, ContinuationOptions, DriveEnd, FinishReason,
    StepOutcome, Timings, crosses,
};
use crate::derive::{Stretch, period_doubled_stretches, point_half_order_share};
use crate::hb::HarmonicBalance;
use crate::record::types::{
    BifurcationRecord, BranchRecord, FloquetCounts, PointRecord, RunInfo, RunStatus,
};
use crate::record::{RecordError, Sink};
use crate::stability::{BifurcationKind, ExpSip, FloquetResult, StabilityError, StabilityMethod};

pub mod verify;
pub use crate::study::{
    DEFAULT_INTERVALS, FloquetSettings, HarmonicSettings, OperatingSettings, RECORD_SAMPLES,
    StabilityChoice, StudyError, StudySettings, SweepProblem, SweepSettings, stability_method,
};

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

/// Errors of a sweep.
#[derive(Debug, Error)]
pub enum SweepError {
    #[error(transparent)]
    Study(#[from] StudyError),
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
    /// While the branch's events are re-solved at higher truncation orders, after the
    /// branch ([`verify`]).
    pub verifying: bool,
    /// While a batch of period-doubled branches is followed (several at once, recorded
    /// when all are done): the branches recorded so far, how many the batch follows, and
    /// the run's period doublings (the most there can be).
    pub switching: Option<(usize, usize, usize)>,
}

/// What a finished sweep reports.
#[derive(Clone, Debug)]
pub struct SweepReport {
    /// Recorded points, those of followed branches included.
    pub points: usize,
    /// Located bifurcations (ω, label) of the run's own branch; those of the followed
    /// branches are in `branches`.
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
    /// [`crate::derive::PERIOD_DOUBLED_SHARE`]).
    pub period_doubled: Vec<Stretch>,
    /// The speed a lead-in continuation started from, when the start could not be solved
    /// from the linear response (see `SweepProblem::run`).
    pub lead_in_from: Option<f64>,
    /// Where the recorded continuation's time went (the lead-in not included).
    pub timings: Timings,
    /// Time spent deriving the recorded quantities of the points and writing them.
    pub record_seconds: f64,
    /// Recorded points flagged stable and unstable (points without a verdict in neither).
    pub stable_points: usize,
    pub unstable_points: usize,
    /// Warnings about the branch, also written to the recording's `/log`: changes of
    /// stability that could not be located, folds the multipliers do not confirm.
    pub warnings: Vec<String>,
    /// The period-doubled branches followed from the run's period doublings (see
    /// [`SweepSettings::switch_branches`]); their points are counted in `points`.
    pub branches: Vec<FollowedBranch>,
    /// The run's branch's located bifurcations (in the order of `bifurcations`) and its
    /// unlocated changes of stability re-solved at higher truncation orders
    /// ([`verify`], study key `verify`); empty when not checked.
    pub truncation: Vec<crate::record::TruncationCheck>,
    /// Wall time of that check, s.
    pub verify_seconds: f64,
}

/// What one step of the branch (from point `after_point` to the next) says beyond its
/// located bifurcations ([`audit_step`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepAudit {
    /// Per located bifurcation (in the order given): whether the multipliers confirm it
    /// (see `BifurcationRecord::confirmed`).
    pub confirmed: Vec<bool>,
    /// Warnings for the recording's `/log` and the summary.
    pub notes: Vec<String>,
}

/// The real fast multiplier nearest +1, for a warning.
fn nearest_real_to_one(f: &FloquetResult) -> Option<f64> {
    f.multipliers
        .iter()
        .filter(|m| m.im.abs() <= 0.05 * m.norm() && m.re > 0.0)
        .map(|m| m.re)
        .min_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))
}

/// Audits one step of the branch between points `after_point` (ω `omegas.0`, stability
/// `before`) and the next (ω `omegas.1`, `after`), with the bifurcations `located`
/// between them:
///
/// * a saddle-node is *confirmed* when the monodromy product's count of real multipliers
///   above +1 (without the fold-parity correction) changes across the step; a lone
///   unconfirmed fold gets a warning (the fold belongs to the truncated balance). A step
///   with two folds (a pair inside one step) cannot tell and counts as confirmed;
/// * a change of the number of multipliers outside the circle with nothing located gets
///   a warning with the reason: a real multiplier through +1 where the branch does not
///   fold (the balance and the product disagree), time scales not separated, a jump of
///   the count (a collision of real multipliers outside the circle), or a change of the
///   near-zero exponents' count by an odd number (an exponent that jumped: a pair
///   changes it by two, and a real exponent passes zero only at a fold).
pub fn audit_step(
    before: Option<&FloquetResult>,
    after: Option<&FloquetResult>,
    located: &[BifurcationKind],
    omegas: (f64, f64),
    after_point: u64,
) -> StepAudit {
    let between = format!(
        "between points {after_point} and {} (ω {:.4} → {:.4} rad/s)",
        after_point + 1,
        omegas.0,
        omegas.1
    );
    let folds = located
        .iter()
        .filter(|k| **k == BifurcationKind::SaddleNode)
        .count();
    let mut audit = StepAudit::default();
    for kind in located {
        let confirmed = match (kind, before, after) {
            (BifurcationKind::SaddleNode, Some(a), Some(b)) if folds == 1 => {
                crate::stability::confirms_fold(a, b)
            }
            _ => true,
        };
        if !confirmed && let (Some(a), Some(b)) = (before, after) {
            let show = |f: &FloquetResult| {
                nearest_real_to_one(f).map_or("none".to_string(), |m| format!("{m:.4}"))
            };
            audit.notes.push(format!(
                "saddle-node {between} not confirmed by the orbits' multipliers: no real multiplier of the monodromy product passes +1 there (the real one nearest +1 is {} before and {} after); the fold belongs to the truncated harmonic balance, whose real exponent is counted instead — where rolling elements lose contact, sampling the bearings makes such folds (--exact-contacts integrates the contacts exactly and decides); else check it with a higher truncation order",
                show(a),
                show(b)
            ));
        }
        audit.confirmed.push(confirmed);
    }
    let near_zero = |f: Option<&FloquetResult>| f.is_some_and(|f| f.near_zero.is_some());
    let exact = near_zero(before) && near_zero(after);
    if let (Some(a), Some(b)) = (before, after)
        && folds == 1
        && exact
        && a.real_above_one().abs_diff(b.real_above_one()) > 1
    {
        audit.notes.push(format!(
            "saddle-node {between}: the count of real exponents above zero of the coupled balance changes from {} to {}, not by one: a real exponent passes zero only where the branch folds (det J = 0), so the others entered as a complex pair crossing the imaginary axis (a Neimark–Sacker point) that split into two real ones, or at a second fold, within this one step — a smaller step (--ds-max) separates them",
            a.real_above_one(),
            b.real_above_one()
        ));
    } else if let (Some(a), Some(b)) = (before, after)
        && folds == 1
        && a.real_above_one().abs_diff(b.real_above_one()) > 1
    {
        audit.notes.push(format!(
            "saddle-node {between}: the count of real multipliers above +1 changes from {} to \
             {}, not by one: in the same step real multipliers outside the unit circle collide \
             into complex pairs (or pairs split), besides the one through +1",
            a.real_above_one(),
            b.real_above_one()
        ));
    }
    if let (Some(a), Some(b)) = (before, after)
        && located.is_empty()
        && a.unstable_count() != b.unstable_count()
    {
        let (slow_a, slow_b) = (a.slow_unstable_count(), b.slow_unstable_count());
        let reason = if exact && slow_a.abs_diff(slow_b) % 2 == 1 {
            format!(
                "the coupled exponents nearest zero with a positive real part changed from {} to {}, by an odd number, where the branch does not fold: a pair crossing the imaginary axis changes that count by two and a real exponent passes zero only at a fold (det J = 0), so an exponent jumped, across the axis or through the edge of the disk, not a Neimark–Sacker point (nothing to locate) — where rolling elements lose contact, sampling the bearings makes such jumps (--exact-contacts integrates the contacts exactly and decides)",
                slow_a, slow_b
            )
        } else if exact && slow_a != slow_b {
            format!(
                "the coupled exponents nearest zero changed from {} to {} with a positive real part, and the search could not follow a pair across the imaginary axis (a real exponent passes zero only at a fold, det J = 0, so the change is a pair's crossing, a Neimark–Sacker point, narrower than the step, a fold pair inside it, or a jump where rolling elements lose contact) — a smaller step (--ds-max) resolves the first two, --exact-contacts decides the last",
                slow_a, slow_b
            )
        } else if a.fold_parity_mismatch != b.fold_parity_mismatch {
            "a real multiplier of the monodromy product passes +1 where the branch does not fold: the truncated harmonic balance, whose real exponents pass zero only at folds, and the orbit's linearisation disagree here — where rolling elements lose contact, sampling the bearings moves folds (--exact-contacts integrates the contacts exactly and decides); else raise the truncation order"
                .to_string()
        } else if a.split_uncertain() || b.split_uncertain() {
            format!(
                "a fast multiplier near +1 is not separated from the slow thermal exponents (split ratio {:.2} and {:.2}): the slow/fast split cannot decide here",
                a.split_ratio().unwrap_or(0.0),
                b.split_ratio().unwrap_or(0.0)
            )
        } else {
            "the count changed by a jump, not a crossing: real multipliers outside the circle collided into a complex pair, or a pair split (nothing to locate)"
                .to_string()
        };
        audit.notes.push(format!(
            "stability changes {between} ({} → {} multipliers outside the unit circle) without a located bifurcation: {reason}",
            a.unstable_count(),
            b.unstable_count()
        ));
    }
    audit
}

impl SweepReport {
    /// The run's located bifurcations (ω, label) with their truncation check, when one
    /// was made ([`Self::truncation`]), in order.
    pub fn checked_bifurcations(
        &self,
    ) -> impl Iterator<Item = (f64, &str, Option<&crate::record::TruncationCheck>)> {
        let mut checks = self.truncation.iter().filter(|c| c.kind.is_some());
        self.bifurcations
            .iter()
            .map(move |(w, label)| (*w, label.as_str(), checks.next()))
    }

    /// Where the sweep's time went, one line (`corrector … s (… steps, … ms each),
    /// stability …, bifurcation location …, recording … s`), each part summed over its
    /// calls (see [`Timings`]); the stability part names the instruction set of the
    /// Floquet kernel ([`crate::stability::panel_kernel_isa`]), which sets its speed.
    pub fn time_summary(&self) -> String {
        self.time_summary_with(true)
    }

    /// [`Self::time_summary`], naming the Floquet product's kernel (its instruction set)
    /// only when `kernel` is set.
    pub fn time_summary_with(&self, kernel: bool) -> String {
        format!(
            "{}, recording {:.1} s",
            self.timings.summary(kernel),
            self.record_seconds
        )
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
        if let Err(e @ crate::stability::StabilityError::Setting { .. }) = &out
            && let Ok(mut g) = self.reason.lock()
        {
            *g = Some(e.to_string());
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

impl SweepProblem {
    /// The continuation this problem's sweep runs (settings' range, step limits, AFT
    /// samples and the model's static start guess), with `stability` per point or none.
    /// [`Self::run`] drives it into a sink; other drivers (the truncation study) step it
    /// themselves.
    pub fn continuation<'s>(
        &'s self,
        stability: Option<&'s dyn StabilityMethod>,
    ) -> Result<Continuation<'s>, SweepError> {
        let s = &self.settings;
        self.continuation_over(
            s.sweep.omega_start,
            s.sweep.omega_end,
            None,
            stability,
            s.sweep.max_points,
        )
    }

    /// A continuation from `from` to `to` with the study's settings, started from `guess`
    /// (default: the system's initial guess), of at most `max_points` points.
    pub fn continuation_over<'s>(
        &'s self,
        from: f64,
        to: f64,
        guess: Option<Vec<f64>>,
        stability: Option<&'s dyn StabilityMethod>,
        max_points: usize,
    ) -> Result<Continuation<'s>, SweepError> {
        self.continuation_within(from, to, None, guess, stability, max_points)
    }

    /// [`Self::continuation_over`] with the ω range the branch may cover (`bounds`, see
    /// [`ContinuationOptions::omega_bounds`]; default from `from` to `to`).
    pub fn continuation_within<'s>(
        &'s self,
        from: f64,
        to: f64,
        bounds: Option<(f64, f64)>,
        guess: Option<Vec<f64>>,
        stability: Option<&'s dyn StabilityMethod>,
        max_points: usize,
    ) -> Result<Continuation<'s>, SweepError> {
        let opts = self.continuation_options(from, to, bounds, guess, max_points);
        self.continuation_with(opts, stability)
    }

    /// The options [`Self::continuation_within`] follows the branch with.
    pub fn continuation_options(
        &self,
        from: f64,
        to: f64,
        bounds: Option<(f64, f64)>,
        guess: Option<Vec<f64>>,
        max_points: usize,
    ) -> ContinuationOptions {
        let s = &self.settings;
        let mut opts = ContinuationOptions::new(from, to);
        opts.omega_bounds = bounds;
        opts.ds_max = s.sweep.ds_max;
        opts.ds_initial = opts.ds_initial.min(s.sweep.ds_max);
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
        opts
    }

    /// A continuation of this problem's balance with `opts` (see
    /// [`Self::continuation_options`]) and `stability`.
    pub fn continuation_with<'s>(
        &'s self,
        opts: ContinuationOptions,
        stability: Option<&'s dyn StabilityMethod>,
    ) -> Result<Continuation<'s>, SweepError> {
        let hb = HarmonicBalance::new(
            &self.system,
            &self.basis,
            self.settings.harmonic.aft_samples,
        )?;
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
        let up = s.sweep.omega_end >= s.sweep.omega_start;
        let mut tried = Vec::new();
        for frac in LEAD_IN_FRACTIONS {
            let from = if up {
                s.sweep.omega_start * frac
            } else {
                s.sweep.omega_start / frac
            };
            match self.lead_in_from(from, interrupted, at, pools)? {
                LeadIn::Failed(why) => tried.push(format!("from {from:.3} rad/s: {why}")),
                done => return Ok(done),
            }
        }
        Err(SweepError::LeadIn {
            omega: s.sweep.omega_start,
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
        let target = self.settings.sweep.omega_start;
        // not recorded: the sweep's own point budget does not apply
        let budget = StudySettings::default().sweep.max_points;
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
        let sip = GivingUp::new(if s.floquet.stability {
            stability_method(s, &self.system, s.sweep.omega_start)
        } else {
            Ok(Box::new(ExpSip::default()) as Box<dyn StabilityMethod>)
        });
        let stab: Option<&dyn StabilityMethod> = if s.floquet.stability {
            Some(&sip)
        } else {
            None
        };
        let cont = self.continuation(stab)?;

        sink.begin_run(&self.run)?;
        let interrupted = || {
            interrupt
                .as_ref()
                .is_some_and(|f| f.load(Ordering::Relaxed))
        };
        let mut run = Running {
            problem: self,
            stab,
            pools,
            interrupted: &interrupted,
            sink,
            progress: &mut progress,
            cont,
            rec: Recorder::new(&self.run),
            finish: None,
            lead_in_from: None,
            branches: Vec::new(),
            truncation: Vec::new(),
            verify_seconds: 0.0,
        };
        let result = run
            .own_branch()
            .and_then(|status| run.period_doubled_branches(status))
            .and_then(|status| run.truncation_check(status));
        run.report(result, start).map(|mut r| {
            r.stability_note = sip.reason();
            r
        })
    }

    /// Whether [`Self::run`] follows the period-doubled branches: `switch_branches` on a
    /// primary basis with stability on (see [`SweepSettings::switch_branches`]). The basis
    /// is primary when it holds no half orders: `half_orders = false`, or a single rotor
    /// (λ = 1), whose basis is the integer one either way.
    pub fn switches_branches(&self) -> bool {
        let s = &self.settings;
        s.sweep.switch_branches && self.primary() && s.floquet.stability
    }

    /// Whether the run's basis is primary: every harmonic a multiple of `ω/q` for the
    /// speed ratio `λ = p/q` (no half order a period doubling brings in).
    fn primary(&self) -> bool {
        let q = crate::study::speed_ratio(&self.model).den;
        self.basis
            .harmonics()
            .iter()
            .all(|h| (u64::from(h.num) * u64::from(q)) % u64::from(h.den) == 0)
    }

    /// Follows the period-doubled branch of every period doubling `rec` located on the
    /// run's branch, each recorded as a branch of its own (numbers 1, 2, … in the order of
    /// the period doublings): a start beside the period doubling on the doubled basis
    /// ([`switch_at_period_doubling`]), then a continuation with stability away from it
    /// over the sweep's range, until the half-order share falls below
    /// [`SwitchOptions::min_share`] (the branch has rejoined the run's branch, at another
    /// period doubling or the same), it leaves the range, or a continuation end. A period
    /// doubling where an earlier switched branch rejoined is not switched at again: its
    /// branch is that one. A period doubling without a start is reported as a warning.
    ///
    /// The branches are independent once the run's branch is done: as many as the pool
    /// has threads are followed at once ([`Self::follow_switched`]), then recorded one
    /// after the other in their order, so the recording is the same as one at a time
    /// gives. A branch whose period doubling an earlier one of the same batch rejoined at
    /// is followed but not recorded.
    fn follow_period_doublings(
        &self,
        rec: &mut Recorder,
        sink: &mut dyn Sink,
        stab: Option<&dyn StabilityMethod>,
        pools: &dyn StepPools,
        interrupted: &(dyn Fn() -> bool + Sync),
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Vec<FollowedBranch>, SweepError> {
        use rayon::prelude::*;
        let s = &self.settings;
        let switch = SwitchOptions {
            aft_samples: s.harmonic.aft_samples.map(|n| 2 * n),
            ..SwitchOptions::default()
        };
        let doublings = std::mem::take(&mut rec.period_doublings);
        let mut followed: Vec<FollowedBranch> = Vec::new();
        let rejoined_at = |followed: &[FollowedBranch], w: f64| {
            followed
                .iter()
                .any(|b| b.rejoined.is_some_and(|(a, z)| crosses(a, z, w)))
        };
        for batch in doublings.chunks(rayon::current_num_threads().max(1)) {
            if interrupted() {
                break;
            }
            let todo: Vec<&(u32, crate::hb::HbSolution)> = batch
                .iter()
                .filter(|(_, pd)| !rejoined_at(&followed, pd.omega))
                .collect();
            if todo.is_empty() {
                continue;
            }
            rec.prog.switching = Some((followed.len(), todo.len(), doublings.len()));
            progress(&rec.prog);
            let runs: Vec<Result<Result<SwitchedRun, String>, SweepError>> = todo
                .par_iter()
                .map(|(_, pd)| self.follow_switched(pd, &switch, stab, pools, interrupted))
                .collect();
            rec.prog.switching = None;
            let mut stopped = false;
            for (&(number, ref pd), run) in todo.into_iter().zip(runs) {
                // one at a time, this period doubling would not have been switched at
                // (an earlier branch rejoined there) or reached (the run was interrupted
                // during an earlier branch): what it gave is dropped
                if stopped || rejoined_at(&followed, pd.omega) {
                    continue;
                }
                match run? {
                    Ok(run) => {
                        stopped = matches!(run.end, BranchEnd::Interrupted);
                        let branch = followed.len() as u32 + 1;
                        followed.push(self.record_switched(
                            rec,
                            sink,
                            progress,
                            branch,
                            (number, pd),
                            run,
                        )?);
                    }
                    Err(e) => {
                        let note = format!(
                            "period doubling #{number} at ω = {:.4} rad/s: no period-doubled branch followed ({e})",
                            pd.omega
                        );
                        sink.write_note(rec.prog.points.saturating_sub(1) as u64, &note)?;
                        rec.warnings.push(note);
                    }
                }
            }
        }
        Ok(followed)
    }

    /// Records `run`, the branch followed from period doubling `number` at `pd`, as branch
    /// `branch`: its description, every step (points through `rec`, refused steps
    /// counted, `progress` after each), a note if it failed; what the summary lists of it.
    fn record_switched(
        &self,
        rec: &mut Recorder,
        sink: &mut dyn Sink,
        progress: &mut dyn FnMut(&Progress),
        branch: u32,
        (number, pd): (u32, &crate::hb::HbSolution),
        run: SwitchedRun,
    ) -> Result<FollowedBranch, SweepError> {
        let recording = std::time::Instant::now();
        let record = BranchRecord {
            branch,
            kind: "period_doubled".into(),
            parent: 0,
            origin_bifurcation: number,
            origin_omega_rad_s: pd.omega,
            harmonics: run.start.basis.harmonics().to_vec(),
        };
        sink.write_branch(&record)?;
        rec.begin_branch(branch, &record.run_of(&self.run));
        let first_index = rec.prog.points;
        for step in &run.steps {
            match step {
                StepOutcome::Accepted {
                    point,
                    bifurcations,
                } => rec.accept(self, sink, point, bifurcations)?,
                _ => rec.prog.rejected_steps += 1,
            }
            progress(&rec.prog);
        }
        if let BranchEnd::Failed(why) = &run.end {
            let note = format!("branch {branch}: {why}");
            sink.write_note(rec.prog.points.saturating_sub(1) as u64, &note)?;
            rec.warnings.push(note);
        }
        let followed = FollowedBranch {
            branch,
            origin_omega_rad_s: pd.omega,
            points: rec.prog.points - first_index,
            bifurcations: rec.branch_bifurcations.clone(),
            seconds: run.seconds + recording.elapsed().as_secs_f64(),
            switch_seconds: run.switch_seconds,
            timings: run.timings,
            omega_range: rec
                .branch_range
                .unwrap_or((run.start.omega, run.start.omega)),
            rejoined: match run.end {
                BranchEnd::Rejoined { between } => Some(between),
                _ => None,
            },
            end: run.end.to_string(),
        };
        rec.begin_branch(0, &self.run);
        Ok(followed)
    }

    /// Follows the period-doubled branch of the period doubling at `pd` (see
    /// [`Self::follow_period_doublings`]) without recording it: its start, the outcome of
    /// every step, how it ended; or why there is no start.
    fn follow_switched(
        &self,
        pd: &crate::hb::HbSolution,
        switch: &SwitchOptions,
        stab: Option<&dyn StabilityMethod>,
        pools: &dyn StepPools,
        interrupted: &(dyn Fn() -> bool + Sync),
    ) -> Result<Result<SwitchedRun, String>, SweepError> {
        let s = &self.settings;
        let (lo, hi) = (
            s.sweep.omega_start.min(s.sweep.omega_end),
            s.sweep.omega_start.max(s.sweep.omega_end),
        );
        let started = std::time::Instant::now();
        let start = match switch_at_period_doubling(&self.system, &self.basis, pd, switch) {
            Ok(start) => start,
            Err(e) => return Ok(Err(e.to_string())),
        };
        let to = if start.omega >= pd.omega { hi } else { lo };
        let hb = HarmonicBalance::new(&self.system, &start.basis, switch.aft_samples)?;
        let mut opts = ContinuationOptions::new(start.omega, to);
        opts.ds_max = s.sweep.ds_max;
        opts.ds_initial = opts.ds_initial.min(s.sweep.ds_max);
        opts.max_points = s.sweep.max_points;
        opts.initial_guess = Some(start.unknowns.clone());
        opts.omega_bounds = Some((lo, hi));
        opts.bifurcation_tol_arclength = BIFURCATION_TOL_ARCLENGTH;
        opts.bifurcation_tol_modulus = BIFURCATION_TOL_MODULUS;
        opts.bifurcation_tol_omega = BIFURCATION_TOL_OMEGA;
        let mut cont = Continuation::new(hb, opts, stab)?;
        let mut last_omega = start.omega;
        let switch_seconds = started.elapsed().as_secs_f64();
        let mut steps = Vec::new();
        let end = loop {
            if interrupted() {
                break BranchEnd::Interrupted;
            }
            match step_in(pools, &mut cont) {
                Ok(StepOutcome::Accepted {
                    point,
                    bifurcations,
                }) => {
                    let share =
                        half_order_share(&point.solution.unknowns(), &self.basis, &start.basis);
                    if share < switch.min_share {
                        break BranchEnd::Rejoined {
                            between: (last_omega, point.solution.omega),
                        };
                    }
                    last_omega = point.solution.omega;
                    steps.push(StepOutcome::Accepted {
                        point,
                        bifurcations,
                    });
                }
                Ok(rejected @ StepOutcome::Rejected(_)) => steps.push(rejected),
                Ok(StepOutcome::Finished(f)) => break BranchEnd::Finished(f),
                Err(e) => break BranchEnd::Failed(e.to_string()),
            }
        };
        Ok(Ok(SwitchedRun {
            start,
            steps,
            end,
            seconds: started.elapsed().as_secs_f64(),
            switch_seconds,
            timings: cont.timings(),
        }))
    }

    /// Converts one branch point into the recorded form, with bearing loads, clearances
    /// and thermal forces evaluated through the model over one period; `run` describes the
    /// points of the point's branch (the run's own, or [`BranchRecord::run_of`]).
    pub fn point_record(
        &self,
        run: &RunInfo,
        index: u64,
        p: &BranchPoint,
    ) -> Result<PointRecord, SweepError> {
        let mut rec =
            crate::derive::point_record(&self.system, run, index, &p.solution, RECORD_SAMPLES)
                .map_err(|e| SweepError::Derive(e.to_string()))?;
        rec.arc_length = p.arclength;
        rec.stable = p.stable();
        rec.bifurcation = p.bifurcation;
        if let Some(f) = &p.stability {
            rec.multipliers.clone_from(&f.multipliers);
            rec.slow_exponents.clone_from(&f.slow_exponents);
            rec.superseded.clone_from(&f.superseded);
            rec.floquet_counts = Some(FloquetCounts::of(f));
        }
        Ok(rec)
    }
}

/// A sweep's run as it goes (see [`SweepProblem::run_in`]): the problem and its stability
/// method, where the steps run, how the run is stopped, where its points are written and
/// its progress told, the continuation of the run's own branch, and what the run has
/// recorded and found so far.
struct Running<'s, 'a> {
    problem: &'s SweepProblem,
    stab: Option<&'s dyn StabilityMethod>,
    pools: &'a dyn StepPools,
    interrupted: &'a (dyn Fn() -> bool + Sync),
    sink: &'a mut dyn Sink,
    progress: &'a mut dyn FnMut(&Progress),
    cont: Continuation<'s>,
    rec: Recorder,
    finish: Option<FinishReason>,
    lead_in_from: Option<f64>,
    branches: Vec<FollowedBranch>,
    truncation: Vec<crate::record::TruncationCheck>,
    verify_seconds: f64,
}

impl Running<'_, '_> {
    /// Drives the run's own branch until it ends, is interrupted or fails, in the pool
    /// `pools` names (a drive pauses when that changes and goes on in the new one); a
    /// start that does not converge from the linear response is reached once by a lead-in
    /// ([`SweepProblem::lead_in`]).
    fn own_branch(&mut self) -> Result<RunStatus, SweepError> {
        let problem = self.problem;
        let s = &problem.settings;
        // the pool a drive runs in; a campaign's last run is moved to a wider one
        let same_pool = |a: Option<&rayon::ThreadPool>, b: Option<&rayon::ThreadPool>| match (a, b)
        {
            (Some(a), Some(b)) => std::ptr::eq(a, b),
            (None, None) => true,
            _ => false,
        };
        loop {
            if (self.interrupted)() {
                return Ok(RunStatus::Interrupted);
            }
            let pool = self.pools.for_next_step();
            let mut failure: Option<SweepError> = None;
            let mut observe = |out: StepOutcome| -> Result<(), SweepError> {
                match out {
                    StepOutcome::Accepted {
                        point,
                        bifurcations,
                    } => {
                        self.rec.accept(problem, self.sink, &point, &bifurcations)?;
                        self.rec.prog.fraction = ((point.solution.omega - s.sweep.omega_start)
                            / (s.sweep.omega_end - s.sweep.omega_start))
                            .clamp(0.0, 1.0);
                        (self.progress)(&self.rec.prog);
                    }
                    StepOutcome::Rejected(_) => {
                        self.rec.prog.rejected_steps += 1;
                        (self.progress)(&self.rec.prog);
                    }
                    StepOutcome::Finished(f) => self.finish = Some(f),
                }
                Ok(())
            };
            let mut observer = |out: StepOutcome| {
                if failure.is_none()
                    && let Err(e) = observe(out)
                {
                    failure = Some(e);
                }
                if failure.is_some()
                    || (self.interrupted)()
                    || !same_pool(self.pools.for_next_step(), pool)
                {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            };
            let end = self.cont.drive(pool, &mut observer);
            if let Some(e) = failure {
                return Err(e);
            }
            match end {
                Ok(DriveEnd::Finished(_)) => return Ok(RunStatus::Completed),
                // interrupted (checked above) or moved to another pool
                Ok(DriveEnd::Paused) => continue,
                Err(ContinuationError::Start { .. }) if self.lead_in_from.is_none() => {
                    // reach the start by continuation from where the response is milder
                    self.rec.prog.lead_in = true;
                    let mut at = |w: f64| {
                        self.rec.prog.omega_rad_s = w;
                        (self.progress)(&self.rec.prog);
                    };
                    let found = problem.lead_in(self.interrupted, &mut at, self.pools)?;
                    self.rec.prog.lead_in = false;
                    let (from, guess) = match found {
                        LeadIn::Reached { from, coeffs } => (from, coeffs),
                        // (`lead_in` hands out only a reached start or an interruption)
                        _ => return Ok(RunStatus::Interrupted),
                    };
                    self.lead_in_from = Some(from);
                    self.cont = problem.continuation_over(
                        s.sweep.omega_start,
                        s.sweep.omega_end,
                        Some(guess),
                        self.stab,
                        s.sweep.max_points,
                    )?;
                }
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// After a completed run's own branch (`status`), follows the period-doubled branches
    /// when the run switches branches ([`SweepProblem::follow_period_doublings`]); the
    /// status is then interrupted when the run was by the end of that.
    fn period_doubled_branches(&mut self, status: RunStatus) -> Result<RunStatus, SweepError> {
        if status != RunStatus::Completed || !self.problem.switches_branches() {
            return Ok(status);
        }
        self.branches = self.problem.follow_period_doublings(
            &mut self.rec,
            self.sink,
            self.stab,
            self.pools,
            self.interrupted,
            self.progress,
        )?;
        Ok(if (self.interrupted)() {
            RunStatus::Interrupted
        } else {
            status
        })
    }

    /// After a completed run (`status`), re-solves the run's branch's events at higher
    /// truncation orders ([`verify::verify_events`]) when the study asks for it (`verify`
    /// with stability) and there are events, writing each check to the sink (before the
    /// end status) and timing the whole; the status is then interrupted when the run was
    /// by the end of that.
    fn truncation_check(&mut self, status: RunStatus) -> Result<RunStatus, SweepError> {
        let s = &self.problem.settings;
        if status != RunStatus::Completed
            || !(s.floquet.verify && s.floquet.stability)
            || self.rec.events.is_empty()
        {
            return Ok(status);
        }
        let t0 = std::time::Instant::now();
        self.rec.prog.verifying = true;
        (self.progress)(&self.rec.prog);
        let points: Vec<verify::StartPoint> = self
            .rec
            .starts
            .iter()
            .map(|(index, w, m, t)| verify::StartPoint {
                index: *index,
                omega_rad_s: *w,
                coeffs_mech: m,
                coeffs_therm: t,
            })
            .collect();
        let options = verify::VerifyOptions::for_settings(s);
        let checks = verify::verify_events(
            s,
            &self.problem.model,
            Some(&self.problem.basis),
            &points,
            &self.rec.events,
            &options,
            |_| {},
            self.interrupted,
        )?;
        for c in &checks {
            self.sink.write_truncation_check(c)?;
        }
        self.truncation = checks;
        self.verify_seconds = t0.elapsed().as_secs_f64();
        self.rec.prog.verifying = false;
        Ok(if (self.interrupted)() {
            RunStatus::Interrupted
        } else {
            status
        })
    }

    /// Ends the recording with the run's status (`result`; a failure ends it as failed)
    /// and reports what the run found, its wall time counted from `start`.
    fn report(
        self,
        result: Result<RunStatus, SweepError>,
        start: std::time::Instant,
    ) -> Result<SweepReport, SweepError> {
        let rec = self.rec;
        match result {
            Ok(status) => {
                self.sink.finish(status.clone())?;
                Ok(SweepReport {
                    points: rec.prog.points,
                    bifurcations: rec.bifurcations,
                    status,
                    finish: self.finish,
                    total_seconds: start.elapsed().as_secs_f64(),
                    stability_note: None,
                    rejected_steps: rec.prog.rejected_steps,
                    period_doubled: period_doubled_stretches(rec.shares),
                    lead_in_from: self.lead_in_from,
                    timings: self.cont.timings(),
                    record_seconds: rec.record_seconds,
                    stable_points: rec.stable_points,
                    unstable_points: rec.unstable_points,
                    warnings: rec.warnings,
                    branches: self.branches,
                    truncation: self.truncation,
                    verify_seconds: self.verify_seconds,
                })
            }
            Err(e) => {
                let _ = self.sink.finish(RunStatus::Failed(e.to_string()));
                Err(e)
            }
        }
    }
}

/// A period-doubled branch a sweep followed (see `SweepProblem::run`).
#[derive(Clone, Debug, PartialEq)]
pub struct FollowedBranch {
    /// Its number in the recording (1, 2, …).
    pub branch: u32,
    /// ω of the period doubling it leaves from (rad/s).
    pub origin_omega_rad_s: f64,
    /// Recorded points.
    pub points: usize,
    /// Smallest and largest ω of its points (rad/s).
    pub omega_range: (f64, f64),
    /// Where it rejoined the run's branch: ω of its last point and of the first solution
    /// without a half-order part; a period doubling of the run's branch between the two
    /// is where it ends.
    pub rejoined: Option<(f64, f64)>,
    /// Its located bifurcations (ω, label), in branch order.
    pub bifurcations: Vec<(f64, String)>,
    /// Wall time of the branch in all, of its start (the switch), and where its
    /// continuation's time went.
    pub seconds: f64,
    pub switch_seconds: f64,
    pub timings: Timings,
    /// How it ended, in words.
    pub end: String,
}

/// A period-doubled branch followed and not yet recorded
/// ([`SweepProblem::follow_switched`]): its start, the accepted and refused steps in
/// order, how it ended, its wall time (all, and of the start) and where its
/// continuation's time went.
struct SwitchedRun {
    start: crate::continuation::switch::SwitchedStart,
    steps: Vec<StepOutcome>,
    end: BranchEnd,
    seconds: f64,
    switch_seconds: f64,
    timings: Timings,
}

/// How the continuation of a switched branch ended.
enum BranchEnd {
    Rejoined { between: (f64, f64) },
    Finished(FinishReason),
    Failed(String),
    Interrupted,
}

impl std::fmt::Display for BranchEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Rejoined { between } => write!(
                f,
                "rejoined the run's branch between ω = {:.3} and {:.3} rad/s",
                between.0, between.1
            ),
            Self::Finished(r) => write!(f, "{r}"),
            Self::Failed(why) => write!(f, "stopped: {why}"),
            Self::Interrupted => write!(f, "interrupted"),
        }
    }
}

/// What a sweep has recorded so far, over all its branches: the point count (the next
/// point's index), the located bifurcations (numbered in one sequence), counts, warnings;
/// and for the branch being recorded its number, how its points are described, and the
/// previous point for the audit of the next step.
struct Recorder {
    prog: Progress,
    run: RunInfo,
    branch: u32,
    /// ω and stability of the branch's last recorded point.
    previous: Option<(f64, Option<FloquetResult>)>,
    /// ω range of the branch's points so far.
    branch_range: Option<(f64, f64)>,
    /// Located bifurcations (ω, label) of the run's own branch, and of the switched branch
    /// being recorded.
    bifurcations: Vec<(f64, String)>,
    branch_bifurcations: Vec<(f64, String)>,
    n_bif: u32,
    /// The run's own period doublings (number, solution there), for branch switching.
    period_doublings: Vec<(u32, crate::hb::HbSolution)>,
    /// (index, ω, ω/2 share) per point of the run's own branch.
    shares: Vec<(u64, f64, Option<f64>)>,
    record_seconds: f64,
    stable_points: usize,
    unstable_points: usize,
    warnings: Vec<String>,
    /// The run's branch's located bifurcations and unlocated changes of stability, for the
    /// truncation check.
    events: Vec<verify::Event>,
    /// The run's branch's points (index, ω, mechanical and thermal coefficients), where
    /// the truncation check's windows start.
    starts: Vec<(u64, f64, Vec<f64>, Vec<f64>)>,
}

impl Recorder {
    fn new(run: &RunInfo) -> Self {
        Self {
            prog: Progress::default(),
            run: run.clone(),
            branch: 0,
            previous: None,
            branch_range: None,
            bifurcations: Vec::new(),
            branch_bifurcations: Vec::new(),
            n_bif: 0,
            period_doublings: Vec::new(),
            shares: Vec::new(),
            record_seconds: 0.0,
            stable_points: 0,
            unstable_points: 0,
            warnings: Vec::new(),
            events: Vec::new(),
            starts: Vec::new(),
        }
    }

    /// Points from here on belong to branch `branch`, described by `run`.
    fn begin_branch(&mut self, branch: u32, run: &RunInfo) {
        self.branch = branch;
        self.run = run.clone();
        self.previous = None;
        self.branch_range = None;
        self.branch_bifurcations.clear();
    }

    /// The crossing pair of a located Neimark–Sacker point `b` and the modulation it
    /// starts, with the thermal share of its mode when the pair is one of the coupled
    /// exponents nearest zero (one more Hill solve, with the thermal capacities changed).
    fn modulation(
        &self,
        problem: &SweepProblem,
        b: &BranchPoint,
    ) -> Option<crate::stability::Modulation> {
        let f = b.stability.as_ref()?;
        let mut m = f.crossing_pair(crate::system::PeriodicOrbit::period(&b.solution))?;
        if let Some(l) = m.exponent {
            let basis = self.run.basis().unwrap_or_else(|_| problem.basis.clone());
            let options = crate::stability::HillOptions::default();
            m.thermal_share = HarmonicBalance::new(
                &problem.system,
                &basis,
                problem.settings.harmonic.aft_samples,
            )
            .ok()
            .and_then(|hb| {
                let want = hb.n_therm() + options.extra;
                crate::stability::HillPencil::new(&hb, &b.solution, None)
                    .and_then(|p| p.thermal_share(l, want, &options))
                    .ok()
            });
        }
        Some(m)
    }

    /// Records an accepted point and the bifurcations located on the step to it: the
    /// step's audit, each bifurcation, the point (carrying the first bifurcation's type).
    fn accept(
        &mut self,
        problem: &SweepProblem,
        sink: &mut dyn Sink,
        point: &BranchPoint,
        bifurcations: &[BranchPoint],
    ) -> Result<(), SweepError> {
        let after_point = self.prog.points.saturating_sub(1) as u64;
        let kinds: Vec<BifurcationKind> =
            bifurcations.iter().filter_map(|b| b.bifurcation).collect();
        let audit = match &self.previous {
            None => StepAudit::default(),
            Some((w, f)) => audit_step(
                f.as_ref(),
                point.stability.as_ref(),
                &kinds,
                (*w, point.solution.omega),
                after_point,
            ),
        };
        for ((b, kind), confirmed) in bifurcations
            .iter()
            .filter_map(|b| b.bifurcation.map(|k| (b, k)))
            .zip(audit.confirmed.iter().copied())
        {
            let rec = BifurcationRecord {
                branch: self.branch,
                // 0, 1, … (the schema's running number)
                number: self.n_bif,
                kind,
                omega_rad_s: b.solution.omega,
                arc_length: b.arclength,
                after_point,
                amplitude_rms_m: amplitudes(&self.run, &b.solution.mech),
                multipliers: b
                    .stability
                    .as_ref()
                    .map(|f| f.multipliers.clone())
                    .unwrap_or_default(),
                confirmed,
                modulation: (kind == BifurcationKind::NeimarkSacker)
                    .then(|| self.modulation(problem, b))
                    .flatten(),
                coeffs_mech: b.solution.mech.clone(),
                coeffs_therm: b.solution.therm.clone(),
            };
            sink.write_bifurcation(&rec)?;
            if self.branch == 0 {
                self.events.push(verify::Event {
                    number: self.n_bif,
                    kind: Some(kind),
                    omega_rad_s: b.solution.omega,
                    after_point,
                });
            }
            if self.branch == 0 && kind == BifurcationKind::PeriodDoubling {
                self.period_doublings.push((self.n_bif, b.solution.clone()));
            }
            self.n_bif += 1;
            let label = match rec.modulation {
                Some(m) => format!(
                    "{}{} (angle {:.3e} rad: a modulation of {:.4} s, {:.0} revolutions{})",
                    if m.thermo_mechanical() {
                        "thermo-mechanical "
                    } else {
                        ""
                    },
                    kind.label(),
                    m.angle_rad,
                    m.period_s,
                    m.period_s * b.solution.omega / std::f64::consts::TAU,
                    m.thermal_share
                        .map(|s| format!("; thermal share {s:.2}"))
                        .unwrap_or_default()
                ),
                None => kind.label().to_string(),
            };
            let located = (b.solution.omega, label);
            if self.branch == 0 {
                self.bifurcations.push(located);
            } else {
                self.branch_bifurcations.push(located);
            }
        }
        for note in audit.notes {
            sink.write_note(after_point, &note)?;
            self.warnings.push(note);
        }
        // a change of the stable flag with nothing located on the step: an end of an
        // unstable stretch the truncation check re-solves too
        if self.branch == 0
            && kinds.is_empty()
            && let Some((w, Some(before))) = &self.previous
            && let Some(after) = &point.stability
            && before.stable != after.stable
        {
            self.events.push(verify::Event {
                number: 0,
                kind: None,
                omega_rad_s: 0.5 * (w + point.solution.omega),
                after_point,
            });
        }
        self.previous = Some((point.solution.omega, point.stability.clone()));
        let recording = std::time::Instant::now();
        let mut rec = problem.point_record(&self.run, self.prog.points as u64, point)?;
        rec.branch = self.branch;
        // the point after located bifurcations carries the first one's type
        // (`/summary.bifurcation`, the `bifurcation` column of `replay branch`)
        if rec.bifurcation.is_none() {
            rec.bifurcation = kinds.first().copied();
        }
        if self.branch == 0 {
            self.starts.push((
                rec.index,
                rec.omega_rad_s,
                rec.coeffs_mech.clone(),
                rec.coeffs_therm.clone(),
            ));
            self.shares.push((
                rec.index,
                rec.omega_rad_s,
                point_half_order_share(&self.run, &rec),
            ));
        }
        sink.write_point(&rec)?;
        match rec.stable {
            Some(true) => self.stable_points += 1,
            Some(false) => self.unstable_points += 1,
            None => {}
        }
        self.record_seconds += recording.elapsed().as_secs_f64();
        let w = point.solution.omega;
        self.branch_range = Some(
            self.branch_range
                .map_or((w, w), |(a, z)| (a.min(w), z.max(w))),
        );
        self.prog.points += 1;
        self.prog.omega_rad_s = w;
        self.prog.bifurcations = self.n_bif as usize;
        Ok(())
    }
}

fn amplitudes(run: &RunInfo, mech: &[f64]) -> Vec<f64> {
    crate::derive::amplitude_rms(run, mech).unwrap_or_default()
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
            stable_points: 0,
            unstable_points: 0,
            warnings: Vec::new(),
            branches: Vec::new(),
            truncation: Vec::new(),
            verify_seconds: 0.0,
        }
    }

    fn floquet(reals: &[f64], odd_folds: bool) -> FloquetResult {
        FloquetResult::new(
            reals
                .iter()
                .map(|&r| num_complex::Complex64::new(r, 0.0))
                .collect(),
        )
        .with_branch_parity(odd_folds)
    }

    #[test]
    fn a_fold_the_product_crosses_with_it_is_confirmed_without_a_warning() {
        let (a, b) = (floquet(&[0.9, 0.2], false), floquet(&[1.2, 0.2], true));
        let audit = audit_step(
            Some(&a),
            Some(&b),
            &[BifurcationKind::SaddleNode],
            (1.0, 1.1),
            4,
        );
        assert_eq!(audit.confirmed, vec![true]);
        assert!(audit.notes.is_empty());
        // the count of real multipliers above +1 changes by one, the verdict with it
        assert_eq!((a.real_above_one(), b.real_above_one()), (0, 1));
    }

    #[test]
    fn a_fold_the_product_does_not_see_is_counted_by_parity_and_reported() {
        let (a, b) = (floquet(&[0.7, 0.2], false), floquet(&[0.77, 0.2], true));
        assert!(a.stable && !b.stable, "the middle segment is unstable");
        assert!(b.fold_parity_mismatch);
        let audit = audit_step(
            Some(&a),
            Some(&b),
            &[BifurcationKind::SaddleNode],
            (582.3286, 582.2960),
            30,
        );
        assert_eq!(audit.confirmed, vec![false]);
        assert_eq!(audit.notes.len(), 1);
        assert!(
            audit.notes[0].contains("not confirmed"),
            "{}",
            audit.notes[0]
        );
        assert!(audit.notes[0].contains("between points 30 and 31"));
    }

    #[test]
    fn a_fold_with_a_collision_in_its_step_says_so() {
        let a = floquet(&[1.02, 5.5, 2.0], true);
        let pair = [
            num_complex::Complex64::new(1.1, 0.8),
            num_complex::Complex64::new(1.1, -0.8),
        ];
        let b = FloquetResult::new(vec![
            pair[0],
            pair[1],
            num_complex::Complex64::new(0.92, 0.0),
        ])
        .with_branch_parity(false);
        assert_eq!((a.real_above_one(), b.real_above_one()), (3, 0));
        let audit = audit_step(
            Some(&a),
            Some(&b),
            &[BifurcationKind::SaddleNode],
            (562.9414, 562.9610),
            297,
        );
        assert_eq!(audit.confirmed, vec![true]);
        assert_eq!(audit.notes.len(), 1);
        assert!(audit.notes[0].contains("collide"), "{}", audit.notes[0]);
    }

    #[test]
    fn a_fold_pair_inside_one_step_is_not_judged() {
        let (a, b) = (floquet(&[0.7], false), floquet(&[0.7], false));
        let kinds = [BifurcationKind::SaddleNode, BifurcationKind::SaddleNode];
        let audit = audit_step(Some(&a), Some(&b), &kinds, (1.0, 1.1), 2);
        assert_eq!(audit.confirmed, vec![true, true]);
        assert!(audit.notes.is_empty());
    }

    #[test]
    fn a_change_of_stability_without_a_located_bifurcation_is_reported_with_its_reason() {
        // a real multiplier through +1 where the branch does not fold
        let (a, b) = (floquet(&[0.9], false), floquet(&[1.1], false));
        let audit = audit_step(Some(&a), Some(&b), &[], (694.0, 694.5), 7);
        assert_eq!(audit.notes.len(), 1);
        assert!(
            audit.notes[0].contains("does not fold"),
            "{}",
            audit.notes[0]
        );
        // a jump of the count: two real multipliers outside become a pair outside
        let c = FloquetResult::new(vec![
            num_complex::Complex64::new(1.1, 0.3),
            num_complex::Complex64::new(1.1, -0.3),
        ]);
        let d = floquet(&[1.3, 1.2], false);
        let e = floquet(&[0.5], false);
        assert!(
            audit_step(Some(&c), Some(&d), &[], (1.0, 1.1), 1)
                .notes
                .is_empty()
        );
        let jump = audit_step(Some(&c), Some(&e), &[], (1.0, 1.1), 1);
        assert!(jump.notes[0].contains("jump"), "{}", jump.notes[0]);
        // nothing changes: nothing to say
        assert!(
            audit_step(Some(&a), Some(&a), &[], (1.0, 1.1), 1)
                .notes
                .is_empty()
        );
    }

    #[test]
    fn an_odd_change_of_the_near_zero_exponents_is_reported_as_a_jump() {
        use num_complex::Complex64 as C;
        // the coupled exponents nearest zero of an orbit of period 0.05 s, with one fast
        // multiplier well inside the circle
        let at = |exponents: Vec<C>| {
            FloquetResult::new(vec![C::new(0.2, 0.0)]).with_near_zero(
                crate::stability::NearZero {
                    exponents,
                    radius: 30.0,
                    outer: 40.0,
                    thermal: 1,
                    steps: 0,
                },
                0.05,
            )
        };
        let thermal = C::new(-0.01, 0.0);
        // a real exponent above zero at one end, a stable pair at the other (as on the
        // literature model at 612.68 rad/s): a count changed by one, not a pair's crossing
        let a = at(vec![thermal, C::new(0.6, 0.0)]);
        let b = at(vec![thermal, C::new(-2.4, 21.0), C::new(-2.4, -21.0)]);
        assert_eq!((a.slow_unstable_count(), b.slow_unstable_count()), (1, 0));
        let leap = audit_step(Some(&a), Some(&b), &[], (613.58, 612.48), 290);
        assert_eq!(leap.notes.len(), 1, "{:?}", leap.notes);
        assert!(
            leap.notes[0].contains("by an odd number"),
            "{}",
            leap.notes[0]
        );
        assert!(leap.notes[0].contains("not a Neimark"), "{}", leap.notes[0]);
        // a pair that crossed unseen changes it by two: the reason stays a crossing's
        let c = at(vec![thermal, C::new(0.3, 5.0), C::new(0.3, -5.0)]);
        let pair = audit_step(Some(&c), Some(&b), &[], (1.0, 1.1), 1);
        assert_eq!(pair.notes.len(), 1, "{:?}", pair.notes);
        assert!(!pair.notes[0].contains("odd"), "{}", pair.notes[0]);
        assert!(
            pair.notes[0].contains("could not follow a pair"),
            "{}",
            pair.notes[0]
        );
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
