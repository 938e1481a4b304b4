//! Pseudo-arclength continuation of harmonic-balance solutions in the continuation
//! parameter ω, with stability per point and located bifurcations.
//!
//! ## Method
//! Unknowns `X = (A, ω)` are measured in scaled units `u = A / s` (`s = s_mech` for
//! mechanical, `s_therm` for thermal coefficients, or one scale per DoF with
//! [`ContinuationOptions::scale_per_dof`]) and `ϖ = ω / s_ω`, so that
//! displacements, temperatures and speed weigh comparably in the arclength (see
//! [`ContinuationOptions`] for the scales). From an accepted point with unit tangent `τ`:
//!
//! * predictor `X + ds·τ + ds²/2·κ`, `κ` the change of the unit tangent per unit
//!   arclength over the step that reached `X` ([`ContinuationOptions::curved_predictor`];
//!   `X + ds·τ` at the start point), put back onto the step's hyperplane; a search
//!   inside a step (fold, Neimark–Sacker, period doubling) predicts on the cubic Hermite
//!   curve through the step's two points and tangents instead; corrector: damped Newton
//!   ([`crate::hb::newton`]) on
//!   `R(A, ω) = 0` plus `τ·(X − X_prev) = ds` (the bordered system stays regular at folds,
//!   so folds are passed and unstable parts traced). Its first iteration is Keller's: it
//!   solves with the matrix factored for the tangent at `X_prev`, whose border row is
//!   switched from the previous tangent to `τ` by a rank-one (Sherman–Morrison) update
//!   ([`crate::hb::Factorization::replace_border_row`]); the later ones are Newton's, each
//!   with the Jacobian its full-step trial computed along with the residual;
//! * new tangent from `[[∂R/∂A, ∂R/∂ω], [τ_prevᵀ]] t = [0; 1]`, normalised: this keeps the
//!   orientation (`τ_prev·t > 0`), i.e. direction control. The Jacobian at the point is
//!   the one the corrector's last trial computed with its residual, and `∂R/∂ω` a forward
//!   difference from that residual. When the corrector ended with chord iterations, the
//!   tangent system is solved by iterative refinement with their matrix (the Jacobian of
//!   an earlier iterate, bordered with `τ_prev`'s row): a product with the unassembled
//!   Jacobian and a solve per refinement step, no factorization; only when the
//!   refinement does not contract is the Jacobian at the point factored. The matrix the
//!   tangent was solved with is kept for the next step's Keller iteration;
//! * step control: `ds ← ds·clamp(sqrt(n_target / n_iter), 0.5, 2)` after success, halving
//!   after a failed corrector, a corrector that needed more than `max_step_iterations`
//!   iterations, a turn of the tangent by more than 60°, a corrected point
//!   farther than `max_corrector_distance · ds` from the predictor, or a step over which ω
//!   moved against the tangent at both ends (a fold pair inside one step, which the fold
//!   search between the two points could not see);
//! * the start point is Newton at `ω_start` from zero coefficients (its first iterate is the
//!   linear response) or from [`ContinuationOptions::initial_guess`]; its tangent is oriented towards `ω_end`;
//! * stops when ω leaves `[min(ω_start, ω_end), max(…)]` (the last point is re-solved on the
//!   bound), after `max_points`, when the step falls below `ds_min`, or when the branch
//!   comes back onto its own path: going the same way ([`closing_point`]: a closed curve
//!   would otherwise be traced round and round until `max_points`) or the other way
//!   ([`reversing_point`]: after a jump between sheets where they meet, the path would
//!   otherwise retrace itself backwards).
//!
//! With a [`StabilityMethod`], each point's Floquet multipliers are computed on its
//! [`HbSolution`]. The bifurcations between neighbouring points are located in arclength
//! (re-correcting from the earlier point at intermediate arclength) and emitted as
//! labelled points; the saddle-nodes need no multipliers and are located without a
//! stability method too. A point is handed out one step late: its stability evaluation,
//! and then the location of a change of stability between the point before it and it,
//! run beside the next step's corrector (`rayon::join`), so that both cores have work;
//! the search for a fold between the two, which needs no multipliers, follows the
//! corrector on its side (the corrector is usually done first):
//!
//! * **saddle-nodes at folds.** Where the ω-component of the tangent changes sign, the
//!   branch turns in ω; a real multiplier passes through +1 exactly there. The fold is
//!   located as the zero of that component (a test function needing a corrector and a
//!   tangent per search step, no multipliers) by safeguarded regula falsi (Illinois); the
//!   located point carries no multipliers (one of them is +1 there). Locating it by the multiplier
//!   instead would put it where the product resolves the crossing: near folds the crossing
//!   multiplier converges slowly with the intervals (see [`crate::stability::ExpSip`]), and
//!   on the dual rotor the multiplier-located points lagged the turning points by up to two
//!   points, and one fold was counted twice. A real multiplier that crosses +1 away from a
//!   fold (a branch point, not generic in one parameter, or that same lag) is left to the
//!   points' stable flags.
//! * **Neimark–Sacker and period doubling.** When the number of multipliers outside the
//!   unit circle differs between neighbours, each kind whose own count differs (complex
//!   pairs, negative real multipliers: [`BifurcationKind::of_multiplier`]) is located on
//!   the modulus of the crossing multiplier, by the secant of the last two trials while
//!   it converges and a safeguarded regula falsi otherwise (bisection when the bracket's
//!   ends lie on one side of the circle), until the bracket is shorter than
//!   `bifurcation_tol_arclength`, that modulus is within `bifurcation_tol_modulus` of
//!   the circle, or (on a step without a fold) the bracket spans less than
//!   `bifurcation_tol_omega` in ω. Counted per kind, a pair crossing in the
//!   same step as a real multiplier through +1 at a fold is not hidden by it; the crossing
//!   multiplier is ranked among the multipliers of its kind only, so that slow thermal
//!   multipliers just below +1 do not stand in for it. A search that does not bring it
//!   within `CROSSING_MODULUS_TOL` (0.02) of the circle found a jump of the count (a
//!   collision of two real multipliers into a pair), not a crossing, and reports
//!   nothing; it ends once its bracket is below `JUMP_BRACKET_FRACTION` of the step with
//!   the modulus that far from the circle, on one side, at both ends. The trials use the
//!   method's search evaluation ([`StabilityMethod::search_multipliers`]: for [`crate::stability::ExpSip`] the
//!   product on the intervals of the finer end, without further refinement), and the
//!   located point carries those multipliers.
//!
//! Solutions at given speeds (a truncation study at fixed ω, say): watch consecutive
//! accepted points with [`crosses`] and re-solve on the speed with
//! [`Continuation::solve_between`].
//!
//! The driver follows argmin's split: [`Continuation::step`] returns a [`StepOutcome`],
//! [`Continuation::run`] loops and calls an observer per outcome. [`Continuation::drive`]
//! hands the same outcomes to an observer from a pipeline in which the corrector does not
//! wait for the points' stability (see [`pipeline`]); the sweep uses it.

pub mod csv;
pub mod fold;
mod locate;
mod path;
pub mod pipeline;
pub mod switch;
mod tangent;

pub use path::{PathHistory, closing_point, reversing_point};

pub use pipeline::DriveEnd;

use std::sync::atomic::{AtomicU64, Ordering};

use thiserror::Error;

use crate::hb::newton::{self, ArcConstraint, NewtonError, NewtonOptions};
use crate::hb::{
    Factorization, HarmonicBalance, HbError, HbSolution, JacobianParts, LinearSolver, SolveError,
    condense::{Border, dot},
};
use crate::stability::{BifurcationKind, FloquetResult, StabilityMethod, UNIT_CIRCLE_TOL};

/// A fold is located until the ω-component of the unit tangent is this fraction of its
/// larger value at the two points around it: near a fold `ω(σ) ≈ ω_f − κ(σ − σ_f)²/2`,
/// so the located ω is then off by about `(1e-2)² = 1e-4` of the ω change between the
/// fold and the farther of the two points.
const FOLD_SLOPE_TOL: f64 = 1e-2;

/// A step is taken to hold a fold pair (see [`RejectReason::FoldPair`]) only when ω moved
/// against both tangents by more than this fraction of the step (scaled units), so that
/// rounding on a branch that runs at constant ω cannot halve the step away.
const FOLD_PAIR_MIN_CHANGE: f64 = 1e-6;

/// A located Neimark–Sacker or period-doubling point is reported only when the search
/// brought the crossing multiplier this close to the unit circle. A count of one kind
/// can also change by a jump: where a real pair collides into a complex one (or the
/// reverse) next to a fold, the multipliers of that kind appear or vanish with a modulus
/// far from 1, and the search then closes in on the jump, not on a crossing. On the
/// default sweep (step caps 0.15 and 0.25) the ten crossings end within 3.3e-4 of the
/// circle and the one jump (589.5 rad/s, at a fold) no closer than 0.10.
const CROSSING_MODULUS_TOL: f64 = 0.02;

/// A crossing search ends as a jump of the count (see [`CROSSING_MODULUS_TOL`]) once its
/// bracket is narrower than this fraction of the step and the crossing multiplier's
/// modulus lies on the same side of the circle at both ends, farther from it than
/// `CROSSING_MODULUS_TOL`: a continuous crossing would have a zero of the modulus
/// difference between them. Six halvings: the count's change is then placed within
/// 1/64 of the step, and the searches that closed in further (on the 1 L/min study up
/// to 15 trials) found no trial nearer the circle.
const JUMP_BRACKET_FRACTION: f64 = 1.0 / 64.0;

/// Trials without coming nearer the circle after which a search whose bracket straddles
/// the circle, and has narrowed as in [`JUMP_BRACKET_FRACTION`], ends as a jump. Why: on
/// the default sweep the Neimark–Sacker count changes at 589.52 rad/s, next to a fold,
/// where a pair at modulus 1.11 turns into two real multipliers, one at 0.58; the search
/// alternated between the two sides at 0.10–0.16 and −0.42 from the circle for eleven
/// trials (0.38 s) and reported nothing. Two trials: on continuous crossings the secant
/// and regula falsi trials come nearer within two (the model functions of the unit tests
/// below, slopes up to 500; the paper campaign's six runs locate the same bifurcations
/// with and without the rule).
const JUMP_STALLED_TRIALS: usize = 2;

/// A crossing search's trial stalled when it lands on one end's side no nearer the circle
/// than this fraction of that end's distance (and farther than [`CROSSING_MODULUS_TOL`]);
/// the next trial is then the bracket's midpoint. Where the count changes by a jump the
/// regula falsi trials land again and again on the side whose modulus is nearer the
/// circle, at a value that does not move (on the switched branches of W5, e.g. −0.4903 at
/// five trials in a row against +4.59 at the other end): the bracket shrank by a tenth a
/// trial, and jumps took 2–22 trials (8.6 on average) to reach
/// [`JUMP_BRACKET_FRACTION`]; halving reaches it in six. A smooth crossing's regula falsi
/// trials come nearer by far more than a tenth of the end's distance, and 27 of that
/// run's 36 smooth crossings had no stalled trial.
const STALL_RATIO: f64 = 0.9;

/// Smallest distance of a secant trial from the bracket's ends, as a fraction of its
/// width ([`Bracket::secant_trial`]): the latest trial is usually an end, and once it is
/// nearly there the zero lies next to it (on the default sweep's period doubling at
/// 617.19 rad/s, 1.2e-5 of a bracket 0.034 wide).
const SECANT_MARGIN: f64 = 1e-6;

