//! Nonlinear tuned vibration absorber (Ω ∈ [0.8, 1.4]): Neimark–Sacker points detected,
//! located and classified from Floquet multipliers of the variational equations; time
//! integration just past the first one does not settle on a periodic orbit (the
//! stroboscopic samples spread on a closed curve), while just before it they collapse to
//! a point.

mod engine_support;

use engine_support::{VariationalFloquet, rk4};
use num_complex::Complex64;
use tmrotor::continuation::{Branch, Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{BifurcationKind, FloquetResult, StabilityError, StabilityMethod};
use tmrotor::system::{PeriodicOrbit, System};
use tmrotor::systems::absorber::Absorber;

fn trace() -> Branch {
    let sys = Absorber::default();
    let basis = Basis::integer(7).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let opts = ContinuationOptions::new(0.8, 1.4);
    let floquet = VariationalFloquet { steps: 400 };
    let mut cont = Continuation::new(hb, opts, Some(&floquet)).expect("continuation");
    cont.run(|_| {}).expect("run")
}

/// Spread (max − min) of the stroboscopic samples `x₁(kP)` over `n_record` periods after
/// `n_transient` periods, from the orbit's state at t = 0 scaled by `1 + perturbation`.
fn stroboscopic_spread(
    orbit: &dyn PeriodicOrbit,
    perturbation: f64,
    n_transient: usize,
    n_record: usize,
) -> f64 {
    let sys = Absorber::default();
    let (mut x, mut v) = ([0.0; 2], [0.0; 2]);
    orbit.state_at(0.0, &mut x, &mut v, &mut []);
    let y0: Vec<f64> = x
        .iter()
        .chain(&v)
        .map(|s| s * (1.0 + perturbation))
        .collect();
    let steps = 256;
    let dt = orbit.period() / steps as f64;
    let y = rk4(
        &sys,
        orbit.omega(),
        0.0,
        &y0,
        dt,
        n_transient * steps,
        |_, _| {},
    );
    let mut k = 0usize;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    rk4(
        &sys,
        orbit.omega(),
        0.0,
        &y,
        dt,
        n_record * steps,
        |_, y| {
            k += 1;
            if k.is_multiple_of(steps) {
                lo = lo.min(y[0]);
                hi = hi.max(y[0]);
            }
        },
    );
    hi - lo
}

#[test]
fn neimark_sacker_points_are_located_and_quasi_periodic_past_them() {
    let branch = trace();
    let ns: Vec<_> = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::NeimarkSacker))
        .collect();
    let sn = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::SaddleNode))
        .count();
    assert_eq!(ns.len(), 2, "Neimark–Sacker points: {}", ns.len());
    assert_eq!(sn, 2);
    // at a located NS point a complex pair sits on the unit circle
    for b in &ns {
        let f = b.stability.as_ref().expect("multipliers");
        let pair = f
            .multipliers
            .iter()
            .min_by(|a, c| (a.norm() - 1.0).abs().total_cmp(&(c.norm() - 1.0).abs()))
            .expect("multiplier");
        assert!(
            (pair.norm() - 1.0).abs() < 1e-3,
            "closest |μ| = {}",
            pair.norm()
        );
        assert!(pair.im.abs() > 0.05 * pair.norm(), "μ = {pair}");
    }
    // between the NS points the branch is unstable with exactly two multipliers outside
    let (s1, s2) = (ns[0].arclength, ns[1].arclength);
    let inside: Vec<_> = branch
        .points
        .iter()
        .filter(|p| p.arclength > s1 && p.arclength < s2)
        .collect();
    assert!(inside.len() >= 3);
    for p in &inside {
        let f = p.stability.as_ref().expect("multipliers");
        assert_eq!(f.unstable_count(), 2, "ω = {}", p.solution.omega);
    }
    // time integration: just before NS₁ periodic, just past it not periodic
    let w_ns = ns[0].solution.omega;
    let before = branch
        .points
        .iter()
        .rfind(|p| p.arclength < s1 && p.stable() == Some(true))
        .expect("stable point before");
    let after = inside[0];
    let amp = after.solution.max_abs(0);
    let spread_before = stroboscopic_spread(&before.solution, 0.0, 400, 100);
    let spread_after = stroboscopic_spread(&after.solution, 1e-3, 600, 300);
    eprintln!(
        "NS at ω = {w_ns}; before ω = {}: spread {spread_before:e}; after ω = {}: spread {spread_after:e} (amplitude {amp})",
        before.solution.omega, after.solution.omega
    );
    assert!(spread_before < 1e-4 * amp);
    assert!(spread_after > 1e-2 * amp);
}

