//! The events of a run's branch re-solved at higher truncation orders: does each located
//! bifurcation, and each change of stability the sweep could not locate, hold (its ω and
//! kind within a tolerance), move, or vanish?
//!
//! For each group of events (those closer than two windows to each other) and each order,
//! the branch is followed again on that order's basis from the recorded point a window
//! before the group (its coefficients carried over to the larger basis, the new harmonics
//! zero) to a window past it, with the run's stability method (without stability for a
//! group of saddle-nodes alone: the folds are located from the branch, and stability
//! there would be most of the window's cost). A located bifurcation is
//! matched to the nearest one of its kind found there; an unlocated change of stability to
//! the nearest change of the stable flag between two points, or any bifurcation located
//! there. The sweep runs this by default after its branch ([`super::SweepProblem::run`],
//! study keys `verify`, `verify_orders`, `verify_max_seconds`) and records the verdicts on
//! `/truncation`; `replay verify` runs it on a recording at orders of the user's choice.

use std::time::Instant;

use crate::continuation::{BranchPoint, ContinuationError, FinishReason};
use crate::hb::Basis;
use crate::model::Model;
use crate::record::{TruncationCheck, TruncationOutcome};
use crate::stability::BifurcationKind;
use crate::study::stability_method;

use super::{StudySettings, SweepError, SweepProblem};

/// Settings of [`verify_events`].
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyOptions {
    /// Truncation orders to re-solve at (default: the recorded order + 1 and + 2).
    pub orders: Vec<u32>,
    /// Half-width of the ω window around each group of events, rad/s (default 1).
    pub window_rad_s: f64,
    /// An event whose ω moved by at most this is converged, rad/s (default 0.05: the
    /// scale of the step-size dependence of the located points on the dual rotor).
    pub tolerance_rad_s: f64,
    /// Most points of one window's continuation (default 400).
    pub max_points: usize,
    /// Wall-time budget, s: windows not started within it are reported as failed ("not
    /// reached"). Default: no limit.
    pub max_seconds: f64,
}

impl VerifyOptions {
    /// The defaults for a run recorded at truncation order `order`.
    pub fn for_order(order: u32) -> Self {
        Self {
            orders: (order + 1..=order + 2).filter(|&k| k <= 12).collect(),
            window_rad_s: 1.0,
            tolerance_rad_s: 0.05,
            max_points: 400,
            max_seconds: f64::INFINITY,
        }
    }

    /// The options a sweep with `settings` checks its branch with.
    pub fn for_settings(settings: &StudySettings) -> Self {
        let f = &settings.floquet;
        Self {
            orders: f.verify_orders_for(settings.harmonic.order),
            max_seconds: f.verify_max_seconds,
            ..Self::for_order(settings.harmonic.order)
        }
    }
}

/// A recorded point of the run's branch a window may start from.
#[derive(Clone, Copy, Debug)]
pub struct StartPoint<'a> {
    pub index: u64,
    pub omega_rad_s: f64,
    /// Coefficients on the recorded basis (mechanical blocks, then thermal).
    pub coeffs_mech: &'a [f64],
    pub coeffs_therm: &'a [f64],
}

/// An event of the run's branch to check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// Its number on `/bifurcations` (0 for an unlocated change).
    pub number: u32,
    /// The bifurcation's kind; `None` for a change of stability the sweep did not locate.
    pub kind: Option<BifurcationKind>,
    /// Where the sweep put it (the middle of the step for an unlocated change), rad/s.
    pub omega_rad_s: f64,
    /// The branch point just before it.
    pub after_point: u64,
}

/// Steps of the finest pass over a window where an event seemed to vanish: the
/// continuation's largest step divided by this. It is reached in levels, each
/// [`LEVEL_DIVISOR`] times finer than the one before, every level following again only the
/// stretches of the one before where a change may still hide ([`stretches_to_refine`]).
const FINE_STEP_DIVISOR: f64 = 16.0;

/// How much finer each level of the finer pass is than the one before (see
/// [`FINE_STEP_DIVISOR`]).
const LEVEL_DIVISOR: f64 = 4.0;

/// One window of the check: the branch followed from `start` to `end` within `bounds`.
#[derive(Clone, Copy)]
struct Window<'a> {
    start: Option<&'a StartPoint<'a>>,
    end: f64,
    bounds: Option<(f64, f64)>,
    recorded_basis: Option<&'a Basis>,
    max_points: usize,
}