/// The two ends' stabilities when the number of unstable multipliers differs between
/// them: each kind whose count outside the circle changed is then searched, when the total
/// changed too (a pair outside that turns into two real multipliers outside changes the
/// kinds' counts, not the stability); a real multiplier through +1 is the fold's.
fn stability_changes(ends: [Option<&FloquetResult>; 2]) -> Option<[&FloquetResult; 2]> {
    match ends {
        [Some(fa), Some(fb)] if fa.unstable_count() != fb.unstable_count() => Some([fa, fb]),
        _ => None,
    }
}

/// Whether the tangent's ω-component changes sign between `from` and `to` (a fold).
fn folds_between(from: &Current, to: &Current, nu: usize) -> bool {
    from.tangent[nu] * to.tangent[nu] < 0.0
}

/// The bifurcations located between two points, the fold's first, in arclength order
/// (a stable sort: a fold and a crossing at the same arclength keep that order).
fn merged_changes(
    crossings: Vec<BranchPoint>,
    fold: impl IntoIterator<Item = BranchPoint>,
) -> Vec<BranchPoint> {
    let mut found: Vec<BranchPoint> = fold.into_iter().chain(crossings).collect();
    found.sort_by(|a, b| a.arclength.total_cmp(&b.arclength));
    found
}

/// What a crossing search follows: the counted multipliers of one kind, or the
/// exponents of the near-zero disk whatever their kind (the largest real part among them
/// is continuous where two real exponents collide into a complex pair, so a pair that
/// forms outside and crosses within one step is found; a real one crosses zero only at a
/// fold, which the tangent locates).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Family {
    Kind(BifurcationKind),
    NearZero,
}

impl Family {
    fn holds(self, c: &crate::stability::Counted) -> bool {
        match self {
            Family::Kind(k) => c.exponent.is_none() && c.kind == k,
            Family::NearZero => c.exponent.is_some(),
        }
    }
}

/// Distances outside the circle ([`crate::stability::Counted::excess`]) of the counted
/// multipliers of `family`, largest first.
///
/// For the near-zero exponents the distance is divided by the exponent's modulus (the
/// cosine of its angle to the imaginary axis, less the tolerance): a pair crossing the
/// axis passes zero continuously, while a real exponent stays at ±1 (the slowest thermal
/// exponents, a few 1e-5 1/s below zero, would otherwise sit at zero on the stable side
/// and end every search at its first trial; a real exponent crosses only at a fold).
fn excesses_of(f: &FloquetResult, family: Family) -> Vec<f64> {
    ranked_of(f, family).into_iter().map(|(g, _)| g).collect()
}

/// [`excesses_of`] with each entry's own distance outside the circle beside it
/// ([`crate::stability::Counted::excess`]: for a near-zero exponent `(Re λ − tol)·P`, the
/// modulus of its multiplier less one to first order), in the same order.
fn ranked_of(f: &FloquetResult, family: Family) -> Vec<(f64, f64)> {
    let mut m: Vec<(f64, f64)> = f
        .counted()
        .iter()
        .filter(|c| family.holds(c))
        .map(|c| match (family, c.exponent) {
            (Family::NearZero, Some(l)) if l.norm() > 0.0 => (
                c.excess / (l.norm() * f.near_zero.map_or(1.0, |d| d.period)),
                c.excess,
            ),
            _ => (c.excess, c.excess),
        })
        .collect();
    m.sort_by(|x, y| y.0.total_cmp(&x.0));
    m
}

/// For each family a crossing search follows (fast multipliers leaving through +1, −1
/// and as a complex pair, then the near-zero disk's exponents), the largest distance
/// outside the circle among its counted multipliers, as the searches measure it
/// (negative inside; `−∞` for a family with none). Where one of them comes close to
/// zero between two points and turns back, a crossing pair may have passed out and in
/// again within the step.
pub fn family_margins(f: &FloquetResult) -> [f64; 4] {
    [
        Family::Kind(BifurcationKind::SaddleNode),
        Family::Kind(BifurcationKind::PeriodDoubling),
        Family::Kind(BifurcationKind::NeimarkSacker),
        Family::NearZero,
    ]
    .map(|family| {
        excesses_of(f, family)
            .first()
            .copied()
            .unwrap_or(f64::NEG_INFINITY)
    })
}

/// How many counted multipliers of `family` lie outside the unit circle.
fn outside_of(f: &FloquetResult, family: Family) -> usize {
    f.counted()
        .iter()
        .filter(|c| family.holds(c) && c.excess > 0.0)
        .count()
}

/// How many counted fast multipliers of `kind` lie outside the unit circle.
fn outside_of_kind(f: &FloquetResult, kind: BifurcationKind) -> usize {
    outside_of(f, Family::Kind(kind))
}

/// A tangent refined with a nearby iterate's matrix ([`Continuation::refine_tangent`]) is
/// taken when a correction falls below this fraction of it (scaled units). The tangent's
/// uses are a predictor, an arclength row and the sign of its ω-component at folds, where
/// it is compared with [`FOLD_SLOPE_TOL`] of its size: 1e-9 leaves a wide margin.
const TANGENT_TOL: f64 = 1e-9;

/// Most refinement steps of a tangent before the Jacobian at the point is factored
/// instead (each step at least halves the system's residual, or the refinement stops at
/// once). Twenty solves and products cost about as much as one factorization.
const TANGENT_REFINEMENTS: usize = 20;

/// A solution `(x, μ)` of a bordered system.
type BorderedSolve = (Vec<f64>, f64);

/// The tangent system at a point: `[[∂R/∂A, ∂R/∂ω], [rᵀ, d]]`.
struct TangentSystem<'s> {
    parts: &'s JacobianParts,
    r_omega: &'s [f64],
    row: &'s [f64],
    corner: f64,
}

/// The corrector's chord iterations ([`NewtonOptions::chord_contraction`]): after its
/// Newton iteration, a step keeps solving with that matrix while each iteration cuts the
/// residual tenfold or more. On the dual rotor a corrector then takes Keller's
/// iteration, one Newton iteration and one or two chord iterations, and the tangent at
/// the new point is refined with the Newton iteration's matrix: one factorization per
/// step where the tangent needs no factorization of its own.
/// The chord iterations count half in the step control and in
/// [`ContinuationOptions::max_step_iterations`] ([`newton::NewtonStats::newton_equivalent`]).
pub const CHORD_CONTRACTION: f64 = 0.1;

/// Continuation settings. Every default is given in the field's doc.
#[derive(Clone, Debug)]
pub struct ContinuationOptions {
    /// Start of the sweep (rad/s).
    pub omega_start: f64,
    /// End of the sweep (rad/s); the sweep direction is from start to end.
    pub omega_end: f64,
    /// First step in scaled arclength (default 0.02: 2 % of the ω range when the response
    /// is flat).
    pub ds_initial: f64,
    /// Smallest step before giving up (default 1e-7).
    pub ds_min: f64,
    /// Largest step (default 0.1).
    pub ds_max: f64,
    /// Newton iterations the step control aims at (default 4; counted as
    /// [`newton::NewtonStats::newton_equivalent`]).
    pub target_iterations: usize,
    /// Most corrector iterations of an accepted step (default 4, counted by
    /// [`newton::NewtonStats::newton_equivalent`]: chord iterations count half); a step
    /// that needs more is rejected and halved. The corrector takes Keller's step, then a
    /// Newton step and chord steps, three counted iterations on a smooth branch at the
    /// default step cap. A corrector that
    /// labours has usually started across a turn of the branch: on the 5 L/min branch
    /// the step over the fold pair at 658–661 rad/s needs five (test
    /// `a_step_over_a_fold_pair_is_refused_and_both_folds_are_located`). It does not catch
    /// every such step (see docs/results.md on the fold pair at 612.9 and 618.0 rad/s).
    pub max_step_iterations: usize,
    /// Maximum number of accepted points (default 2000).
    pub max_points: usize,
    /// Newton settings of the corrector (defaults of [`NewtonOptions`], except chord
    /// iterations: `chord_contraction` [`CHORD_CONTRACTION`]).
    pub newton: NewtonOptions,
    /// Scale of mechanical coefficients; default (`None`): the largest mechanical
    /// coefficient magnitude of the start solution (1 if that is zero).
    pub scale_mech: Option<f64>,
    /// Scale of thermal coefficients; default: as `scale_mech` for the thermal part.
    pub scale_therm: Option<f64>,
    /// Scale of ω; default `|ω_end − ω_start|`.
    pub scale_omega: Option<f64>,
    /// Scale each DoF's coefficients by that DoF's largest coefficient magnitude at the
    /// start point instead of one scale for all mechanical (thermal) DoFs; `scale_mech` /
    /// `scale_therm` then only replace DoFs whose coefficients are all zero. Default false.
    /// Use it when the branch's structure lives in DoFs much smaller than the largest one
    /// (a journal inside a bearing clearance next to a disk's static sag): with one scale,
    /// their changes hardly count in the arclength, steps grow across their folds, and the
    /// corrector can land on a neighbouring segment of the branch.
    pub scale_per_dof: bool,
    /// Largest corrector displacement, as a multiple of the step: a step is rejected (and
    /// halved) when the corrected point lies farther than `max_corrector_distance · ds`
    /// (scaled norm) from the predictor. On a smooth branch the displacement is about
    /// `κ ds² / 2` (`κ` the curvature), so this bounds the step by the local curvature; a
    /// corrector that converges onto another nearby branch segment lands about their
    /// separation away and is rejected when that exceeds the bound. Default 1.0 (a turn of
    /// about 115° within one step, beyond the 60° tangent check on smooth branches).
    pub max_corrector_distance: f64,
    /// The crossing search stops when the arclength bracket is shorter than this (scaled
    /// units, default 1e-6).
    pub bifurcation_tol_arclength: f64,
    /// The crossing search also stops once the crossing multiplier's modulus is within
    /// this of the unit circle (default 0: off). Worth setting to the accuracy of the
    /// stability method: further steps only move the point within that error.
    pub bifurcation_tol_modulus: f64,
    /// The crossing search also stops once the bracket spans less than this in ω (rad/s;
    /// default 0: off) on a step without a fold, where ω is monotone along the bracket
    /// and so brackets the crossing's ω: the ω resolution asked of a located point.
    /// Where the crossing modulus is noisier than `bifurcation_tol_modulus` (on the dual
    /// rotor about 3e-4 from trial to trial on 4096 intervals), the search otherwise
    /// narrows on to the arclength tolerance, each trial moving the point by less.
    pub bifurcation_tol_omega: f64,
    /// Maximum search steps per located bifurcation (default 60).
    pub max_bisections: usize,
    /// Start guess for Newton at `omega_start` (all coefficients); default `None`: zero
    /// coefficients, whose first Newton iterate is the linear response. Systems without
    /// linear support (a rotor inside a bearing clearance) need a static guess.
    pub initial_guess: Option<Vec<f64>>,
    /// Predict along the branch's bend as well as its tangent: `X + ds·τ + ds²/2·κ`, with
    /// `κ = (τ − τ_prev)/Δσ` the change of the unit tangent over the step that reached
    /// the point (scaled units). Default true. Why: the linear predictor misses the
    /// branch by about `|κ| ds²/2`, and on the default sweep the tangent turns by 6–10°
    /// per step; the curvature term removes that leading error (on the default sweep
    /// 3.3 corrector iterations per point instead of 3.8, see `docs/speed-history.md`,
    /// "2026-11-24, aea6e76"). The prediction is put back onto the step's hyperplane
    /// `τ·(X − X_prev) = ds`; the check of the corrected point's distance from the linear
    /// predictor is unchanged. The same switch selects the predictor of the searches
    /// inside a step (folds, Neimark–Sacker and period-doubling points): the cubic
    /// Hermite curve through the step's two points and tangents, or (off) the tangent.
    pub curved_predictor: bool,
    /// The ω range the branch may cover, when it is wider than from `omega_start` to
    /// `omega_end` (a branch started inside a sweep's range, heading for one end, that
    /// may fold back past its start). Default `None`: between the two.
    pub omega_bounds: Option<(f64, f64)>,
    /// A direction (unknowns, then ω; unscaled) the first tangent is oriented along
    /// (`τ·d > 0` in scaled units) instead of towards `omega_end`: for a continuation
    /// started in the middle of a known branch, where the branch may run against the
    /// sweep's direction (after a fold). Default `None`.
    pub start_direction: Option<Vec<f64>>,
    /// Scales of the unknowns and ω (see [`Continuation::scales`]) used instead of those
    /// derived from the start point: a continuation of part of another one's curve then
    /// measures arclength as that one does. Default `None`.
    pub scales: Option<Vec<f64>>,
}