#[test]
fn sip_stability_in_the_continuation_locates_the_same_bifurcations() {
    // the library's SIP product (paper Eqs. 30–33) against the RK4 variational reference
    let reference = trace();
    let sys = Absorber::default();
    let basis = Basis::integer(7).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let sip = tmrotor::stability::Sip {
        extrapolate: true,
        ..tmrotor::stability::Sip::default()
    };
    let mut cont =
        Continuation::new(hb, ContinuationOptions::new(0.8, 1.4), Some(&sip)).expect("cont");
    let branch = cont.run(|_| {}).expect("run");
    assert_eq!(branch.bifurcations.len(), reference.bifurcations.len());
    for (a, b) in branch.bifurcations.iter().zip(&reference.bifurcations) {
        assert_eq!(a.bifurcation, b.bifurcation);
        let (wa, wb) = (a.solution.omega, b.solution.omega);
        assert!((wa - wb).abs() < 1e-5 * wb, "{wa} vs {wb}");
    }
}

/// The absorber's multipliers with one more, just below +1: the multiplier of a slow
/// thermal mode, `e^{−P/τ}` with a time constant of minutes against a period of
/// milliseconds, as the coupled rotor has dozens of.
struct WithSlowMode<M>(M);

impl<M: StabilityMethod> StabilityMethod for WithSlowMode<M> {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        let mut f = self.0.multipliers(system, orbit)?;
        f.multipliers.push(Complex64::new(1.0 - 1e-5, 0.0));
        Ok(FloquetResult::new(f.multipliers))
    }
}

#[test]
fn a_slow_multiplier_below_one_does_not_stop_the_crossing_search() {
    // With the modulus tolerance of a sweep, the search for a Neimark–Sacker point must
    // follow the crossing pair, not the largest multiplier: on the stable side that is
    // the slow one at 1 − 1e-5, already within the tolerance of the circle, and a search
    // that ranked all multipliers stopped at its first trial with the pair far inside.
    let sys = Absorber::default();
    let basis = Basis::integer(7).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let opts = ContinuationOptions {
        bifurcation_tol_modulus: 1e-4,
        ..ContinuationOptions::new(0.8, 1.4)
    };
    let floquet = WithSlowMode(VariationalFloquet { steps: 400 });
    let mut cont = Continuation::new(hb, opts, Some(&floquet)).expect("continuation");
    let branch = cont.run(|_| {}).expect("run");
    let ns: Vec<_> = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::NeimarkSacker))
        .collect();
    assert_eq!(ns.len(), 2, "Neimark–Sacker points: {}", ns.len());
    let reference = trace();
    for b in &ns {
        let f = b.stability.as_ref().expect("multipliers");
        let pair = f
            .multipliers
            .iter()
            .filter(|m| m.im.abs() > 0.05 * m.norm())
            .min_by(|a, c| (a.norm() - 1.0).abs().total_cmp(&(c.norm() - 1.0).abs()))
            .expect("a complex pair");
        assert!(
            (pair.norm() - 1.0).abs() <= 1e-4 + 1e-9,
            "ω = {}: closest pair |μ| = {}",
            b.solution.omega,
            pair.norm()
        );
        // and the point is the one found without the slow multiplier
        let w_ref = reference
            .bifurcations
            .iter()
            .filter(|r| r.bifurcation == Some(BifurcationKind::NeimarkSacker))
            .map(|r| r.solution.omega)
            .min_by(|x, y| {
                (x - b.solution.omega)
                    .abs()
                    .total_cmp(&(y - b.solution.omega).abs())
            })
            .expect("reference NS");
        assert!(
            (b.solution.omega - w_ref).abs() < 1e-4 * w_ref,
            "ω = {} against {w_ref}",
            b.solution.omega
        );
    }
}

