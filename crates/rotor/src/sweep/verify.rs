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

/// Steps of the second pass over a window where an event seemed to vanish: the
/// continuation's largest step divided by this.
const FINE_STEP_DIVISOR: f64 = 16.0;

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
    /// which locates the folds alone); what it located and where the stable flag changed.
    fn follow(
        &self,
        problem: &SweepProblem,
        method: Option<&dyn crate::stability::StabilityMethod>,
    ) -> Result<Found, String> {
        let p = self
            .start
            .ok_or_else(|| "no recorded point before the group".to_string())?;
        let guess = embed(
            p.coeffs_mech,
            p.coeffs_therm,
            self.recorded_basis.unwrap_or(&problem.basis),
            &problem.basis,
        );
        let branch = problem
            .continuation_within(
                p.omega_rad_s,
                self.end,
                self.bounds,
                Some(guess),
                method,
                self.max_points,
            )
            .map_err(|e| e.to_string())
            .and_then(|mut c| c.run(|_| {}).map_err(|e| e.to_string()))?;
        // the folds also from the branch's shape: where ω turns back between points with
        // no fold located on those steps (a fold the location did not report still turns
        // the branch)
        let located: Vec<(BifurcationKind, f64)> = branch
            .bifurcations
            .iter()
            .filter_map(|b| b.bifurcation.map(|k| (k, b.solution.omega)))
            .collect();
        let turns: Vec<(BifurcationKind, f64)> = branch
            .points
            .windows(3)
            .filter_map(|q| {
                let (a, b, c) = (
                    q[0].solution.omega,
                    q[1].solution.omega,
                    q[2].solution.omega,
                );
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                let seen = located
                    .iter()
                    .any(|&(k, w)| k == BifurcationKind::SaddleNode && w >= lo && w <= hi);
                ((b - a) * (c - b) < 0.0 && !seen).then_some((BifurcationKind::SaddleNode, b))
            })
            .collect();
        Ok(Found {
            bifurcations: located.into_iter().chain(turns).collect(),
            changes: branch
                .points
                .windows(2)
                .filter_map(|q| {
                    let a = q[0].stability.as_ref()?.stable;
                    let b = q[1].stability.as_ref()?.stable;
                    (a != b).then_some(0.5 * (q[0].solution.omega + q[1].solution.omega))
                })
                .collect(),
        })
    }
}

/// What a window's continuation found: located bifurcations (kind, ω) and changes of the
/// stable flag between consecutive points (ω between them).
struct Found {
    bifurcations: Vec<(BifurcationKind, f64)>,
    changes: Vec<f64>,
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

impl Checking<'_> {
    /// The outcomes of group `g` (indices into the events) at order `o`: its window
    /// followed from the recorded point before it, again with a finer step where an event
    /// seemed to vanish.
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
        // the start: walking back along the branch from the group's first event while
        // the points stay inside the window (the branch may pass the same speeds on
        // another sheet earlier), the first point at least half a window from each
        // event, else the earliest of that stretch, else the point just before
        let before: Vec<&StartPoint> = self
            .points
            .iter()
            .filter(|p| p.index <= first_after)
            .collect();
        let stretch: Vec<&StartPoint> = before
            .iter()
            .rev()
            .take_while(|p| p.omega_rad_s >= lo - w && p.omega_rad_s <= hi + w)
            .copied()
            .collect();
        let start = stretch
            .iter()
            .find(|p| omegas.iter().all(|o| (p.omega_rad_s - o).abs() >= 0.5 * w))
            .or_else(|| stretch.last())
            .or_else(|| before.last())
            .copied();
        // the branch is followed until it leaves the window, which holds the start
        let bounds = start.map(|p| ((lo - w).min(p.omega_rad_s), (hi + w).max(p.omega_rad_s)));
        // the way the recorded branch runs from the start point (it may be running
        // back after a fold)
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
        // a group of saddle-nodes alone is matched by the folds of the window's branch,
        // which its corrector locates without multipliers: no stability there
        let folds_only = g
            .iter()
            .all(|&i| self.events[i].kind == Some(BifurcationKind::SaddleNode));
        let method = (!folds_only).then_some(o.method.as_ref());
        let t0 = Instant::now();
        // where the window starts, for the progress lines
        let from = start.map_or(lo - w, |p| p.omega_rad_s);
        let window = Window {
            start,
            end,
            bounds,
            recorded_basis: self.recorded_basis,
            max_points: self.options.max_points,
        };
        let mut found: Result<Found, String> = if (self.interrupted)() {
            Err("not reached: the sweep was interrupted".to_string())
        } else if self.started.elapsed().as_secs_f64() > self.options.max_seconds {
            Err(format!(
                "not reached within the check's budget of {} s (verify_max_seconds)",
                self.options.max_seconds
            ))
        } else {
            if let Some(p) = start {
                say(&format!(
                    "order {order}: ω {:.3} → {:.3} rad/s from point {}",
                    p.omega_rad_s, end, p.index
                ));
            }
            window.follow(&o.problem, method)
        };
        // A fold pair or a crossing narrower than a step is passed over unseen: before
        // an event is called vanished, the window is followed again with
        // 1/FINE_STEP_DIVISOR of the step.
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
        if !missing.is_empty() && !(self.interrupted)() {
            let mut fine = o.settings.clone();
            fine.sweep.ds_max /= FINE_STEP_DIVISOR;
            let fine_problem = SweepProblem::with_model(&fine, self.model.clone())?;
            say(&format!(
                "order {order}, window {from:.3} → {end:.3}: {} not found; again with a step of {:.4}",
                missing.join(", "),
                fine.sweep.ds_max
            ));
            let again = Window {
                max_points: self.options.max_points * FINE_STEP_DIVISOR as usize,
                ..window
            }
            .follow(&fine_problem, method);
            if again.is_ok() {
                found = again;
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