impl ContinuationOptions {
    /// Defaults for a sweep from `omega_start` to `omega_end`.
    pub fn new(omega_start: f64, omega_end: f64) -> Self {
        Self {
            omega_start,
            omega_end,
            ds_initial: 0.02,
            ds_min: 1e-7,
            ds_max: 0.1,
            target_iterations: 4,
            max_step_iterations: 4,
            max_points: 2000,
            newton: NewtonOptions {
                chord_contraction: CHORD_CONTRACTION,
                ..NewtonOptions::default()
            },
            scale_mech: None,
            scale_therm: None,
            scale_omega: None,
            scale_per_dof: false,
            max_corrector_distance: 1.0,
            bifurcation_tol_arclength: 1e-6,
            bifurcation_tol_modulus: 0.0,
            bifurcation_tol_omega: 0.0,
            max_bisections: 60,
            initial_guess: None,
            curved_predictor: true,
            omega_bounds: None,
            start_direction: None,
            scales: None,
        }
    }
}

/// Errors of the continuation.
#[derive(Debug, Error)]
pub enum ContinuationError {
    #[error("invalid continuation setting {field} = {value}: {reason}")]
    Setting {
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    // The Newton errors are in the messages, not `#[source]`s: a source would print
    // them twice in an error chain.
    #[error(
        "no start solution at ω = {omega} rad/s: {cause} (the start is solved from the \
         linear response, or from the initial guess; inside a strongly nonlinear range that \
         can fail: start the sweep where the response is nearly linear, e.g. below the \
         resonances)"
    )]
    Start { omega: f64, cause: NewtonError },
    #[error("no solution at ω = {omega} rad/s between two branch points: {cause}")]
    Target { omega: f64, cause: NewtonError },
    #[error(transparent)]
    Hb(#[from] HbError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The fold-curve continuation ([`fold`]) failed.
    #[error("fold curve: {0}")]
    Fold(String),
    /// Branch switching ([`switch`]) found no start on the new branch.
    #[error("branch switching: {0}")]
    Switch(String),
}

/// Whether the branch segment from speed `from` to speed `to` crosses `omega`. Half-open,
/// so that a crossing is counted once: a segment that ends exactly on `omega` crosses it,
/// one that starts there does not.
pub fn crosses(from: f64, to: f64, omega: f64) -> bool {
    (from < omega && omega <= to) || (from > omega && omega >= to)
}

/// One point of a branch.
#[derive(Clone, Debug)]
pub struct BranchPoint {
    /// Running number among accepted points (located bifurcations carry the number of the
    /// point after them).
    pub index: usize,
    /// Scaled arclength from the start point.
    pub arclength: f64,
    pub solution: HbSolution,
    /// Floquet result, when a stability method is set and succeeded.
    pub stability: Option<FloquetResult>,
    /// The stability method's error message, if it failed at this point.
    pub stability_error: Option<String>,
    /// Set on located bifurcation points.
    pub bifurcation: Option<BifurcationKind>,
    /// `∂R/∂A` at the point, when the corrector computed it there (the stability's slow
    /// exponents reuse it instead of evaluating it again).
    pub jacobian: Option<std::sync::Arc<JacobianParts>>,
}

impl BranchPoint {
    /// Stable flag, `None` when unknown.
    pub fn stable(&self) -> Option<bool> {
        self.stability.as_ref().map(|f| f.stable)
    }
}

/// Why a step was rejected.
#[derive(Clone, Debug, PartialEq)]
pub enum RejectReason {
    /// The corrector failed (message with numbers); the step is halved.
    Corrector { ds: f64, message: String },
    /// The tangent turned by more than 60°; the step is halved.
    Turn { ds: f64, cos_angle: f64 },
    /// The corrected point lies farther than `max_corrector_distance · ds` from the
    /// predictor (scaled norm); the step is halved.
    Distance { ds: f64, distance: f64 },
    /// The tangent's ω-component has the same sign at both ends of the step, but ω moved
    /// the other way (`omega_change`, rad/s): the branch turned twice within the step, a
    /// fold pair that neither end can see; the step is halved.
    FoldPair { ds: f64, omega_change: f64 },
    /// The corrector needed more than `max_step_iterations` iterations; the step is
    /// halved.
    Iterations { ds: f64, iterations: usize },
}

/// Why the continuation stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum FinishReason {
    /// ω reached a bound of the sweep.
    Bound { omega: f64 },
    /// `max_points` accepted.
    MaxPoints,
    /// The step fell below `ds_min` at `omega`.
    StepTooSmall { omega: f64, ds: f64 },
    /// The branch came back onto itself: the point at `omega` lies on the segment after
    /// the earlier point `earlier` (running number), going the same way, so from here on
    /// the continuation would retrace a closed curve (see [`closing_point`]).
    Closed { omega: f64, earlier: usize },
    /// The branch came back onto itself reversed: the point at `omega` and the one before
    /// it lie on the segments after the earlier point `earlier` (running number), going
    /// the other way; the path jumped between sheets of the branch where they meet and
    /// would now retrace itself backwards (see [`reversing_point`]).
    Reversed { omega: f64, earlier: usize },
    /// The caller stopped the branch after the point at `omega`
    /// ([`Continuation::run_until`]).
    Stopped { omega: f64 },
}

impl std::fmt::Display for FinishReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Bound { omega } => write!(f, "reached ω = {omega:.3} rad/s"),
            Self::MaxPoints => write!(f, "stopped at the maximum number of points"),
            Self::StepTooSmall { omega, ds } => write!(
                f,
                "stopped at ω = {omega:.3} rad/s: the step fell to {ds:.3e}, below ds_min"
            ),
            Self::Closed { omega, earlier } => write!(
                f,
                "stopped at ω = {omega:.3} rad/s: it closed on itself (it retraces the \
                 segment after point {earlier})"
            ),
            Self::Reversed { omega, earlier } => write!(
                f,
                "stopped at ω = {omega:.3} rad/s: it came back onto its own path going the \
                 other way (along the segment after point {earlier}); it jumped between \
                 sheets of the branch where they meet, and would now retrace itself. A \
                 different step cap (ds_max) may keep it on one sheet"
            ),
            Self::Stopped { omega } => write!(f, "stopped at ω = {omega:.3} rad/s as asked"),
        }
    }
}

/// Result of one [`Continuation::step`].
#[derive(Clone, Debug)]
pub enum StepOutcome {
    Accepted {
        point: Box<BranchPoint>,
        /// Bifurcations located between the previous point and this one.
        bifurcations: Vec<BranchPoint>,
    },
    Rejected(RejectReason),
    Finished(FinishReason),
}

/// A traced branch.
#[derive(Clone, Debug)]
pub struct Branch {
    pub points: Vec<BranchPoint>,
    pub bifurcations: Vec<BranchPoint>,
    pub finish: FinishReason,
    pub rejected_steps: usize,
}

impl Branch {
    /// Whether the located bifurcation `b` is confirmed by the multipliers of the points
    /// on either side ([`crate::stability::confirms_fold`]): always for kinds other than
    /// saddle-nodes. The points compared are the assessed ones within
    /// [`Self::CONFIRM_REACH`] points before and after the fold, any pair of them: a method
    /// that corrects the orbit (shooting) may fail right at the fold, where its Newton
    /// matrix is singular, and puts the true fold a truncation error away from the
    /// balance's. Never confirmed without assessed points on both sides.
    pub fn confirmed(&self, b: &BranchPoint) -> bool {
        if b.bifurcation != Some(BifurcationKind::SaddleNode) {
            return true;
        }
        let at = |i: usize| {
            self.points
                .iter()
                .find(|p| p.index == i)
                .and_then(|p| p.stability.as_ref())
        };
        let reach = Self::CONFIRM_REACH;
        let before: Vec<_> = (1..=reach)
            .filter_map(|k| b.index.checked_sub(k).and_then(at))
            .collect();
        let after: Vec<_> = (0..reach).filter_map(|k| at(b.index + k)).collect();
        before
            .iter()
            .any(|x| after.iter().any(|y| crate::stability::confirms_fold(x, y)))
    }

    /// How many points away from a fold [`Self::confirmed`] looks for assessed ones.
    pub const CONFIRM_REACH: usize = 3;
}

/// The cubic Hermite curve `X(θ)` from an accepted point (`θ = 0`, unit tangent `τ₀`) to
/// the next (`θ = 1`, tangent `τ₁`):
/// `X(θ) − X₀ = h₀₁(θ) (X₁ − X₀) + L (h₁₀(θ) τ₀ + h₁₁(θ) τ₁)`, with `L` the arclength of
/// the circular arc through both points with those tangents (`L = c·(α/2)/sin(α/2)`, `c`
/// the chord, `α` the angle between the tangents): with the tangents scaled by the
/// curve's own length the interpolation is fourth order (scaled by the pseudo-arclength
/// or the chord instead it is third). The predictor of a search inside the step.
#[derive(Clone, Copy, Debug)]
struct Hermite {
    /// `L`.
    scale: f64,
    /// `τ₀·(X₁ − X₀)`, the step's pseudo-arclength.
    along_chord: f64,
    /// `τ₀·τ₁`.
    along_end: f64,
}

impl Hermite {
    /// The curve between two points `x0`, `x1` (their difference `chord`) with unit
    /// tangents `t0`, `t1`.
    fn new(chord: &[f64], t0: &[f64], t1: &[f64]) -> Self {
        let along_end = dot(t0, t1);
        let half_turn = 0.5 * along_end.clamp(-1.0, 1.0).acos();
        let c = dot(chord, chord).sqrt();
        let scale = if half_turn > 1e-8 {
            c * half_turn / half_turn.sin()
        } else {
            c
        };
        Self {
            scale,
            along_chord: dot(t0, chord),
            along_end,
        }
    }

    /// `X(θ) − X₀`.
    fn offset(&self, th: f64, chord: &[f64], t0: &[f64], t1: &[f64]) -> Vec<f64> {
        let [h01, h10, h11] = Self::weights(th);
        (0..chord.len())
            .map(|i| h01 * chord[i] + self.scale * (h10 * t0[i] + h11 * t1[i]))
            .collect()
    }

    /// `[h₀₁, h₁₀, h₁₁]` at `θ`.
    fn weights(th: f64) -> [f64; 3] {
        let (th2, th3) = (th * th, th * th * th);
        [3.0 * th2 - 2.0 * th3, th3 - 2.0 * th2 + th, th3 - th2]
    }

    /// `τ₀·(X(θ) − X₀)`, the pseudo-arclength of the curve's point at `θ`.
    fn arclength(&self, th: f64) -> f64 {
        let [h01, h10, h11] = Self::weights(th);
        h01 * self.along_chord + self.scale * (h10 + h11 * self.along_end)
    }