#[test]
fn the_continuation_accounts_for_its_time() {
    let sys = Absorber::default();
    let basis = Basis::integer(7).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let floquet = VariationalFloquet { steps: 400 };
    let mut cont = Continuation::new(hb, ContinuationOptions::new(0.8, 1.4), Some(&floquet))
        .expect("continuation");
    let start = std::time::Instant::now();
    let branch = cont.run(|_| {}).expect("run");
    let elapsed = start.elapsed().as_secs_f64();
    let t = cont.timings();
    // one corrector step per point after the start and per refused step; one evaluation
    // per accepted point; a search for each of the branch's Neimark–Sacker points
    assert_eq!(
        t.steps,
        branch.points.len() - 1 + branch.rejected_steps,
        "{t:?}"
    );
    assert_eq!(t.evaluations, branch.points.len(), "{t:?}");
    assert!(
        t.searches >= branch.bifurcations.len() / 2 && t.searches > 0,
        "{t:?}"
    );
    // each part took time, and no part more than the whole run (single-part sums)
    for (what, secs) in [
        ("steps", t.step_seconds),
        ("stability", t.stability_seconds),
        ("searches", t.search_seconds),
    ] {
        assert!(
            secs > 0.0 && secs <= elapsed,
            "{what}: {secs} s of {elapsed} s"
        );
    }
}

/// Counts the evaluations of a bifurcation search.
struct CountingSearches<M> {
    method: M,
    searches: std::sync::atomic::AtomicUsize,
}

impl<M: StabilityMethod> StabilityMethod for CountingSearches<M> {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        self.method.multipliers(system, orbit)
    }

    fn search_multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        ends: [&FloquetResult; 2],
    ) -> Result<FloquetResult, StabilityError> {
        self.searches
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.method.search_multipliers(system, orbit, ends)
    }
}

#[test]
fn the_omega_resolution_ends_the_crossing_search_within_it() {
    // The search with only the (tight) arclength tolerance against the same search that
    // also stops once its bracket spans less than 1e-5 in ω: the same two
    // Neimark–Sacker points to that resolution, with fewer trials.
    let run = |tol_omega: f64| {
        let sys = Absorber::default();
        let basis = Basis::integer(7).expect("basis");
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let opts = ContinuationOptions {
            bifurcation_tol_omega: tol_omega,
            ..ContinuationOptions::new(0.8, 1.4)
        };
        let floquet = CountingSearches {
            method: VariationalFloquet { steps: 400 },
            searches: 0.into(),
        };
        let mut cont = Continuation::new(hb, opts, Some(&floquet)).expect("continuation");
        let branch = cont.run(|_| {}).expect("run");
        let ns: Vec<f64> = branch
            .bifurcations
            .iter()
            .filter(|b| b.bifurcation == Some(BifurcationKind::NeimarkSacker))
            .map(|b| b.solution.omega)
            .collect();
        (ns, floquet.searches.into_inner())
    };
    let (fine, fine_trials) = run(0.0);
    let (resolved, resolved_trials) = run(1e-5);
    assert_eq!(fine.len(), 2, "{fine:?}");
    assert_eq!(resolved.len(), 2, "{resolved:?}");
    for (a, b) in fine.iter().zip(&resolved) {
        assert!((a - b).abs() <= 1e-5, "ω {b} against {a}");
    }
    assert!(
        resolved_trials < fine_trials,
        "{resolved_trials} trials against {fine_trials}"
    );
}

/// A branch as `Continuation::drive` hands it out: every outcome in order, pausing after
/// every `pause_every`-th (then driving on), in `pool` or the current one.
fn driven(pool: Option<&rayon::ThreadPool>, pause_every: Option<usize>) -> Branch {
    use std::ops::ControlFlow;
    use tmrotor::continuation::{DriveEnd, StepOutcome};
    let sys = Absorber::default();
    let basis = Basis::integer(7).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let opts = ContinuationOptions::new(0.8, 1.4);
    let floquet = VariationalFloquet { steps: 400 };
    let mut cont = Continuation::new(hb, opts, Some(&floquet)).expect("continuation");
    let (mut points, mut bifurcations, mut rejected, mut seen) = (Vec::new(), Vec::new(), 0, 0);
    let mut pauses = 0;
    let finish = loop {
        let mut observer = |out: StepOutcome| {
            seen += 1;
            match out {
                StepOutcome::Accepted {
                    point,
                    bifurcations: b,
                } => {
                    points.push(*point);
                    bifurcations.extend(b);
                }
                StepOutcome::Rejected(_) => rejected += 1,
                StepOutcome::Finished(_) => {}
            }
            match pause_every {
                Some(n) if seen % n == 0 => ControlFlow::Break(()),
                _ => ControlFlow::Continue(()),
            }
        };
        match cont.drive(pool, &mut observer).expect("drive") {
            DriveEnd::Finished(f) => break f,
            DriveEnd::Paused => pauses += 1,
        }
    };
    if pause_every.is_some() {
        assert!(pauses > 3, "paused {pauses} times");
    }
    Branch {
        points,
        bifurcations,
        finish,
        rejected_steps: rejected,
    }
}