impl Window<'_> {
    /// Follows the window on `problem`'s basis with `method` (`None`: without stability,
    /// which locates the folds alone): the branch and the scales its arclength is
    /// measured in.
    fn follow(
        &self,
        problem: &SweepProblem,
        method: Option<&dyn crate::stability::StabilityMethod>,
    ) -> Result<Traced, Unfollowed> {
        let p = self
            .start
            .ok_or_else(|| Unfollowed::Other("no recorded point before the group".to_string()))?;
        let guess = embed(
            p.coeffs_mech,
            p.coeffs_therm,
            self.recorded_basis.unwrap_or(&problem.basis),
            &problem.basis,
        );
        let opts = problem.continuation_options(
            p.omega_rad_s,
            self.end,
            self.bounds,
            Some(guess),
            self.max_points,
        );
        Traced::follow(problem, opts, method)
    }

    /// Follows again the stretches of `first` (this window's branch) where a crossing may
    /// hide between two of its points ([`stretches_to_refine`]), at each of `levels` in
    /// turn ([`Self::stretch_found`]). What the window found: `first`'s findings outside
    /// the stretches, the finer passes' inside them (`first`'s alone when there are no
    /// levels); an error when a stretch is not covered at any level.
    fn refine(
        &self,
        first: &Traced,
        levels: &[SweepProblem],
        method: Option<&dyn crate::stability::StabilityMethod>,
        stretches: &[(usize, usize)],
    ) -> Result<Found, Refining> {
        if levels.is_empty() {
            return Ok(first.found());
        }
        let in_stretch = |step: usize| stretches.iter().any(|&(i, j)| step >= i && step <= j);
        let mut found = first.found_outside(&in_stretch);
        for &(i, j) in stretches {
            found.extend(self.stretch_found(first, levels, method, i, j)?);
        }
        Ok(found)
    }

    /// What the stretch of `first` from point `i` to point `j + 1` holds: followed with
    /// the first of `levels`, and the stretches of that pass where a change may still
    /// hide with the next ones ([`Self::refine`]). Where a finer pass fails, this level's
    /// findings stand; where it is not covered (this level's path jumped between sheets
    /// within a step), the stretch is followed again at the next level directly.
    fn stretch_found(
        &self,
        first: &Traced,
        levels: &[SweepProblem],
        method: Option<&dyn crate::stability::StabilityMethod>,
        i: usize,
        j: usize,
    ) -> Result<Found, Refining> {
        let Some((fine, finer)) = levels.split_first() else {
            return Err(Refining::Failed("no finer level".to_string()));
        };
        let segment = self.follow_stretch(first, fine, method, i, j)?;
        let within = stretches_to_refine(&segment, method.is_some());
        if finer.is_empty() || within.is_empty() {
            return Ok(segment.found());
        }
        match self.refine(&segment, finer, method, &within) {
            Ok(f) => Ok(f),
            Err(Refining::Failed(_)) => Ok(segment.found()),
            Err(Refining::NotCovered(_)) => self.stretch_found(first, finer, method, i, j),
        }
    }

    /// The stretch of `first` from point `i` to point `j + 1` followed on `fine`'s
    /// smaller step: from point `i`, oriented along the chord to the next, in `first`'s
    /// arclength scales, until it has passed point `j + 1` (close to it, beyond the plane
    /// through it across the last step's chord); an error when it does not get there.
    fn follow_stretch(
        &self,
        first: &Traced,
        fine: &SweepProblem,
        method: Option<&dyn crate::stability::StabilityMethod>,
        i: usize,
        j: usize,
    ) -> Result<Traced, Refining> {
        let points = &first.branch.points;
        // a point's unknowns, then ω
        let x = |b: &BranchPoint| -> Vec<f64> {
            let mut v = b.solution.unknowns();
            v.push(b.solution.omega);
            v
        };
        let scaled = |a: &[f64], b: &[f64]| -> Vec<f64> {
            a.iter()
                .zip(b)
                .zip(&first.scales)
                .map(|((u, v), s)| (u - v) / s)
                .collect()
        };
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(u, v)| u * v).sum::<f64>();
        let start = x(&points[i]);
        let end = x(&points[j + 1]);
        // the stretch's last step, along which the fine pass is seen to pass its end
        let along = scaled(&end, &x(&points[j]));
        let span = points[j + 1].arclength - points[i].arclength;
        let mut opts = fine.continuation_options(
            points[i].solution.omega,
            self.end,
            self.bounds,
            Some(start[..start.len() - 1].to_vec()),
            (j + 1 - i) * 2 * LEVEL_DIVISOR as usize + 16,
        );
        // how close to the stretch's end a point past it must be: the fine pass
        // solves the same equations, so on the same sheet it passes through that
        // point, and its first point past it lies within a fine step (along the
        // tangent, and the corrector's reach across it); twice that
        let mcd = opts.max_corrector_distance;
        let reach = 2.0 * (1.0 + mcd * mcd).sqrt() * opts.ds_max;
        // oriented along the first pass's chord (the window's end decides only the
        // count of folds passed, as in the first pass)
        opts.start_direction = Some(
            x(&points[i + 1])
                .iter()
                .zip(&start)
                .map(|(b, a)| b - a)
                .collect(),
        );
        opts.scales = Some(first.scales.clone());
        let passed = |b: &BranchPoint| {
            let d = scaled(&x(b), &end);
            dot(&d, &along) >= 0.0 && dot(&d, &d).sqrt() <= reach && b.arclength >= 0.5 * span
        };
        let segment = Traced::follow_until(fine, opts, method, passed)
            .map_err(|e| Refining::Failed(e.into()))?;
        // a stretch the finer pass did not cover is no evidence either way
        let covered = match (&segment.branch.finish, &first.branch.finish) {
            (FinishReason::Stopped { .. }, _) => true,
            // the stretch ends where the first pass reached the window's bound
            (FinishReason::Bound { omega: a }, FinishReason::Bound { omega: b }) => {
                j + 2 == points.len() && a == b
            }
            _ => false,
        };
        if !covered {
            return Err(Refining::NotCovered(format!(
                "the finer pass over steps {i}–{j} did not reach point {}: {}",
                j + 1,
                segment.branch.finish
            )));
        }
        Ok(segment)
    }

    /// What the window's branch `first` found, with its `stretches` where a change may
    /// hide ([`stretches_to_refine`]) followed again at each of `levels` in turn
    /// ([`Self::refine`]). Where a stretch is not covered (a pass jumped between sheets of
    /// the branch within a step), the whole window is followed again at the first level,
    /// and its stretches refined at the next ones (down to the whole window at the finest
    /// level). `max_points` bounds the coarse pass: a level's whole window may take
    /// proportionally more. An error when a finer pass failed (the first pass's findings
    /// stand).
    fn deepen(
        &self,
        first: &Traced,
        stretches: &[(usize, usize)],
        levels: &[SweepProblem],
        method: Option<&dyn crate::stability::StabilityMethod>,
        interrupted: &dyn Fn() -> bool,
        note: &dyn Fn(String),
    ) -> Result<Found, String> {
        let Some((fine, finer)) = levels.split_first() else {
            return Ok(first.found());
        };
        if stretches.is_empty() {
            return Ok(first.found());
        }
        match self.refine(first, levels, method, stretches) {
            Ok(f) => Ok(f),
            Err(Refining::Failed(e)) => Err(e),
            Err(Refining::NotCovered(_)) if interrupted() => {
                Err("the sweep was interrupted".to_string())
            }
            Err(Refining::NotCovered(e)) => {
                note(format!(
                    "{e}; the whole window again with a step of {:.4}",
                    fine.settings.sweep.ds_max
                ));
                let wider = Window {
                    max_points: self.max_points * LEVEL_DIVISOR as usize,
                    ..*self
                };
                let whole = wider.follow(fine, method).map_err(String::from)?;
                let stretches = stretches_to_refine(&whole, method.is_some());
                wider.deepen(&whole, &stretches, finer, method, interrupted, note)
            }
        }
    }
}