    /// The `θ ∈ [0, 1]` whose point lies on the hyperplane `τ₀·(X − X₀) = ds` (bisection;
    /// the arclength rises along the curve when the tangent turns by less than 90°, which
    /// the step control ensures), so that the corrector starts on its constraint.
    fn parameter_at(&self, ds: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if self.arclength(mid) < ds {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

struct Current {
    a: Vec<f64>,
    omega: f64,
    tangent: Vec<f64>, // scaled, unknowns then ω, unit length
    arclength: f64,
    stability: Option<FloquetResult>,
    /// The Jacobian at this point, factored and bordered with the arclength row of
    /// `tangent`: the corrector's starting matrix for steps from here (`None` at the
    /// start point, whose tangent comes from the unbordered matrix).
    chord: Option<Factorization>,
    /// Change of the unit tangent per unit arclength over the step that reached this
    /// point (scaled units), the predictor's bend ([`ContinuationOptions::curved_predictor`]);
    /// `None` at the start point.
    bend: Option<Vec<f64>>,
}

/// The continuation driver.
pub struct Continuation<'a> {
    hb: HarmonicBalance<'a>,
    opts: ContinuationOptions,
    stability: Option<&'a dyn StabilityMethod>,
    scales: Vec<f64>, // per unknown, then ω
    current: Option<Current>,
    walk: Walk,
    finished: Option<FinishReason>,
    /// With a stability method: the accepted point at `current`, not handed out yet (see
    /// the module docs).
    held: Option<Held>,
    /// With a stability method: the accepted point before `current`, its stability known,
    /// for locating a change between it and `current`.
    previous: Option<Current>,
    /// Where the time went (see [`Continuation::timings`]).
    clock: Clock,
}

/// The corrector's side of the state: what the step control and the end of the branch
/// depend on, changed only by accepted and rejected steps (never by stability).
#[derive(Default)]
struct Walk {
    /// The next step, scaled arclength.
    ds: f64,
    /// Points accepted so far (the next point's index).
    n_points: usize,
    /// Why the branch ends after the last accepted point.
    finish_after: Option<FinishReason>,
    /// Accepted points in scaled units (unknowns, then ω) with their arclengths, for
    /// [`closing_point`].
    history: PathHistory,
}

/// Time spent in the parts of a continuation, each summed over its calls (wall time of
/// each call): the corrector steps (predictor, corrector and tangent, accepted or
/// refused), the stability evaluations of the accepted points, and the location of
/// bifurcations between points (its correctors and evaluations). With a stability
/// method on more than one thread a point's evaluation runs beside the next step's
/// corrector, so the three add up to more than the elapsed time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Corrector steps tried (accepted and refused).
    pub steps: usize,
    pub step_seconds: f64,
    /// Stability evaluations of accepted points.
    pub evaluations: usize,
    pub stability_seconds: f64,
    /// Searches between neighbouring points: one for a fold, one for a change of
    /// stability (a pair of points can have both).
    pub searches: usize,
    pub search_seconds: f64,
}

impl Timings {
    /// Where the time went, in words: the corrector, the stability evaluations (when
    /// any; the Floquet product's kernel named when `kernel` is set) and the bifurcation
    /// searches (when any).
    pub fn summary(&self, kernel: bool) -> String {
        let per = |secs: f64, n: usize| {
            if n > 0 {
                format!(", {:.0} ms each", 1e3 * secs / n as f64)
            } else {
                String::new()
            }
        };
        let mut line = format!(
            "corrector {:.1} s ({} steps{})",
            self.step_seconds,
            self.steps,
            per(self.step_seconds, self.steps)
        );
        if self.evaluations > 0 {
            line += &format!(
                ", stability {:.1} s ({} evaluations{}, beside the corrector{})",
                self.stability_seconds,
                self.evaluations,
                per(self.stability_seconds, self.evaluations),
                if kernel {
                    format!(", {} kernel", crate::stability::panel_kernel_isa())
                } else {
                    String::new()
                }
            );
        }
        if self.searches > 0 {
            line += &format!(
                ", bifurcation location {:.1} s ({} searches)",
                self.search_seconds, self.searches
            );
        }
        line
    }
}

/// Counters behind [`Timings`], shared by the tasks that run side by side.
#[derive(Debug, Default)]
struct Clock {
    steps: AtomicU64,
    step_ns: AtomicU64,
    evaluations: AtomicU64,
    stability_ns: AtomicU64,
    searches: AtomicU64,
    search_ns: AtomicU64,
}

impl Clock {
    /// Runs `f`, adding one call and its wall time to `count` and `ns`.
    fn time<R>(count: &AtomicU64, ns: &AtomicU64, f: impl FnOnce() -> R) -> R {
        let start = std::time::Instant::now();
        let out = f();
        let spent = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        count.fetch_add(1, Ordering::Relaxed);
        ns.fetch_add(spent, Ordering::Relaxed);
        out
    }

    fn read(&self) -> Timings {
        let n = |c: &AtomicU64| usize::try_from(c.load(Ordering::Relaxed)).unwrap_or(usize::MAX);
        let secs = |c: &AtomicU64| c.load(Ordering::Relaxed) as f64 * 1e-9;
        Timings {
            steps: n(&self.steps),
            step_seconds: secs(&self.step_ns),
            evaluations: n(&self.evaluations),
            stability_seconds: secs(&self.stability_ns),
            searches: n(&self.searches),
            search_seconds: secs(&self.search_ns),
        }
    }
}

/// An accepted point waiting for its stability, or for the next step to hand it out.
struct Held {
    point: Box<BranchPoint>,
    /// Located between the previous point and this one.
    bifurcations: Vec<BranchPoint>,
}

impl Held {
    fn new(point: BranchPoint) -> Self {
        Self {
            point: Box::new(point),
            bifurcations: Vec::new(),
        }
    }

    /// Whether the stability method has been applied (it gives multipliers or an error).
    fn assessed(&self) -> bool {
        self.point.stability.is_some() || self.point.stability_error.is_some()
    }
}

/// An arclength bracket `[lo, hi]` on whose ends a test function `g` has opposite signs,
/// narrowed by safeguarded regula falsi with the Illinois modification (the fold and the
/// multiplier-crossing searches).
struct Bracket {
    lo: f64,
    hi: f64,
    g_lo: f64,
    g_hi: f64,
    /// Which end moved last (+1 `lo`, −1 `hi`, 0 none yet).
    moved: i8,
}

impl Bracket {
    fn new(span: f64, g_lo: f64, g_hi: f64) -> Self {
        Self {
            lo: 0.0,
            hi: span,
            g_lo,
            g_hi,
            moved: 0,
        }
    }

    fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// The next trial: the secant's zero, kept at least `guard` times the width from
    /// either end; the midpoint when `g` gives no usable slope or has the same sign at
    /// both ends.
    fn trial(&self, guard: f64) -> f64 {
        let (lo, hi, width) = (self.lo, self.hi, self.width());
        // ends on the same side of zero (the count decides the sides, and a jump of the
        // count leaves the modulus on one side): the secant's zero lies outside
        let straddles = (self.g_lo < 0.0) != (self.g_hi < 0.0);
        if self.g_lo.is_finite() && self.g_hi.is_finite() && straddles {
            let margin = guard * width;
            (lo - self.g_lo * width / (self.g_hi - self.g_lo)).clamp(lo + margin, hi - margin)
        } else {
            0.5 * (lo + hi)
        }
    }

    /// The zero of the secant through the last two `trials` (arclength offset, `g`) when
    /// it converges: the latest trial nearer the zero than the one before, the secant's
    /// zero inside the bracket, at least [`SECANT_MARGIN`] of the width from either end,
    /// and at most half the last step away from the last trial (Brent's condition: a
    /// step that does not shrink leaves the choice to [`Self::trial`]).
    /// Close to the zero the regula falsi's guard would push the trial a tenth of the
    /// bracket away from the end that is nearly there, overshooting to the other side;
    /// the secant of the two latest trials does not.
    fn secant_trial(&self, trials: &[(f64, f64)]) -> Option<f64> {
        let [.., (s1, g1), (s2, g2)] = *trials else {
            return None;
        };
        // converging: the latest trial nearer the zero than the one before
        if !(g1.is_finite() && g2.is_finite()) || g2.abs() >= g1.abs() || s1 == s2 {
            return None;
        }
        let x = s2 - g2 * (s2 - s1) / (g2 - g1);
        let margin = SECANT_MARGIN * self.width();
        (x > self.lo + margin && x < self.hi - margin && (x - s2).abs() <= 0.5 * (s2 - s1).abs())
            .then_some(x)
    }

    /// The next trial of a crossing search: [`Self::secant_trial`] of the `trials` so far
    /// when it converges, else [`Self::trial`] with `guard`.
    fn next_trial(&self, trials: &[(f64, f64)], guard: f64) -> f64 {
        self.secant_trial(trials)
            .unwrap_or_else(|| self.trial(guard))
    }

    /// Moves the `lo` end (when `lo_side`: `g(mid)` is on `lo`'s side) or the `hi` end to
    /// `mid`; when the same end moves twice in a row the other end's `g` is halved
    /// (Illinois), so that the secant does not stall against it.
    fn narrow(&mut self, mid: f64, g_mid: f64, lo_side: bool) {
        if lo_side {
            self.lo = mid;
            self.g_lo = g_mid;
            if self.moved == 1 {
                self.g_hi *= 0.5;
            }
            self.moved = 1;
        } else {
            self.hi = mid;
            self.g_hi = g_mid;
            if self.moved == -1 {
                self.g_lo *= 0.5;
            }
            self.moved = -1;
        }
    }
}

/// The state of a Neimark–Sacker or period-doubling search ([`Continuation::locate`]) on
/// the arclength offset `s ∈ [0, span]` of a step, apart from the points themselves: the
/// bracket, the test function `g` and ω at its ends as evaluated (the bracket's own `g`
/// are halved by Illinois), and the trials so far.
struct CrossingSearch {
    span: f64,
    bracket: Bracket,
    end_g: [f64; 2],
    end_omega: [f64; 2],
    /// The trials' `(s, g)`, for the secant through the last two.
    trials: Vec<(f64, f64)>,
    /// Whether the last trial stalled ([`STALL_RATIO`]): the next one halves the bracket.
    stalled_last: bool,
}

impl CrossingSearch {
    fn new(span: f64, end_g: [f64; 2], end_omega: [f64; 2]) -> Self {
        Self {
            span,
            bracket: Bracket::new(span, end_g[0], end_g[1]),
            end_g,
            end_omega,
            trials: Vec::new(),
            stalled_last: false,
        }
    }

    /// The bracket's midpoint after a trial that stalled ([`STALL_RATIO`]); else the
    /// converging secant of the last two trials, else regula falsi kept at least a tenth
    /// of the bracket from either end ([`Bracket::next_trial`]).
    fn next_trial(&self) -> f64 {
        if self.stalled_last {
            return 0.5 * (self.bracket.lo + self.bracket.hi);
        }
        self.bracket.next_trial(&self.trials, 0.1)
    }

    /// Records the trial at `s` (test function `g`, on the `lo` end's side when `lo_side`,
    /// at speed `omega`) and says whether the search is over: the crossing found to
    /// `tol_modulus`, the accuracy the multipliers themselves have; a jump of the count
    /// ([`Self::closed_on_a_jump`]); or, with `tol_omega` (given on a step without a
    /// fold), the bracket narrower than that in ω.
    fn record(
        &mut self,
        s: f64,
        g: f64,
        lo_side: bool,
        omega: f64,
        tol_modulus: f64,
        tol_omega: Option<f64>,
    ) -> bool {
        self.bracket.narrow(s, g, lo_side);
        let end = usize::from(!lo_side);
        self.stalled_last =
            g.abs() > CROSSING_MODULUS_TOL && g.abs() >= STALL_RATIO * self.end_g[end].abs();
        self.end_g[end] = g;
        self.end_omega[end] = omega;
        self.trials.push((s, g));
        g.abs() <= tol_modulus
            || self.closed_on_a_jump()
            || tol_omega.is_some_and(|tol| (self.end_omega[1] - self.end_omega[0]).abs() <= tol)
    }