/// The pipelined driver hands out the branch `step` traces: the same points in the same
/// order with the same multipliers, the same bifurcations and the same end, whether its
/// corrector runs on a pool thread (a one-thread pool: its tasks run while it waits) or
/// on the caller with the tasks on the pool, and when it is paused and driven on.
#[test]
fn the_pipelined_driver_hands_out_the_branch_that_stepping_traces() {
    let reference = trace();
    assert!(
        reference
            .bifurcations
            .iter()
            .any(|b| b.bifurcation == Some(BifurcationKind::NeimarkSacker)),
        "the reference branch has Neimark–Sacker points to locate"
    );
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let runs = [
        ("caller outside the pool", driven(Some(&two), None)),
        ("on a one-thread pool", one.install(|| driven(None, None))),
        ("paused and driven on", driven(Some(&two), Some(7))),
        (
            "paused, one-thread pool",
            one.install(|| driven(None, Some(5))),
        ),
    ];
    for (what, b) in &runs {
        assert_eq!(b.points.len(), reference.points.len(), "{what}: points");
        for (p, r) in b.points.iter().zip(&reference.points) {
            assert_eq!(p.index, r.index, "{what}");
            assert_eq!(p.solution, r.solution, "{what}: point {}", r.index);
            assert_eq!(p.stability, r.stability, "{what}: point {}", r.index);
            assert_eq!(p.arclength, r.arclength, "{what}: point {}", r.index);
        }
        let key = |v: &[tmrotor::continuation::BranchPoint]| {
            v.iter()
                .map(|b| {
                    (
                        b.index,
                        b.bifurcation,
                        b.solution.omega,
                        b.stability.clone(),
                    )
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(key(&b.bifurcations), key(&reference.bifurcations), "{what}");
        assert_eq!(b.finish, reference.finish, "{what}");
        assert_eq!(b.rejected_steps, reference.rejected_steps, "{what}");
    }
}

/// A stability method that panics past `omega` (a stand-in for a bug in one).
struct PanicsPast<M>(M, f64);

impl<M: StabilityMethod> StabilityMethod for PanicsPast<M> {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        assert!(orbit.omega() <= self.1, "a stability method's own bug");
        self.0.multipliers(system, orbit)
    }
}

/// A panic in one of the pipeline's tasks reaches the caller of `drive` (on a pool and
/// from outside one) instead of leaving the corrector waiting for its result.
#[test]
fn a_panicking_stability_task_ends_the_drive_with_its_panic() {
    let sys = Absorber::default();
    let basis = Basis::integer(7).expect("basis");
    let floquet = PanicsPast(VariationalFloquet { steps: 400 }, 1.0);
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    for pool in [Some(&two), None] {
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let opts = ContinuationOptions::new(0.8, 1.4);
        let mut cont = Continuation::new(hb, opts, Some(&floquet)).expect("continuation");
        let mut last_omega = 0.0;
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut observer = |out| {
                if let tmrotor::continuation::StepOutcome::Accepted { point, .. } = out {
                    last_omega = point.solution.omega;
                }
                std::ops::ControlFlow::Continue(())
            };
            match pool {
                Some(p) => cont.drive(Some(p), &mut observer),
                None => two.install(|| cont.drive(None, &mut observer)),
            }
        }));
        assert!(outcome.is_err(), "the drive ended without the panic");
        assert!(
            last_omega > 0.8 && last_omega <= 1.0,
            "last point at {last_omega}"
        );
    }
}