/// How many recorded points further back a window may start from when the higher order
/// has no solution near a start point's coefficients.
const MAX_START_RETRIES: usize = 3;

/// Starts tried before the window when none inside it has a solution of the higher order
/// near its coefficients: the first recorded points these many windows' width from the
/// events (see [`start_candidates`]). On W2 the fold at 541.00 rad/s and on W5 nine
/// saddle-nodes went unchecked at orders 4 and 5 because every start inside the window
/// failed (the higher order's solution there lies far from the recorded one); W2's fold
/// starts at two, four of W5's at two or three, and W5's five folds near 499 rad/s at five
/// windows' width. A start that fails costs one Newton solve.
const OUTSIDE_STARTS_WINDOWS: [f64; 4] = [2.0, 3.0, 5.0, 8.0];

/// Where a group's window may start, in the order tried: walking back along the branch
/// from the group's first event (`before`: the recorded points up to it, in branch order)
/// while the points stay inside the window (the branch may pass the same speeds on
/// another sheet earlier), the first point at least half a window (`w`) from each event
/// (`omegas`), then up to [`MAX_START_RETRIES`] further back inside the window (further
/// from the events as the branch runs there, though not necessarily in ω); else the
/// earliest of that stretch; else the point just before. Then, walking on back past the
/// window for as long as ω moves away from the events (no fold between, so the same
/// sheet), the first points [`OUTSIDE_STARTS_WINDOWS`] windows' width from the events.
fn start_candidates<'p>(
    before: &[&'p StartPoint<'p>],
    omegas: &[f64],
    w: f64,
) -> Vec<&'p StartPoint<'p>> {
    let lo = omegas.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = omegas.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let stretch: Vec<&StartPoint> = before
        .iter()
        .rev()
        .take_while(|p| p.omega_rad_s >= lo - w && p.omega_rad_s <= hi + w)
        .copied()
        .collect();
    let mut starts: Vec<&StartPoint> = match stretch
        .iter()
        .position(|p| omegas.iter().all(|o| (p.omega_rad_s - o).abs() >= 0.5 * w))
    {
        Some(i) => stretch[i..]
            .iter()
            .take(1 + MAX_START_RETRIES)
            .copied()
            .collect(),
        None => stretch
            .last()
            .or_else(|| before.last())
            .copied()
            .into_iter()
            .collect(),
    };
    // past the window: the distance from the events grows at every point (no fold)
    let away = |p: &StartPoint| (lo - p.omega_rad_s).max(p.omega_rad_s - hi);
    let mut last = stretch.last().map_or(0.0, |p| away(p));
    let mut wanted = OUTSIDE_STARTS_WINDOWS.iter().map(|k| k * w).peekable();
    for p in before[..before.len() - stretch.len()].iter().rev() {
        let d = away(p);
        let Some(&at) = wanted.peek() else { break };
        if d < last {
            break;
        }
        last = d;
        if d >= at {
            if !starts.iter().any(|q| q.index == p.index) {
                starts.push(p);
            }
            while wanted.next_if(|&k| d >= k).is_some() {}
        }
    }
    starts
}

/// The settings of the finer pass's levels, coarsest first: each with a step
/// [`LEVEL_DIVISOR`] times smaller than the one before, down to the step divided by
/// [`FINE_STEP_DIVISOR`].
fn finer_levels(settings: &StudySettings) -> Vec<StudySettings> {
    let finest = settings.sweep.ds_max / FINE_STEP_DIVISOR;
    let mut levels: Vec<StudySettings> = Vec::new();
    let mut fine = settings.clone();
    while fine.sweep.ds_max > finest * (1.0 + 1e-9) {
        fine.sweep.ds_max = (fine.sweep.ds_max / LEVEL_DIVISOR).max(finest);
        levels.push(fine.clone());
    }
    levels
}

/// Why [`Window::refine`] gave no findings.
enum Refining {
    /// A stretch's finer pass did not reach the stretch's end: the first pass's path is
    /// no guide there (the whole window is followed again).
    NotCovered(String),
    /// A finer pass failed (its start, a setting): the first pass's findings stand.
    Failed(String),
}

/// Why a window's branch was not followed.
enum Unfollowed {
    /// No solution of the window's order near the start point's coefficients (carried
    /// over from the recorded order): next to a fold that moved at the higher order the
    /// start's sheet may end before its ω.
    Start(String),
    /// Any other failure (a setting, a step, the interrupt).
    Other(String),
}

impl From<Unfollowed> for String {
    fn from(u: Unfollowed) -> String {
        match u {
            Unfollowed::Start(m) | Unfollowed::Other(m) => m,
        }
    }
}

/// A window's branch and the scales of its arclength.
struct Traced {
    branch: crate::continuation::Branch,
    scales: Vec<f64>,
}

impl Traced {
    fn follow(
        problem: &SweepProblem,
        opts: crate::continuation::ContinuationOptions,
        method: Option<&dyn crate::stability::StabilityMethod>,
    ) -> Result<Self, Unfollowed> {
        Self::follow_until(problem, opts, method, |_| false)
    }