    /// Whether the search has closed in on a jump of the count rather than a crossing (see
    /// [`JUMP_BRACKET_FRACTION`]): the bracket has narrowed on the change while the
    /// multiplier stays far from the circle at both ends, either on one side of it, or on
    /// both sides with the last [`JUMP_STALLED_TRIALS`] trials no nearer the circle than
    /// the best before them (a count that jumps across the circle: a pair outside turns
    /// into two real multipliers, one inside; on a continuous crossing the trials come
    /// nearer, see [`JUMP_STALLED_TRIALS`]).
    fn closed_on_a_jump(&self) -> bool {
        let g = self.end_g;
        self.bracket.width() < self.span * JUMP_BRACKET_FRACTION
            && g[0].abs().min(g[1].abs()) > CROSSING_MODULUS_TOL
            && (g[0].signum() == g[1].signum() || self.stalled())
    }

    /// Whether the last [`JUMP_STALLED_TRIALS`] trials came no nearer zero than the
    /// nearest before them.
    fn stalled(&self) -> bool {
        let n = self.trials.len();
        if n <= JUMP_STALLED_TRIALS {
            return false;
        }
        let nearest =
            |t: &[(f64, f64)]| t.iter().map(|(_, g)| g.abs()).fold(f64::INFINITY, f64::min);
        let (before, last) = self.trials.split_at(n - JUMP_STALLED_TRIALS);
        nearest(last) >= nearest(before)
    }
}

/// Whether a crossing search of `family` found a crossing (see [`Continuation::locate`]),
/// its bracket's ends at test values `end_g` and the trial nearest the circle at `g_best`,
/// on a step where the count of that family changed by an odd number without a fold
/// (`odd_without_fold`): the crossing multiplier brought within [`CROSSING_MODULUS_TOL`]
/// of the circle; or, for the near-zero exponents, a bracket that straddles the axis with
/// the exponent complex at the trial nearest it. The near-zero test is a cosine (see
/// `excesses_of`): a pair that crosses fast keeps it far from zero until the bracket is
/// narrow in ω, while a real exponent sits at ±1. But a pair changes the count of
/// exponents with a positive real part by two, and a real exponent passes zero only at a
/// fold (det J = 0): where the count changes by an odd number on a step without a fold,
/// an exponent jumped (where sampled contacts have corners, or through the disk's edge),
/// and such a bracket is that jump. On the literature model (its default sweep, and
/// 2 L/min at 50 °C on the primary basis) the eleven searches on odd changes ended with
/// the bracket's ends 0.04–17 1/s from the axis (a real exponent at one end in ten of
/// them), and every search that came within `CROSSING_MODULUS_TOL` was on a change by two.
///
/// A fast crossing is also a crossing of the multiplier's modulus: the search must have
/// brought it within `CROSSING_MODULUS_TOL` of the circle at one end of its last bracket
/// or at its nearest trial (`near_circle`), as for the fast multipliers. A pair that
/// crosses close to zero keeps the cosine far from zero with a modulus at 1 (on the
/// literature model's switched branches at 2 L/min and 50 °C, 608.916 rad/s: 0.011 ±
/// 0.017i 1/s at one end, a modulus 1 + 6e-4), while a pair whose multiplier leaps from
/// inside to far outside the circle within the last bracket (there at 587.11 and 587.84
/// rad/s, exponents 10–16 1/s from the axis at both ends, moduli about 0.3 and 5 over the
/// doubled period) jumped.
fn found_a_crossing(
    family: Family,
    end_g: [f64; 2],
    g_best: f64,
    odd_without_fold: bool,
    near_circle: bool,
) -> bool {
    let pair_crossing = family == Family::NearZero
        && !odd_without_fold
        && near_circle
        && (end_g[0] < 0.0) != (end_g[1] < 0.0)
        && g_best.abs() < 1.0 - 1e-9;
    g_best.abs() <= CROSSING_MODULUS_TOL || pair_crossing
}

/// A corrected point of a step, before it is accepted.
struct Candidate {
    a: Vec<f64>,
    omega: f64,
    stats: newton::NewtonStats,
    /// `∂R/∂A` at the point, when the corrector left it.
    jacobian: Option<std::sync::Arc<JacobianParts>>,
    tangent: Vec<f64>,
    chord: Option<Factorization>,
    arclength: f64,
    /// Set when the step left the ω range and the point was re-solved on this bound.
    bound: Option<f64>,
}

impl<'a> Continuation<'a> {
    pub fn new(
        hb: HarmonicBalance<'a>,
        opts: ContinuationOptions,
        stability: Option<&'a dyn StabilityMethod>,
    ) -> Result<Self, ContinuationError> {
        let check = |field: &'static str, value: f64, ok: bool, reason: &'static str| {
            if ok {
                Ok(())
            } else {
                Err(ContinuationError::Setting {
                    field,
                    value,
                    reason,
                })
            }
        };
        check(
            "omega_start",
            opts.omega_start,
            opts.omega_start.is_finite() && opts.omega_start > 0.0,
            "must be positive",
        )?;
        check(
            "omega_end",
            opts.omega_end,
            opts.omega_end.is_finite()
                && opts.omega_end > 0.0
                && opts.omega_end != opts.omega_start,
            "must be positive and differ from omega_start",
        )?;
        check(
            "ds_initial",
            opts.ds_initial,
            opts.ds_initial > 0.0
                && opts.ds_initial >= opts.ds_min
                && opts.ds_initial <= opts.ds_max,
            "must lie in [ds_min, ds_max]",
        )?;
        check("ds_min", opts.ds_min, opts.ds_min > 0.0, "must be positive")?;
        check(
            "max_corrector_distance",
            opts.max_corrector_distance,
            opts.max_corrector_distance > 0.0,
            "must be positive",
        )?;
        let ds = opts.ds_initial;
        Ok(Self {
            hb,
            opts,
            stability,
            scales: Vec::new(),
            current: None,
            walk: Walk {
                ds,
                ..Walk::default()
            },
            finished: None,
            held: None,
            previous: None,
            clock: Clock::default(),
        })
    }

    /// The scales of the unknowns, then ω, that the scaled arclength divides by (set at
    /// the start; empty before).
    pub fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// Where the time went so far (see [`Timings`]).
    pub fn timings(&self) -> Timings {
        self.clock.read()
    }

    /// The harmonic-balance problem.
    pub fn harmonic_balance(&self) -> &HarmonicBalance<'a> {
        &self.hb
    }

    /// Current step in scaled arclength.
    pub fn step_size(&self) -> f64 {
        self.walk.ds
    }

    fn lo_hi(&self) -> (f64, f64) {
        let (a, b) = self
            .opts
            .omega_bounds
            .unwrap_or((self.opts.omega_start, self.opts.omega_end));
        (a.min(b), a.max(b))
    }

    /// The point without its stability.
    fn bare_point(
        &self,
        index: usize,
        a: &[f64],
        omega: f64,
        stats: &newton::NewtonStats,
        arclength: f64,
    ) -> BranchPoint {
        BranchPoint {
            index,
            arclength,
            solution: HbSolution::from_unknowns(omega, self.hb.basis(), self.hb.n_mech(), a, stats),
            stability: None,
            stability_error: None,
            bifurcation: None,
            jacobian: None,
        }
    }

    /// The stability of `solution`, an accepted point with unit tangent `tangent`, or the
    /// method's error message. The count of real multipliers above +1 is reconciled with
    /// the number of folds passed ([`FloquetResult::with_branch_parity`]): odd where the
    /// branch runs against its start direction.
    fn assess(
        &self,
        solution: &HbSolution,
        jacobian: Option<&JacobianParts>,
        tangent: &[f64],
    ) -> (Option<FloquetResult>, Option<String>) {
        if self.stability.is_none() {
            return (None, None);
        }
        let odd_folds = self.runs_backward(tangent);
        let (f, e) = Clock::time(&self.clock.evaluations, &self.clock.stability_ns, || {
            self.assess_with(solution, jacobian, |m, system, orbit| {
                m.multipliers(system, orbit)
            })
        });
        (f.map(|f| f.with_branch_parity(odd_folds)), e)
    }

    /// Whether the tangent's ω-component points against the start direction (from
    /// `omega_start` to `omega_end`): the branch has passed an odd number of folds.
    fn runs_backward(&self, tangent: &[f64]) -> bool {
        let nu = self.hb.n_unknowns();
        tangent[nu] * (self.opts.omega_end - self.opts.omega_start) < 0.0
    }

    /// As [`Self::assess`], with the method's evaluation for a bifurcation search
    /// between two points with results `ends` ([`StabilityMethod::search_multipliers`]).
    fn assess_for_search(
        &self,
        solution: &HbSolution,
        ends: [&FloquetResult; 2],
    ) -> (Option<FloquetResult>, Option<String>) {
        self.assess_with(solution, None, |m, system, orbit| {
            m.search_multipliers(system, orbit, ends)
        })
    }

    /// [`Self::assess_for_search`] without the coupled exponents nearest zero
    /// ([`crate::stability::assess_fast`]): what a period-doubling search's trials need
    /// where the disks at its ends are clear of flips ([`NearZeroDisk::clear_of_flips`]).
    ///
    /// [`NearZeroDisk::clear_of_flips`]: crate::stability::NearZeroDisk::clear_of_flips
    fn assess_fast_for_search(
        &self,
        solution: &HbSolution,
        ends: [&FloquetResult; 2],
    ) -> (Option<FloquetResult>, Option<String>) {
        self.assessed(|m| {
            crate::stability::assess_fast(m, &self.hb, solution, |m, system, orbit| {
                m.search_multipliers(system, orbit, ends)
            })
        })
    }

    fn assess_with(
        &self,
        solution: &HbSolution,
        jacobian: Option<&JacobianParts>,
        evaluate: impl FnOnce(
            &dyn StabilityMethod,
            &dyn crate::system::System,
            &dyn crate::system::PeriodicOrbit,
        ) -> Result<FloquetResult, crate::stability::StabilityError>
        + Send,
    ) -> (Option<FloquetResult>, Option<String>) {
        self.assessed(|m| crate::stability::assess(m, &self.hb, solution, jacobian, evaluate))
    }

    /// What `run` gives with the continuation's stability method, as a point stores it:
    /// the result or the error's message (neither without a method).
    fn assessed(
        &self,
        run: impl FnOnce(
            &dyn StabilityMethod,
        ) -> Result<FloquetResult, crate::stability::StabilityError>,
    ) -> (Option<FloquetResult>, Option<String>) {
        match self.stability.map(run) {
            None => (None, None),
            Some(Ok(f)) => (Some(f), None),
            Some(Err(e)) => (None, Some(e.to_string())),
        }
    }

    /// The start point and the state to continue from (sets the scales and the history).
    fn start(&mut self) -> Result<(Current, BranchPoint), ContinuationError> {
        let omega = self.opts.omega_start;
        let nu = self.hb.n_unknowns();
        let entries = |field: &'static str, v: &[f64], reason: &'static str| {
            Err(ContinuationError::Setting {
                field,
                value: v.len() as f64,
                reason,
            })
        };
        if let Some(d) = &self.opts.start_direction
            && (d.len() != nu + 1 || d.iter().any(|x| !x.is_finite()))
        {
            return entries(
                "start_direction",
                d,
                "must hold one finite entry per unknown and one for ω",
            );
        }
        if let Some(v) = &self.opts.scales
            && (v.len() != nu + 1 || v.iter().any(|x| !(x.is_finite() && *x > 0.0)))
        {
            return entries(
                "scales",
                v,
                "must hold one positive, finite scale per unknown and one for ω",
            );
        }
        let guess = match &self.opts.initial_guess {
            Some(g) if g.len() == nu => g.clone(),
            Some(g) => {
                return Err(ContinuationError::Hb(HbError::Dimension {
                    what: "initial guess",
                    expected: nu,
                    got: g.len(),
                }));
            }
            None => vec![0.0; nu],
        };
        let (a, stats) = newton::solve_fixed(&self.hb, omega, &guess, &self.opts.newton)
            .map_err(|cause| ContinuationError::Start { omega, cause })?;
        self.scales = match &self.opts.scales {
            Some(given) => given.clone(),
            None => self.start_scales(&a),
        };
        let tangent = self.tangent(&a, omega, None, None, None)?;
        let point = self.bare_point(0, &a, omega, &stats, 0.0);
        self.walk.history = PathHistory::new();
        self.walk.history.push(self.scaled(&a, omega), 0.0);
        self.walk.n_points = 1;
        let cur = Current {
            a,
            omega,
            tangent,
            arclength: 0.0,
            stability: None,
            chord: None,
            bend: None,
        };
        Ok((cur, point))
    }

    /// The scales of the unknowns, then ω, derived from the start solution `a` (see
    /// [`ContinuationOptions::scale_mech`] and the fields after it).
    fn start_scales(&self, a: &[f64]) -> Vec<f64> {
        let nm = self.hb.n_mech_unknowns();
        let maxabs = |s: &[f64]| s.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let or1 = |v: f64| if v > 0.0 && v.is_finite() { v } else { 1.0 };
        let sm = self
            .opts
            .scale_mech
            .unwrap_or_else(|| or1(maxabs(&a[..nm])));
        let st = self
            .opts
            .scale_therm
            .unwrap_or_else(|| or1(maxabs(&a[nm..])));
        let sw = self
            .opts
            .scale_omega
            .unwrap_or((self.opts.omega_end - self.opts.omega_start).abs());
        let mut scales: Vec<f64> = (0..a.len()).map(|i| if i < nm { sm } else { st }).collect();
        if self.opts.scale_per_dof {
            let nc = self.hb.n_coeffs();
            for (block, scales) in a.chunks(nc).zip(scales.chunks_mut(nc)) {
                let m = maxabs(block);
                if m > 0.0 && m.is_finite() {
                    scales.iter_mut().for_each(|v| *v = m);
                }
            }
        }
        scales.push(sw);
        scales
    }

    /// The arclength row of the unknowns for the scaled tangent `t`: `t_i / s_i`.
    fn arc_row(&self, t: &[f64]) -> Vec<f64> {
        let nu = self.hb.n_unknowns();
        (0..nu).map(|i| t[i] / self.scales[i]).collect()
    }

    /// `(a, ω)` in scaled units.
    fn scaled(&self, a: &[f64], omega: f64) -> Vec<f64> {
        let s = &self.scales;
        let nu = a.len();
        let mut x: Vec<f64> = a.iter().zip(s).map(|(v, si)| v / si).collect();
        x.push(omega / s[nu]);
        x
    }

    /// Corrects from `cur` at arclength offset `ds` along its tangent.
    fn correct(&self, cur: &Current, ds: f64) -> Result<newton::Converged, NewtonError> {
        self.correct_toward(cur, ds, None)
    }

    /// [`Self::correct`]; with `end`, a later accepted point, the predictor is the cubic
    /// Hermite curve through both points and their tangents (a search inside the step
    /// between them: the trials start within `O(h⁴)` of the branch instead of the
    /// `O(h²)`/`O(h³)` of the tangent and bend extrapolations, `h` the step).
    fn correct_toward(
        &self,
        cur: &Current,
        ds: f64,
        end: Option<&Current>,
    ) -> Result<newton::Converged, NewtonError> {
        let nu = self.hb.n_unknowns();
        let s = &self.scales;
        let t = &cur.tangent;
        let offset = self.predictor_offset(cur, ds, end);
        let pred: Vec<f64> = (0..nu).map(|i| cur.a[i] + offset[i] * s[i]).collect();
        let w_pred = cur.omega + offset[nu] * s[nu];
        let row = self.arc_row(t);
        let arc = ArcConstraint {
            anchor: &cur.a,
            anchor_omega: cur.omega,
            row: &row,
            corner: t[nu] / s[nu],
            ds,
        };
        newton::solve_arclength_from(
            &self.hb,
            &pred,
            w_pred,
            &arc,
            cur.chord.as_ref(),
            &self.opts.newton,
        )
    }

    /// The predictor's offset from `cur` in scaled units (unknowns, then ω) for a step of
    /// `ds`: along the tangent, plus the bend's term when known
    /// ([`ContinuationOptions::curved_predictor`]); inside the step to `end`, the cubic
    /// Hermite curve between the two points.
    fn predictor_offset(&self, cur: &Current, ds: f64, end: Option<&Current>) -> Vec<f64> {
        let nu = self.hb.n_unknowns();
        let t = &cur.tangent;
        let h = end.map_or(0.0, |e| e.arclength - cur.arclength);
        if let Some(e) = end.filter(|_| self.opts.curved_predictor && h > 0.0) {
            let s = &self.scales;
            let chord: Vec<f64> = (0..=nu)
                .map(|i| {
                    if i < nu {
                        (e.a[i] - cur.a[i]) / s[i]
                    } else {
                        (e.omega - cur.omega) / s[nu]
                    }
                })
                .collect();
            let hermite = Hermite::new(&chord, t, &e.tangent);
            return hermite.offset(hermite.parameter_at(ds), &chord, t, &e.tangent);
        }
        match &cur.bend {
            Some(k) => {
                let mut offset: Vec<f64> =
                    (0..=nu).map(|i| ds * t[i] + 0.5 * ds * ds * k[i]).collect();
                // back onto the step's hyperplane τ·ΔX = ds (the bend is nearly normal to
                // τ; what it has along τ would only be undone by the corrector's first
                // iteration)
                let along = dot(t, &offset) - ds;
                offset
                    .iter_mut()
                    .zip(t)
                    .for_each(|(o, ti)| *o -= along * ti);
                offset
            }
            None => t.iter().map(|ti| ds * ti).collect(),
        }
    }

    /// Scaled distance of `(a, omega)` from the predictor `cur + ds·τ`.
    fn corrector_distance(&self, cur: &Current, ds: f64, a: &[f64], omega: f64) -> f64 {
        let s = &self.scales;
        let t = &cur.tangent;
        let nu = a.len();
        let sq: f64 = (0..nu)
            .map(|i| ((a[i] - cur.a[i]) / s[i] - ds * t[i]).powi(2))
            .sum();
        (sq + ((omega - cur.omega) / s[nu] - ds * t[nu]).powi(2)).sqrt()
    }

    /// One continuation step (the first call computes the start point).
    pub fn step(&mut self) -> Result<StepOutcome, ContinuationError> {
        if let Some(f) = &self.finished {
            return Ok(StepOutcome::Finished(f.clone()));
        }
        if self.walk.finish_after.is_some() {
            // the last accepted point first, then the reason
            if self.held.is_some() {
                self.settle_held();
                if let Some(out) = self.hand_out() {
                    return Ok(out);
                }
            }
            if let Some(f) = self.walk.finish_after.take() {
                self.finished = Some(f.clone());
                return Ok(StepOutcome::Finished(f));
            }
        }
        let mut cur = match self.current.take() {
            Some(cur) => cur,
            None => {
                let (cur, point) = self.start()?;
                if self.stability.is_none() {
                    self.current = Some(cur);
                    return Ok(StepOutcome::Accepted {
                        point: Box::new(point),
                        bifurcations: Vec::new(),
                    });
                }
                // handed out after the next corrector, which runs alongside its stability
                self.held = Some(Held::new(point));
                cur
            }
        };
        let outcome = self.advance(&mut cur);
        match self.current {
            None => self.current = Some(cur),
            Some(_) if self.stability.is_some() => self.previous = Some(cur),
            Some(_) => {}
        }
        outcome
    }

    /// The held point with its stability, and the change located between the previous
    /// point and it (no-op when it is already assessed).
    fn settle_held(&mut self) {
        let Some(held) = self.held.as_ref().filter(|h| !h.assessed()) else {
            return;
        };
        if let Some(mut cur) = self.current.take() {
            let result = self.assess(
                &held.point.solution,
                held.point.jacobian.as_deref(),
                &cur.tangent,
            );
            self.settle(&mut cur, result);
            self.current = Some(cur);
        }
    }

    /// Stores the stability of the held point at `cur` and locates a change of stability
    /// between the previous point and it.
    fn settle(&mut self, cur: &mut Current, result: (Option<FloquetResult>, Option<String>)) {
        let found = match (&self.previous, &self.held) {
            (Some(prev), Some(held)) => {
                Some(self.located_changes_with(prev, cur, result.0.as_ref(), held.point.index))
            }
            _ => None,
        };
        self.settle_with(cur, result, found);
    }

    /// [`Self::settle`] with the change between the previous point and the held one
    /// already located (`found`).
    fn settle_with(
        &mut self,
        cur: &mut Current,
        result: (Option<FloquetResult>, Option<String>),
        found: Option<Vec<BranchPoint>>,
    ) {
        let Some(mut held) = self.held.take() else {
            return;
        };
        cur.stability.clone_from(&result.0);
        (held.point.stability, held.point.stability_error) = result;
        // the Jacobian was kept for the assessment alone (megabytes a point)
        held.point.jacobian = None;
        held.bifurcations.extend(found.into_iter().flatten());
        self.held = Some(held);
    }

    /// Hands out the held point with its bifurcations.
    fn hand_out(&mut self) -> Option<StepOutcome> {
        self.held.take().map(|h| StepOutcome::Accepted {
            point: h.point,
            bifurcations: h.bifurcations,
        })
    }

    fn advance(&mut self, cur: &mut Current) -> Result<StepOutcome, ContinuationError> {
        // the held point's stability alongside this step's corrector
        // ... and the location of a change between the previous point and the held one
        // (which needs the held point's stability) after it, still beside the corrector
        let ds = self.walk.ds;
        let (assessed, candidate) = match self.held.as_ref().filter(|h| !h.assessed()) {
            Some(held) => {
                // the fold's search needs no stability: it runs after the corrector,
                // the side that is usually done first
                let index = held.point.index;
                let ((result, crossings), (candidate, folds)) = rayon::join(
                    || {
                        let result = self.assess(
                            &held.point.solution,
                            held.point.jacobian.as_deref(),
                            &cur.tangent,
                        );
                        let found = self.previous.as_ref().map(|prev| {
                            let ends = [prev.stability.as_ref(), result.0.as_ref()];
                            self.located_crossings(prev, cur, ends, index)
                        });
                        (result, found)
                    },
                    || {
                        let candidate = self.candidate(cur, ds);
                        let folds = self
                            .previous
                            .as_ref()
                            .map(|prev| self.located_fold(prev, cur, index));
                        (candidate, folds)
                    },
                );
                let found = crossings.map(|c| merged_changes(c, folds.into_iter().flatten()));
                (Some((result, found)), candidate)
            }
            None => (None, self.candidate(cur, ds)),
        };
        if let Some((result, found)) = assessed {
            self.settle_with(cur, result, found);
        }
        let c = match candidate {
            Ok(c) => c,
            Err(reason) => return Ok(Self::reject(&mut self.walk, &self.opts, reason, cur.omega)),
        };
        let mut walk = std::mem::take(&mut self.walk);
        let (mut point, mut next) = self.accept(&mut walk, cur, c);
        self.walk = walk;
        if self.stability.is_some() {
            if let Some(out) = self.hand_out() {
                // the held point (assessed above) goes out; the new one is held
                self.held = Some(Held::new(point));
                self.current = Some(next);
                return Ok(out);
            }
            // nothing was held (not reached): assessed and handed out at once
            (point.stability, point.stability_error) =
                self.assess(&point.solution, point.jacobian.as_deref(), &next.tangent);
            point.jacobian = None;
            next.stability.clone_from(&point.stability);
        }
        let bifurcations = self.located_changes(cur, &next, point.index);
        self.current = Some(next);
        Ok(StepOutcome::Accepted {
            point: Box::new(point),
            bifurcations,
        })
    }