    /// [`Self::follow`], ending after the first point for which `stop` is true.
    fn follow_until(
        problem: &SweepProblem,
        opts: crate::continuation::ContinuationOptions,
        method: Option<&dyn crate::stability::StabilityMethod>,
        stop: impl FnMut(&BranchPoint) -> bool,
    ) -> Result<Self, Unfollowed> {
        let mut c = problem
            .continuation_with(opts, method)
            .map_err(|e| Unfollowed::Other(e.to_string()))?;
        let branch = c.run_until(|_| {}, stop).map_err(|e| match e {
            ContinuationError::Start { .. } => Unfollowed::Start(e.to_string()),
            e => Unfollowed::Other(e.to_string()),
        })?;
        Ok(Self {
            branch,
            scales: c.scales().to_vec(),
        })
    }

    /// Everything the branch found (see [`Found`]).
    fn found(&self) -> Found {
        self.found_outside(&|_| false)
    }

    /// The step (from point `k` to `k + 1`) that arclength `s` lies on.
    fn step_at(&self, s: f64) -> usize {
        let p = &self.branch.points;
        p.windows(2)
            .position(|q| s <= q[1].arclength)
            .unwrap_or(p.len().saturating_sub(2))
    }

    /// What the branch found (see [`Found`]), leaving out what lies on the steps
    /// `skip` names.
    fn found_outside(&self, skip: &dyn Fn(usize) -> bool) -> Found {
        let points = &self.branch.points;
        // the folds also from the branch's shape: where ω turns back between points with
        // no fold located on those steps (a fold the location did not report still turns
        // the branch)
        let located: Vec<(BifurcationKind, f64, usize)> = self
            .branch
            .bifurcations
            .iter()
            .filter_map(|b| {
                b.bifurcation
                    .map(|k| (k, b.solution.omega, self.step_at(b.arclength)))
            })
            .collect();
        let turns: Vec<(BifurcationKind, f64, usize)> = points
            .windows(3)
            .enumerate()
            .filter_map(|(k, q)| {
                let (a, b, c) = (
                    q[0].solution.omega,
                    q[1].solution.omega,
                    q[2].solution.omega,
                );
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                let seen = located
                    .iter()
                    .any(|&(kind, w, _)| kind == BifurcationKind::SaddleNode && w >= lo && w <= hi);
                // the turn at point k + 1 lies on the steps k and k + 1
                ((b - a) * (c - b) < 0.0 && !seen && !skip(k) && !skip(k + 1)).then_some((
                    BifurcationKind::SaddleNode,
                    b,
                    k,
                ))
            })
            .collect();
        Found {
            bifurcations: located
                .into_iter()
                .filter(|&(_, _, k)| !skip(k))
                .chain(turns)
                .map(|(kind, w, _)| (kind, w))
                .collect(),
            changes: points
                .windows(2)
                .enumerate()
                .filter_map(|(k, q)| {
                    let a = q[0].stability.as_ref()?.stable;
                    let b = q[1].stability.as_ref()?.stable;
                    (a != b && !skip(k))
                        .then_some(0.5 * (q[0].solution.omega + q[1].solution.omega))
                })
                .collect(),
        }
    }
}

/// The stretches of a branch where a change may hide between two points, as runs of
/// steps `(i, j)` (from point `i` to point `j + 1`):
/// - the steps on which a bifurcation was located or ω turns back;
/// - where the slope `Δω/Δs` of a step keeps its sign but comes close to zero between
///   steps where it is steeper (a fold pair within the step turns ω back and forth and
///   flattens the chord): closer than the sum of its changes to the two steps beside
///   it; that step and its flatter neighbour;
/// - with `stability`: where the stable flag changes or a point has no stability, and
///   where the largest distance outside the unit circle of a family of multipliers
///   ([`crate::continuation::family_margins`], and of all of them) changes sign, or
///   comes close to zero and turns back at a point: closer than the sum of its changes
///   over the two steps beside it, which bounds how far a peak between samples can rise
///   above the sample (a parabola through the three rises by at most an eighth of it).
///
/// The closeness rule is the same for both: a sampled extremum `b` between `a` and `c`
/// is close when `|b| < |b − a| + |c − b|`.
fn stretches_to_refine(t: &Traced, stability: bool) -> Vec<(usize, usize)> {
    let points = &t.branch.points;
    let n = points.len();
    if n < 2 {
        return Vec::new();
    }
    // a sampled turn of `b` towards zero (same sign as its neighbours, or at most zero
    // from the side of `a`) that may reach it between the samples
    let close = |a: f64, b: f64, c: f64| {
        let reach = (b - a).abs() + (c - b).abs();
        let finite = a.is_finite() && b.is_finite() && c.is_finite();
        finite
            && ((b >= a && b >= c && b <= 0.0 && -b < reach)
                || (b <= a && b <= c && b > 0.0 && b < reach))
    };
    let mut flag = vec![false; n - 1];
    for b in &t.branch.bifurcations {
        flag[t.step_at(b.arclength)] = true;
    }
    let w = |i: usize| points[i].solution.omega;
    let slope = |k: usize| (w(k + 1) - w(k)) / (points[k + 1].arclength - points[k].arclength);
    for k in 1..n - 1 {
        if (w(k) - w(k - 1)) * (w(k + 1) - w(k)) < 0.0 {
            flag[k - 1] = true;
            flag[k] = true;
        }
    }
    for k in 1..n.saturating_sub(2) {
        let (a, b, c) = (slope(k - 1), slope(k), slope(k + 1));
        // the flattest of three steps running the same way, as a turn of |slope|
        if a * b > 0.0 && b * c > 0.0 && close(-a.abs(), -b.abs(), -c.abs()) {
            flag[k] = true;
            flag[if a.abs() < c.abs() { k - 1 } else { k + 1 }] = true;
        }
    }
    if !stability {
        return runs(&flag);
    }
    let margins: Vec<Option<[f64; 5]>> = points
        .iter()
        .map(|p| {
            p.stability.as_ref().map(|f| {
                let m = crate::continuation::family_margins(f);
                let all = m.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                [m[0], m[1], m[2], m[3], all]
            })
        })
        .collect();
    for k in 0..n - 1 {
        let (a, b) = (points[k].stable(), points[k + 1].stable());
        if a.is_none() || b.is_none() || a != b {
            flag[k] = true;
        }
        if let (Some(ga), Some(gb)) = (margins[k], margins[k + 1])
            && ga
                .iter()
                .zip(&gb)
                .any(|(x, y)| x.is_finite() && y.is_finite() && x * y <= 0.0)
        {
            flag[k] = true;
        }
    }
    for k in 1..n - 1 {
        if let (Some(g0), Some(g1), Some(g2)) = (margins[k - 1], margins[k], margins[k + 1])
            && (0..5).any(|f| close(g0[f], g1[f], g2[f]))
        {
            flag[k - 1] = true;
            flag[k] = true;
        }
    }
    runs(&flag)
}

/// The runs of set entries of `flag`, as `(first, last)` index pairs.
fn runs(flag: &[bool]) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    for (k, _) in flag.iter().enumerate().filter(|(_, f)| **f) {
        match out.last_mut() {
            Some((_, j)) if *j + 1 == k => *j = k,
            _ => out.push((k, k)),
        }
    }
    out
}

/// What a window's continuation found: located bifurcations (kind, ω) and changes of the
/// stable flag between consecutive points (ω between them).
struct Found {
    bifurcations: Vec<(BifurcationKind, f64)>,
    changes: Vec<f64>,
}

impl Found {
    fn extend(&mut self, other: Found) {
        self.bifurcations.extend(other.bifurcations);
        self.changes.extend(other.changes);
    }
}

/// Re-solves `events` of a run (settings `settings`, model `model`, recorded on
/// `recorded_basis`, its branch's points `points` in index order) at `options.orders`
/// (see the module docs), telling `progress` what it does; `interrupted` is polled between
/// windows. One [`TruncationCheck`] per event, in the order given. The windows (every
/// group at every order) are independent and run in parallel on the current rayon pool;
/// each one's outcome is the same as it would be alone.
#[allow(clippy::too_many_arguments)]
pub fn verify_events(
    settings: &StudySettings,
    model: &Model,
    recorded_basis: Option<&Basis>,
    points: &[StartPoint<'_>],
    events: &[Event],
    options: &VerifyOptions,
    progress: impl FnMut(&str) + Send,
    interrupted: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<TruncationCheck>, SweepError> {
    use rayon::prelude::*;
    let ascending = settings.sweep.omega_end >= settings.sweep.omega_start;
    let w = options.window_rad_s;
    // groups of events closer than two windows to each other, in branch order
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, e) in events.iter().enumerate() {
        match groups.last_mut() {
            Some(g)
                if g.iter()
                    .any(|&j| (events[j].omega_rad_s - e.omega_rad_s).abs() < 2.0 * w) =>
            {
                g.push(i)
            }
            _ => groups.push(vec![i]),
        }
    }
    let mut checks: Vec<TruncationCheck> = events
        .iter()
        .map(|e| TruncationCheck {
            number: e.number,
            kind: e.kind,
            omega_rad_s: e.omega_rad_s,
            after_point: e.after_point,
            recorded_order: settings.harmonic.order,
            window_rad_s: w,
            tolerance_rad_s: options.tolerance_rad_s,
            orders: Vec::new(),
        })
        .collect();
    let orders = options
        .orders
        .iter()
        .map(|&order| {
            let mut s = settings.clone();
            s.harmonic.order = order;
            if order != settings.harmonic.order {
                s.harmonic.aft_samples = None;
            }
            let problem = SweepProblem::with_model(&s, model.clone())?;
            let method = stability_method(&s, &problem.system, s.sweep.omega_start)
                .map_err(|e| SweepError::Derive(e.to_string()))?;
            Ok(AtOrder {
                order,
                settings: s,
                problem,
                method,
            })
        })
        .collect::<Result<Vec<_>, SweepError>>()?;
    let progress = std::sync::Mutex::new(progress);
    let c = Checking {
        model,
        recorded_basis,
        points,
        events,
        options,
        started: Instant::now(),
        sign: if ascending { 1.0 } else { -1.0 },
        interrupted,
        progress: &|m: &str| {
            if let Ok(mut p) = progress.lock() {
                p(m)
            }
        },
    };
    let windows: Vec<(usize, usize)> = (0..orders.len())
        .flat_map(|o| (0..groups.len()).map(move |g| (o, g)))
        .collect();
    let outcomes = windows
        .par_iter()
        .map(|&(o, g)| c.group(&orders[o], &groups[g]))
        .collect::<Result<Vec<_>, SweepError>>()?;
    // in order and group order, as one window after the other would give them
    for (&(o, g), outs) in windows.iter().zip(outcomes) {
        for (&i, out) in groups[g].iter().zip(outs) {
            checks[i].orders.push((orders[o].order, out));
        }
    }
    Ok(checks)
}

/// One truncation order of the check: its settings, problem and stability method.
struct AtOrder {
    order: u32,
    settings: StudySettings,
    problem: SweepProblem,
    method: Box<dyn crate::stability::StabilityMethod>,
}

/// What every window of a check reads.
struct Checking<'a> {
    model: &'a Model,
    recorded_basis: Option<&'a Basis>,
    points: &'a [StartPoint<'a>],
    events: &'a [Event],
    options: &'a VerifyOptions,
    started: Instant,
    /// +1 for an ascending sweep, −1 for a descending one.
    sign: f64,
    interrupted: &'a (dyn Fn() -> bool + Sync),
    progress: &'a (dyn Fn(&str) + Sync),
}