    /// The bookkeeping of an accepted step from `cur` to the corrected `c`: step control,
    /// the end of the branch (bound, closure, reversal, point budget), the predictor's
    /// bend. The point (without stability) and the state to step on from.
    fn accept(&self, walk: &mut Walk, cur: &Current, c: Candidate) -> (BranchPoint, Current) {
        if let Some(wb) = c.bound {
            walk.finish_after = Some(FinishReason::Bound { omega: wb });
        }
        let mut point = self.bare_point(walk.n_points, &c.a, c.omega, &c.stats, c.arclength);
        point.jacobian = c.jacobian;
        // step control
        let effort = c.stats.newton_equivalent();
        let factor = if effort == 0 {
            2.0
        } else {
            (self.opts.target_iterations as f64 / effort as f64)
                .sqrt()
                .clamp(0.5, 2.0)
        };
        walk.ds = (walk.ds * factor).clamp(self.opts.ds_min, self.opts.ds_max);
        walk.n_points += 1;
        let x = self.scaled(&c.a, c.omega);
        if walk.finish_after.is_none()
            && let Some(earlier) = closing_point(&walk.history, &x, c.arclength, &c.tangent)
        {
            walk.finish_after = Some(FinishReason::Closed {
                omega: c.omega,
                earlier,
            });
        }
        if walk.finish_after.is_none()
            && let Some(earlier) = reversing_point(&walk.history, &x, c.arclength, &c.tangent)
        {
            walk.finish_after = Some(FinishReason::Reversed {
                omega: c.omega,
                earlier,
            });
        }
        walk.history.push(x, c.arclength);
        if walk.n_points >= self.opts.max_points && walk.finish_after.is_none() {
            walk.finish_after = Some(FinishReason::MaxPoints);
        }
        let span = c.arclength - cur.arclength;
        let bend = (self.opts.curved_predictor && c.bound.is_none() && span > 0.0).then(|| {
            c.tangent
                .iter()
                .zip(&cur.tangent)
                .map(|(t, t0)| (t - t0) / span)
                .collect()
        });
        let next = Current {
            a: c.a,
            omega: c.omega,
            tangent: c.tangent,
            arclength: c.arclength,
            stability: None,
            chord: c.chord,
            bend,
        };
        (point, next)
    }

    /// The corrected point of a step of `ds` from `cur`, its tangent, and the
    /// re-solve on the ω bound when the step left the range; or why the step is rejected.
    fn candidate(&self, cur: &Current, ds: f64) -> Result<Candidate, RejectReason> {
        Clock::time(&self.clock.steps, &self.clock.step_ns, || {
            self.try_step(cur, ds)
        })
    }

    /// [`Self::candidate`], untimed.
    fn try_step(&self, cur: &Current, ds: f64) -> Result<Candidate, RejectReason> {
        let nu = self.hb.n_unknowns();
        let corrector = |e: &dyn std::fmt::Display| RejectReason::Corrector {
            ds,
            message: e.to_string(),
        };
        let newton::Converged {
            a,
            omega,
            stats,
            jacobian,
            matrix,
        } = self.correct(cur, ds).map_err(|e| corrector(&e))?;
        if stats.newton_equivalent() > self.opts.max_step_iterations {
            return Err(RejectReason::Iterations {
                ds,
                iterations: stats.newton_equivalent(),
            });
        }
        let distance = self.corrector_distance(cur, ds, &a, omega);
        if distance > self.opts.max_corrector_distance * ds {
            return Err(RejectReason::Distance { ds, distance });
        }
        let (tangent, chord, parts) = self
            .tangent_factored(&a, omega, Some(&cur.tangent), jacobian, matrix, true)
            .map_err(|e| corrector(&e))?;
        // `∂R/∂A` at the point (the corrector's or the tangent's), kept for Hill's pencil
        // when stability is assessed
        let parts = self.stability.is_some().then(|| std::sync::Arc::new(parts));
        let cos_angle: f64 = tangent.iter().zip(&cur.tangent).map(|(x, y)| x * y).sum();
        if cos_angle < 0.5 {
            return Err(RejectReason::Turn { ds, cos_angle });
        }
        // ω(σ) rising at both ends (say) but lower at the end: it fell in between
        let omega_change = omega - cur.omega;
        if tangent[nu] * cur.tangent[nu] > 0.0
            && omega_change * cur.tangent[nu] < 0.0
            && omega_change.abs() > FOLD_PAIR_MIN_CHANGE * ds * self.scales[nu]
        {
            return Err(RejectReason::FoldPair { ds, omega_change });
        }
        debug_assert_eq!(tangent.len(), nu + 1);
        let (lo, hi) = self.lo_hi();
        if omega >= lo && omega <= hi {
            return Ok(Candidate {
                a,
                omega,
                stats,
                jacobian: parts,
                tangent,
                chord,
                arclength: cur.arclength + ds,
                bound: None,
            });
        }
        // re-solve on the bound from the interpolation between the two points
        let wb = if omega < lo { lo } else { hi };
        let f = (wb - cur.omega) / (omega - cur.omega);
        let (ab, st) = self
            .solve_interpolated(&cur.a, cur.omega, &a, omega, wb)
            .map_err(|e| corrector(&e))?;
        // the tangent and its matrix stay those of the corrected point: the bound ends
        // the run, and the point is not stepped from
        Ok(Candidate {
            a: ab,
            omega: wb,
            stats: st,
            jacobian: None,
            tangent,
            chord,
            arclength: cur.arclength + f * ds,
            bound: Some(wb),
        })
    }

    fn reject(
        walk: &mut Walk,
        opts: &ContinuationOptions,
        reason: RejectReason,
        omega: f64,
    ) -> StepOutcome {
        walk.ds *= 0.5;
        if walk.ds < opts.ds_min {
            walk.finish_after = Some(FinishReason::StepTooSmall { omega, ds: walk.ds });
        }
        StepOutcome::Rejected(reason)
    }

    /// Runs to the end, calling `observer` after every step.
    pub fn run(&mut self, observer: impl FnMut(&StepOutcome)) -> Result<Branch, ContinuationError> {
        self.run_until(observer, |_| false)
    }