impl<'a> Checking<'a> {
    /// The window over a group of events from `lo` to `hi` (rad/s), followed from
    /// `start`: its bounds hold the start and reach a window's width past the events,
    /// and its end is the bound the recorded branch runs towards from the start (it may
    /// be running back after a fold).
    fn window_from(&self, start: Option<&'a StartPoint<'a>>, lo: f64, hi: f64) -> Window<'a> {
        let w = self.options.window_rad_s;
        let bounds = start.map(|p| ((lo - w).min(p.omega_rad_s), (hi + w).max(p.omega_rad_s)));
        let forward = start
            .and_then(|p| {
                self.points
                    .iter()
                    .find(|q| q.index > p.index)
                    .map(|q| q.omega_rad_s >= p.omega_rad_s)
            })
            .unwrap_or(self.sign > 0.0);
        let end = match bounds {
            Some((a, b)) => {
                if forward {
                    b
                } else {
                    a
                }
            }
            None => hi + self.sign * w,
        };
        Window {
            start,
            end,
            bounds,
            recorded_basis: self.recorded_basis,
            max_points: self.options.max_points,
        }
    }

    /// The outcomes of group `g` (indices into the events) at order `o`: its window
    /// followed from a recorded point before it ([`start_candidates`], the next one where
    /// a start fails), again with a finer step where an event seemed to vanish.
    fn group(&self, o: &AtOrder, g: &[usize]) -> Result<Vec<TruncationOutcome>, SweepError> {
        let say = |m: &str| (self.progress)(m);
        let order = o.order;
        let w = self.options.window_rad_s;
        let omegas: Vec<f64> = g.iter().map(|&i| self.events[i].omega_rad_s).collect();
        let lo = omegas.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = omegas.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let first_after = g
            .iter()
            .map(|&i| self.events[i].after_point)
            .min()
            .unwrap_or(0);
        let before: Vec<&StartPoint> = self
            .points
            .iter()
            .filter(|p| p.index <= first_after)
            .collect();
        let starts = start_candidates(&before, &omegas, w);
        // a group of saddle-nodes alone is matched by the folds of the window's branch,
        // which its corrector locates without multipliers: no stability there
        let folds_only = g
            .iter()
            .all(|&i| self.events[i].kind == Some(BifurcationKind::SaddleNode));
        let method = (!folds_only).then_some(o.method.as_ref());
        let t0 = Instant::now();
        let mut window = self.window_from(starts.first().copied(), lo, hi);
        let first: Result<Traced, String> = if (self.interrupted)() {
            Err("not reached: the sweep was interrupted".to_string())
        } else if self.started.elapsed().as_secs_f64() > self.options.max_seconds {
            Err(format!(
                "not reached within the check's budget of {} s (verify_max_seconds)",
                self.options.max_seconds
            ))
        } else {
            // where no solution of this order lies near a start point's coefficients
            // (a fold that moved at this order ends the start's sheet before its ω), the
            // next candidate further back in the window
            let mut next = starts.iter().skip(1);
            loop {
                if let Some(p) = window.start {
                    say(&format!(
                        "order {order}: ω {:.3} → {:.3} rad/s from point {}",
                        p.omega_rad_s, window.end, p.index
                    ));
                }
                match window.follow(&o.problem, method) {
                    Err(Unfollowed::Start(e)) if !(self.interrupted)() => match next.next() {
                        Some(&p) => {
                            say(&format!(
                                "order {order}: {e}; from point {} instead",
                                p.index
                            ));
                            window = self.window_from(Some(p), lo, hi);
                        }
                        None => break Err(e),
                    },
                    r => break r.map_err(String::from),
                }
            }
        };
        // where the window starts, and the bound it runs to, for the progress lines
        let (from, end) = (window.start.map_or(lo - w, |p| p.omega_rad_s), window.end);
        let mut found: Result<Found, String> =
            first.as_ref().map(|t| t.found()).map_err(Clone::clone);
        // A fold pair or a crossing narrower than a step is passed over unseen: before
        // an event is called vanished, the stretches of the window where the first
        // pass's shape (and multipliers, with stability) leave room for one between two
        // points ([`stretches_to_refine`]) are followed again with 1/LEVEL_DIVISOR of the
        // step, and the stretches of those passes that still leave room for one with
        // 1/LEVEL_DIVISOR of theirs, down to 1/FINE_STEP_DIVISOR of the step.
        let missing: Vec<String> = match &found {
            Ok(f) => g
                .iter()
                .zip(match_events(g, self.events, f, self.options))
                .filter(|(_, out)| *out == TruncationOutcome::Vanished)
                .map(|(&i, _)| {
                    let e = &self.events[i];
                    let kind = e.kind.map_or("change", |k| k.abbreviation());
                    format!("{kind} {:.3}", e.omega_rad_s)
                })
                .collect(),
            Err(_) => Vec::new(),
        };
        if let (false, Ok(first)) = (missing.is_empty() || (self.interrupted)(), &first) {
            let stretches = stretches_to_refine(first, method.is_some());
            let steps: usize = stretches.iter().map(|(i, j)| j + 1 - i).sum();
            let note = |m: String| say(&format!("order {order}, window {from:.3} → {end:.3}: {m}"));
            if stretches.is_empty() {
                note(format!(
                    "{} not found, and no step where it could hide",
                    missing.join(", ")
                ));
            } else {
                let levels = finer_levels(&o.settings)
                    .iter()
                    .map(|s| SweepProblem::with_model(s, self.model.clone()))
                    .collect::<Result<Vec<_>, _>>()?;
                let step = |p: Option<&SweepProblem>| p.map_or(0.0, |p| p.settings.sweep.ds_max);
                let (coarsest, fine_step) = (step(levels.first()), step(levels.last()));
                note(format!(
                    "{} not found; again with a step of {coarsest:.4} on {} stretches ({steps} \
                     of {} steps), down to {fine_step:.4} where a change may still hide",
                    missing.join(", "),
                    stretches.len(),
                    first.branch.points.len().saturating_sub(1),
                ));
                match window.deepen(first, &stretches, &levels, method, self.interrupted, &note) {
                    Ok(f) => found = Ok(f),
                    Err(e) => note(format!(
                        "the finer pass failed ({e}); the first pass's findings stand"
                    )),
                }
            }
        }
        say(&format!(
            "order {order}, window {from:.3} → {end:.3}: done in {:.1} s",
            t0.elapsed().as_secs_f64()
        ));
        let outcomes = match &found {
            Err(e) => vec![TruncationOutcome::Failed(e.clone()); g.len()],
            Ok(f) => {
                let listed: Vec<String> = f
                    .bifurcations
                    .iter()
                    .map(|(k, w)| format!("{} {w:.4}", k.abbreviation()))
                    .collect();
                say(&format!("order {order}: located {}", listed.join(", ")));
                match_events(g, self.events, f, self.options)
            }
        };
        Ok(outcomes)
    }
}