    /// [`Self::run`], ending after the first accepted point (with its stability and the
    /// bifurcations before it) for which `stop` is true ([`FinishReason::Stopped`]). The
    /// continuation has then taken the corrector step past that point; stepping on
    /// resumes from there.
    pub fn run_until(
        &mut self,
        mut observer: impl FnMut(&StepOutcome),
        mut stop: impl FnMut(&BranchPoint) -> bool,
    ) -> Result<Branch, ContinuationError> {
        let mut points = Vec::new();
        let mut bifs = Vec::new();
        let mut rejected = 0;
        loop {
            let out = self.step()?;
            observer(&out);
            match out {
                StepOutcome::Accepted {
                    point,
                    bifurcations,
                } => {
                    let omega = point.solution.omega;
                    let done = stop(&point);
                    points.push(*point);
                    bifs.extend(bifurcations);
                    if done {
                        return Ok(Branch {
                            points,
                            bifurcations: bifs,
                            finish: FinishReason::Stopped { omega },
                            rejected_steps: rejected,
                        });
                    }
                }
                StepOutcome::Rejected(_) => rejected += 1,
                StepOutcome::Finished(f) => {
                    return Ok(Branch {
                        points,
                        bifurcations: bifs,
                        finish: f,
                        rejected_steps: rejected,
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;

    /// A crossing search as [`Continuation::locate`] runs it, on a test function of the
    /// arclength offset with the side decided by `lo_side`: the trials until `|g| ≤ tol`,
    /// the bracket is narrower than `1e-6`, or it closed on a jump.
    fn bracket_search(
        span: f64,
        g: impl Fn(f64) -> f64,
        lo_side: impl Fn(f64) -> bool,
        secant: bool,
        tol: f64,
    ) -> Vec<(f64, f64)> {
        let mut search = CrossingSearch::new(span, [g(0.0), g(span)], [0.0, span]);
        for _ in 0..60 {
            if search.bracket.width() <= 1e-6 {
                break;
            }
            let s = if secant {
                search.next_trial()
            } else {
                search.bracket.trial(0.1)
            };
            if search.record(s, g(s), lo_side(s), s, tol, None) {
                break;
            }
        }
        search.trials
    }

    #[test]
    fn a_near_zero_leap_on_an_odd_change_is_not_a_crossing() {
        let nz = Family::NearZero;
        // the literature model's default sweep, 613.58 → 612.48 rad/s: a real exponent (+1,
        // 0.038 1/s, its modulus within 0.002 of the circle) at one end of the last
        // bracket, a stable pair (cosine −0.51) at the other, the count 1 → 0
        assert!(!found_a_crossing(nz, [1.0, -0.5109], -0.51, true, true));
        // the same bracket on a change by two: a pair that crossed fast
        assert!(found_a_crossing(nz, [1.0, -0.5109], -0.51, false, true));
        // ... unless its multiplier never came near the circle: a pair that leapt
        // (the switched branches' 587.11 rad/s, cosines 0.97 and −0.87 at the ends)
        assert!(!found_a_crossing(
            nz,
            [0.9714, -0.8746],
            -0.8746,
            false,
            false
        ));
        // a real exponent at the trial nearest the axis is no pair either way
        assert!(!found_a_crossing(nz, [1.0, -0.5], 1.0, false, true));
        // a crossing brought to the axis is one, whatever the count
        assert!(found_a_crossing(nz, [0.0026, -0.093], 0.0026, true, true));
        // the fast multipliers' families are decided by the modulus alone
        let ns = Family::Kind(BifurcationKind::NeimarkSacker);
        assert!(!found_a_crossing(ns, [-0.41, 4.77], -0.41, false, false));
        assert!(found_a_crossing(ns, [-0.01, 0.02], 0.015, false, true));
    }

    /// The converging secant of the last two trials reaches smooth crossings in fewer
    /// trials than the guarded regula falsi alone, and to the same tolerance: test
    /// functions shaped like the default sweep's period-doubling search at 617.19 rad/s
    /// (the modulus from 1e-3 to 1.62 across a step of 0.063, `0.13 sinh(79.5 (s − r))`),
    /// with the crossing moved across the step and the bend varied.
    #[test]
    fn the_secant_trial_finds_smooth_crossings_in_fewer_trials() {
        let span = 0.06285;
        let (mut plain_total, mut secant_total) = (0, 0);
        for k in [5.0, 20.0, 79.5] {
            for i in 1..20 {
                let root = span * f64::from(i) / 20.0;
                let g = |s: f64| (k * (s - root)).sinh() / k;
                let lo_side = |s: f64| g(s) < 0.0;
                let plain = bracket_search(span, g, lo_side, false, 1e-6);
                let secant = bracket_search(span, g, lo_side, true, 1e-6);
                for t in [&plain, &secant] {
                    let last = t.last().expect("trials").1;
                    assert!(last.abs() <= 1e-6, "k {k}, root {root}: {t:?}");
                }
                plain_total += plain.len();
                secant_total += secant.len();
            }
        }
        assert!(
            10 * secant_total < 8 * plain_total,
            "secant {secant_total} trials against regula falsi {plain_total}"
        );
        // a secant step that does not shrink, or whose latest trial is not nearer the
        // zero, is not taken
        let bracket = Bracket::new(0.15, -0.1, 0.1);
        assert_eq!(bracket.secant_trial(&[(0.05, 0.01)]), None);
        assert_eq!(bracket.secant_trial(&[(0.05, 0.01), (0.06, 0.011)]), None);
        assert_eq!(bracket.secant_trial(&[(0.02, 0.04), (0.06, 0.03)]), None);
        // nor one outside the bracket
        assert_eq!(bracket.secant_trial(&[(0.14, 0.02), (0.145, 0.0195)]), None);
        let x = bracket.secant_trial(&[(0.05, 0.04), (0.06, 0.01)]);
        assert!(x.is_some_and(|x| (x - 0.19 / 3.0).abs() < 1e-12), "{x:?}");
    }

    /// A count that changes by a jump, the crossing multiplier's modulus 0.1 outside the
    /// circle on both sides, ends the search once the bracket is below 1/64 of the step;
    /// a smooth crossing, however steep, is never taken for one.
    #[test]
    fn a_jump_of_the_count_ends_the_search_early() {
        let jump = 0.0682;
        let trials = bracket_search(
            0.15,
            |s| if s < jump { 0.1 } else { 0.09 },
            |s| s < jump,
            true,
            1e-4,
        );
        assert!(trials.len() <= 8, "{} trials: {trials:?}", trials.len());
        let to_tolerance = bracket_search(
            0.15,
            |s| if s < jump { 0.1 } else { 0.09 },
            |s| s < jump,
            true,
            0.0,
        );
        assert!(to_tolerance.len() <= 8);
        // a count that jumps across the circle (0.11 outside on one side, 0.42 inside on
        // the other, as at 589.52 rad/s on the default sweep) ends as early, far from it
        for jump in [0.0682, 0.01, 0.14] {
            let g = |s: f64| if s < jump { 0.11 } else { -0.42 };
            let trials = bracket_search(0.15, g, |s| s < jump, true, 1e-4);
            assert!(trials.len() <= 10, "{} trials: {trials:?}", trials.len());
            assert!(trials.iter().all(|t| t.1.abs() > 0.1), "{trials:?}");
        }
        for slope in [0.5, 5.0, 50.0, 500.0] {
            let g = |s: f64| slope * (s - 0.07);
            let t = bracket_search(0.15, g, |s| g(s) < 0.0, true, 1e-4);
            assert!(
                t.last().expect("trials").1.abs() <= 1e-4,
                "slope {slope}: {t:?}"
            );
        }
    }

    /// A jump of the count across the circle with the modulus far outside on one side and
    /// nearer inside on the other (as on W5's switched branches: +4.6 against −0.49), at
    /// any place in the step, ends in at most seven trials: after each trial that stalls
    /// the bracket is halved. Guarded regula falsi alone needs up to 16 here, as the
    /// search before the midpoint rule did (up to 22 trials on W5).
    #[test]
    fn a_stalled_trial_halves_the_bracket() {
        let (span, mut most, mut most_plain) = (0.15, 0, 0);
        for i in 1..40 {
            let jump = span * f64::from(i) / 40.0;
            for (outside, inside) in [(4.6, -0.49), (-0.49, 4.6), (0.11, -0.42)] {
                let g = |s: f64| if s < jump { outside } else { inside };
                let trials = bracket_search(span, g, |s| s < jump, true, 1e-4);
                assert!(trials.iter().all(|t| t.1.abs() > 0.1), "{trials:?}");
                most = most.max(trials.len());
                let plain = bracket_search(span, g, |s| s < jump, false, 1e-4);
                most_plain = most_plain.max(plain.len());
            }
        }
        assert!(most <= 7, "{most} trials");
        assert!(most_plain > most, "{most_plain} against {most}");
    }

    #[test]
    fn the_hermite_predictor_follows_a_circle_to_fourth_order() {
        // Unit circle from angle 0 with unit tangents: the step of angle φ has
        // pseudo-arclength h = τ₀·(X₁ − X₀) = sin φ; the point of the curve on the
        // hyperplane τ₀·(X − X₀) = h/2 lies on the circle at angle asin(h/2).
        let error = |phi: f64| {
            let x0 = [1.0, 0.0];
            let t0 = [0.0, 1.0];
            let x1 = [phi.cos(), phi.sin()];
            let t1 = [-phi.sin(), phi.cos()];
            let chord = [x1[0] - x0[0], x1[1] - x0[1]];
            let h = dot(&t0, &chord);
            let hermite = Hermite::new(&chord, &t0, &t1);
            assert!((hermite.scale - phi).abs() < 1e-12, "the arc's length");
            let th = hermite.parameter_at(0.5 * h);
            assert!((hermite.arclength(th) - 0.5 * h).abs() < 1e-12 * h);
            let off = hermite.offset(th, &chord, &t0, &t1);
            let p = [x0[0] + off[0], x0[1] + off[1]];
            let exact = (0.5 * h).asin();
            ((p[0] - exact.cos()).powi(2) + (p[1] - exact.sin()).powi(2)).sqrt()
        };
        let (coarse, fine) = (error(0.4), error(0.2));
        // the end points and tangents are matched: the midpoint error falls as h⁴
        assert!(coarse < 1e-4, "{coarse}");
        let order = (coarse / fine).log2();
        eprintln!("midpoint error {coarse:.2e} at φ = 0.4, {fine:.2e} at 0.2: order {order:.2}");
        assert!(
            (3.7..4.3).contains(&order),
            "order {order}: {coarse} / {fine}"
        );
        // the weights reproduce both ends and both tangents
        assert_eq!(Hermite::weights(0.0), [0.0, 0.0, 0.0]);
        assert_eq!(Hermite::weights(1.0), [1.0, 0.0, 0.0]);
    }

    #[test]
    fn a_pair_crossing_beside_a_fold_is_seen_in_its_own_kind() {
        // From the default sweep next to the fold at 592.16 rad/s: a complex pair outside
        // at one point; at the next it is back inside while three real multipliers have
        // left through +1 (the fold's and two slow ones). Ranked together, the smallest
        // outside multiplier is real and positive, and the step reads as a fold only.
        let c = |re: f64, im: f64| Complex64::new(re, im);
        let pair = FloquetResult::new(vec![
            c(0.85, 0.62),
            c(0.85, -0.62),
            c(0.9958, 0.0),
            c(-0.3, 0.0),
        ]);
        let reals = FloquetResult::new(vec![
            c(0.5, 0.4),
            c(0.5, -0.4),
            c(1.058, 0.0),
            c(1.0115, 0.0),
            c(1.0013, 0.0),
            c(-0.3, 0.0),
        ]);
        assert_eq!(
            crate::stability::classify_crossing(&pair, &reals),
            Some(BifurcationKind::SaddleNode)
        );
        let ns = BifurcationKind::NeimarkSacker;
        assert_eq!(outside_of_kind(&pair, ns), 2);
        assert_eq!(outside_of_kind(&reals, ns), 0);
        let pd = BifurcationKind::PeriodDoubling;
        assert_eq!(outside_of_kind(&pair, pd), outside_of_kind(&reals, pd));
        // the pair's distances outside the circle, largest first, without the real
        // multiplier near +1
        let m = excesses_of(&pair, Family::Kind(ns));
        assert_eq!(m.len(), 2);
        assert!((m[0] - (c(0.85, 0.62).norm() - 1.0 - UNIT_CIRCLE_TOL)).abs() < 1e-15);
    }

    /// The tangent refined with the matrix of a neighbouring point equals the one from a
    /// factorization at the point itself, and a matrix from far away is either refused or
    /// gives the far system's solution.
    #[test]
    fn refined_tangent_equals_the_freshly_factored_one() {
        use crate::hb::Basis;
        use crate::systems::duffing::Duffing;
        let sys = Duffing::default();
        let basis = Basis::integer(3).expect("basis");
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let opts = ContinuationOptions::new(0.5, 1.6);
        let mut cont = Continuation::new(hb, opts, None).expect("continuation");
        let (start, _) = cont.start().expect("start");
        let nu = cont.hb.n_unknowns();
        // `∂R/∂A` and `∂R/∂ω` at a point
        let jacobians = |cont: &Continuation<'_>, a: &[f64], w: f64| {
            let mut r = vec![0.0; nu];
            let parts = cont.hb.residual_jacobian(a, w, &mut r).expect("J");
            let mut r_omega = vec![0.0; nu];
            cont.hb
                .d_residual_d_omega_from(a, w, &r, &mut r_omega)
                .expect("dR/dω");
            (parts, r_omega)
        };
        // a nearby point, and the start's Jacobian bordered with its tangent's row
        let c = cont.correct(&start, 0.005).expect("corrects");
        let (_, m, _) = cont
            .tangent_factored(
                &start.a,
                start.omega,
                Some(&start.tangent),
                None,
                None,
                true,
            )
            .expect("tangent at the start");
        let m = m.expect("bordered matrix");
        let fresh = cont
            .tangent(&c.a, c.omega, Some(&start.tangent), None, None)
            .expect("fresh tangent");
        let refined = cont
            .tangent(&c.a, c.omega, Some(&start.tangent), None, Some(m.clone()))
            .expect("refined tangent");
        let diff = fresh
            .iter()
            .zip(&refined)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(diff < 1e-8, "refined and fresh tangents differ by {diff:e}");
        // the refinement itself converged (no fallback to a factorization)
        let (parts, r_omega) = jacobians(&cont, &c.a, c.omega);
        let row = cont.arc_row(&start.tangent);
        let corner = start.tangent[nu] / cont.scales[nu];
        let sys_at = TangentSystem {
            parts: &parts,
            r_omega: &r_omega,
            row: &row,
            corner,
        };
        assert!(cont.refine_tangent(&m, &sys_at).is_some());
        // a point far along the branch (past the resonance): if the start's matrix is
        // taken there at all, its answer must solve the far system
        let mut reached = false;
        for _ in 0..400 {
            match cont.step().expect("step") {
                StepOutcome::Accepted { point, .. } if point.solution.omega > 1.3 => {
                    let a = point.solution.unknowns();
                    let (parts, r_omega_far) = jacobians(&cont, &a, point.solution.omega);
                    let sys_far = TangentSystem {
                        parts: &parts,
                        r_omega: &r_omega_far,
                        row: &row,
                        corner,
                    };
                    if let Some((z, zeta, _)) = cont.refine_tangent(&m, &sys_far) {
                        let mut jz = vec![0.0; nu];
                        cont.hb.apply_jacobian(&parts, &z, &mut jz);
                        let res = jz
                            .iter()
                            .zip(&r_omega_far)
                            .map(|(j, c)| (j + c * zeta).abs())
                            .fold(0.0, f64::max);
                        let size = jz.iter().map(|v| v.abs()).fold(0.0, f64::max);
                        assert!(res <= 1e-6 * size.max(1e-300), "residual {res:e}");
                    }
                    reached = true;
                    break;
                }
                StepOutcome::Accepted { .. } | StepOutcome::Rejected(_) => {}
                StepOutcome::Finished(_) => break,
            }
        }
        assert!(reached, "the branch reaches past the resonance");
    }
}