/// Matches the events of group `g` one to one with what a window found, the closest pairs
/// first: a located bifurcation with one of its kind, an unlocated change with a change of
/// the stable flag or any located bifurcation, within the window.
fn match_events(
    g: &[usize],
    events: &[Event],
    found: &Found,
    options: &VerifyOptions,
) -> Vec<TruncationOutcome> {
    // candidates: (kind or None for a flag change, ω)
    let candidates: Vec<(Option<BifurcationKind>, f64)> = found
        .bifurcations
        .iter()
        .map(|&(k, w)| (Some(k), w))
        .chain(found.changes.iter().map(|&w| (None, w)))
        .collect();
    // (distance, event, candidate, its ω)
    let mut pairs: Vec<(f64, usize, usize, f64)> = Vec::new();
    for &i in g {
        for (j, &(k, w)) in candidates.iter().enumerate() {
            let d = (w - events[i].omega_rad_s).abs();
            let fits = match events[i].kind {
                Some(kind) => k == Some(kind),
                None => true,
            };
            if fits && d <= options.window_rad_s {
                pairs.push((d, i, j, w));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut taken = Vec::new();
    let mut matched: Vec<(usize, f64)> = Vec::new();
    for (_, i, j, w) in pairs {
        if matched.iter().any(|(m, _)| *m == i) || taken.contains(&j) {
            continue;
        }
        taken.push(j);
        matched.push((i, w));
    }
    g.iter()
        .map(|&i| match matched.iter().find(|(m, _)| *m == i) {
            None => TruncationOutcome::Vanished,
            Some(&(_, w)) => {
                if (w - events[i].omega_rad_s).abs() <= options.tolerance_rad_s {
                    TruncationOutcome::Converged { omega_rad_s: w }
                } else {
                    TruncationOutcome::Moved { omega_rad_s: w }
                }
            }
        })
        .collect()
}

/// Coefficients on basis `from` (mechanical blocks, then thermal, each
/// `[a0, a1..aH, b1..bH]`) carried over to basis `to`: the harmonics both have keep their
/// values, the others are zero.
fn embed(mech: &[f64], therm: &[f64], from: &Basis, to: &Basis) -> Vec<f64> {
    let (nf, nt) = (from.n_coeffs(), to.n_coeffs());
    let (hf, ht) = (from.n_harmonics(), to.n_harmonics());
    let map: Vec<Option<usize>> = from
        .harmonics()
        .iter()
        .map(|r| to.harmonics().iter().position(|q| q == r))
        .collect();
    let blocks = mech.chunks(nf).chain(therm.chunks(nf));
    let mut out = Vec::new();
    for block in blocks {
        let mut b = vec![0.0; nt];
        b[0] = block[0];
        for (h, m) in map.iter().enumerate() {
            if let Some(k) = m {
                b[1 + k] = block[1 + h];
                b[1 + ht + k] = block[1 + hf + h];
            }
        }
        out.extend(b);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::continuation::Branch;
    use crate::hb::{HbSolution, ResidualNorms};
    use crate::stability::FloquetResult;
    use num_complex::Complex64;

    /// A branch at ω = 500 + s (s = 0 … 10, one point per unit of arclength) whose only
    /// multipliers are a complex pair of modulus `modulus[k]` at point `k`.
    fn branch(modulus: &[f64]) -> Traced {
        let omegas: Vec<f64> = (0..modulus.len()).map(|k| 500.0 + k as f64).collect();
        branch_at(&omegas, modulus)
    }

    /// [`branch`] with point `k` at `omegas[k]`.
    fn branch_at(omegas: &[f64], modulus: &[f64]) -> Traced {
        let basis = Basis::integer(1).expect("basis");
        let points = modulus
            .iter()
            .enumerate()
            .map(|(k, &r)| {
                let mut f = FloquetResult::new(vec![
                    Complex64::from_polar(r, 1.0),
                    Complex64::from_polar(r, -1.0),
                ]);
                f.stable = r < 1.0;
                BranchPoint {
                    index: k,
                    arclength: k as f64,
                    solution: HbSolution {
                        omega: omegas[k],
                        basis: basis.clone(),
                        mech: vec![0.0; 3],
                        therm: Vec::new(),
                        residual: ResidualNorms::default(),
                        relative_residual: ResidualNorms::default(),
                        iterations: 1,
                    },
                    stability: Some(f),
                    stability_error: None,
                    bifurcation: None,
                    jacobian: None,
                }
            })
            .collect();
        Traced {
            branch: Branch {
                points,
                bifurcations: Vec::new(),
                finish: FinishReason::MaxPoints,
                rejected_steps: 0,
            },
            scales: vec![1.0; 4],
        }
    }

    /// A pair that comes within 0.004 of the circle at point 3 after rising by 0.006 and
    /// 0.004 on the steps beside it may have crossed and come back between the points:
    /// both steps are refined. A turn 0.05 inside the circle whose steps change it by
    /// 0.01 and 0.02 cannot have; the pair leaving the circle between points 8 and 9
    /// (the stable flag changes) is refined.
    #[test]
    fn the_steps_where_a_pair_may_cross_unseen_are_refined_and_only_they() {
        let t = branch(&[
            0.98, 0.99, 0.990, 0.996, 0.992, 0.96, 0.95, 0.97, 0.99, 1.01, 1.02,
        ]);
        assert_eq!(stretches_to_refine(&t, true), vec![(2, 3), (8, 8)]);
        // an unstable pair that comes back towards the circle and turns away again
        let t = branch(&[
            1.05, 1.04, 1.02, 1.003, 1.01, 1.03, 1.05, 1.06, 1.07, 1.08, 1.09,
        ]);
        assert_eq!(stretches_to_refine(&t, true), vec![(2, 3)]);
        // what the first pass found on a refined step is left to the fine pass
        let t = branch(&[
            0.98, 0.99, 0.990, 0.996, 0.992, 0.96, 0.95, 0.97, 0.99, 1.01, 1.02,
        ]);
        let all = t.found();
        assert_eq!(all.changes, vec![508.5]);
        let outside = t.found_outside(&|k| k == 8);
        assert!(outside.changes.is_empty());
    }

    /// A window starts from the first recorded point half a window before the event, and
    /// where the higher order has no solution there from the points further back inside
    /// the window, at most three of them; then from points two, three, five and eight
    /// windows' width from the event, on the same sheet only.
    #[test]
    fn a_window_starts_half_a_window_back_then_further_back_inside_it() {
        let at = |omegas: &[f64]| -> Vec<StartPoint<'static>> {
            omegas
                .iter()
                .enumerate()
                .map(|(i, &w)| StartPoint {
                    index: i as u64,
                    omega_rad_s: w,
                    coeffs_mech: &[],
                    coeffs_therm: &[],
                })
                .collect()
        };
        let indices = |points: &[StartPoint<'static>], omegas: &[f64]| -> Vec<u64> {
            let before: Vec<&StartPoint> = points.iter().collect();
            start_candidates(&before, omegas, 1.0)
                .iter()
                .map(|p| p.index)
                .collect()
        };
        // the points of W2 before its fold at 541.0 rad/s
        let points = at(&[539.33, 539.70, 540.04, 540.25, 540.44, 540.63, 540.82]);
        assert_eq!(indices(&points, &[541.0]), vec![4, 3, 2]);
        // no more than three further back
        let dense: Vec<f64> = (0..12).map(|k| 540.0 + 0.04 * k as f64).collect();
        assert_eq!(indices(&at(&dense), &[541.0]), vec![11, 10, 9, 8]);
        // every point of the window within half a window of the event: its earliest only
        // (then 539.0, two windows' width from the event)
        assert_eq!(indices(&at(&[539.0, 540.6, 540.8]), &[541.0]), vec![1, 0]);
        // none inside the window: the point just before (and one three windows away)
        assert_eq!(indices(&at(&[538.0, 539.5]), &[541.0]), vec![1, 0]);
        // past the window, the first points two and three windows' width from the event
        let longer = [
            537.9, 538.6, 538.95, 539.33, 539.70, 540.04, 540.25, 540.44, 540.63, 540.82,
        ];
        assert_eq!(indices(&at(&longer), &[541.0]), vec![7, 6, 5, 2, 0]);
        // and five and eight windows' width away
        let run: Vec<f64> = (0..18).map(|k| 532.0 + 0.5 * k as f64).collect();
        assert_eq!(indices(&at(&run), &[541.0]), vec![17, 16, 14, 12, 8, 2]);
        // not past a fold: beyond 538.2 the branch came from higher speeds (another sheet)
        let folded = [537.0, 538.6, 538.2, 539.6, 540.2, 540.6];
        assert_eq!(indices(&at(&folded), &[541.0]), vec![4, 2]);
        // a sweep down: the same on the other side
        let down = [544.1, 543.4, 542.0, 541.6, 541.2];
        assert_eq!(indices(&at(&down), &[540.5]), vec![4, 1, 0]);
    }

    /// The finer pass reaches a sixteenth of the step in two levels of a quarter each.
    #[test]
    fn the_finer_levels_reach_a_sixteenth_of_the_step_by_quarters() {
        let mut settings = StudySettings::default();
        settings.sweep.ds_max = 0.16;
        let steps: Vec<f64> = finer_levels(&settings)
            .iter()
            .map(|s| s.sweep.ds_max)
            .collect();
        assert_eq!(steps.len(), 2);
        assert!((steps[0] - 0.04).abs() < 1e-15 && (steps[1] - 0.01).abs() < 1e-15);
    }

    /// Where a step's slope Δω/Δs drops to a fifth of its neighbours' a fold pair may hide
    /// in it: that step and the next (its neighbours equally steep) are refined, with
    /// stability or without. A slope that eases from 1 to 0.8 and back to 0.9 is a bend,
    /// not room for a fold pair; nor are the multipliers, far inside the circle.
    #[test]
    fn the_steps_where_a_fold_pair_may_hide_are_refined() {
        let at = |steps: &[f64]| -> Vec<f64> {
            let mut w = vec![500.0];
            for d in steps {
                w.push(w[w.len() - 1] + d);
            }
            w
        };
        let inside = [0.5; 7];
        let t = branch_at(&at(&[1.0, 1.0, 0.2, 1.0, 1.0, 1.0]), &inside);
        assert_eq!(stretches_to_refine(&t, false), vec![(2, 3)]);
        assert_eq!(stretches_to_refine(&t, true), vec![(2, 3)]);
        let t = branch_at(&at(&[1.0, 0.9, 0.8, 0.85, 0.9, 1.0]), &inside);
        assert!(stretches_to_refine(&t, false).is_empty());
        assert!(stretches_to_refine(&t, true).is_empty());
        // a turn: the steps on either side of the point where ω turns back
        let t = branch_at(&at(&[1.0, 1.0, 1.0, -1.0, -1.0, -1.0]), &inside);
        assert_eq!(stretches_to_refine(&t, false), vec![(2, 3)]);
    }
}
