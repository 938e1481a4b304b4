//! Newton (modified IHB) on a thermo-mechanical problem, failure reporting, and the
//! continuation driver's step outcomes and CSV output.

use tmrotor::continuation::{
    Continuation, ContinuationOptions, FinishReason, RejectReason, StepOutcome, csv::branch_csv,
};
use tmrotor::hb::newton::{NewtonError, NewtonOptions, solve_fixed};
use tmrotor::hb::{Basis, HarmonicBalance, HbSolution, Ratio};
use tmrotor::system::PeriodicOrbit;
use tmrotor::systems::absorber::Absorber;
use tmrotor::systems::chain::Chain;
use tmrotor::systems::duffing::Duffing;

#[test]
fn thermo_mechanical_newton_condensed_equals_full_and_meets_both_tolerances() {
    let sys = Chain::with_contacts(10, 8, 2, 2);
    let basis = Basis::paper(2, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let zero = vec![0.0; hb.n_unknowns()];
    let tight = NewtonOptions {
        tol_therm: 1e-10,
        ..NewtonOptions::default()
    };
    let (a1, s1) = solve_fixed(&hb, 0.9, &zero, &tight).expect("condensed");
    let (a2, _) = solve_fixed(
        &hb,
        0.9,
        &zero,
        &NewtonOptions {
            condense: false,
            ..tight
        },
    )
    .expect("full");
    assert!(s1.relative.mech <= 1e-8 && s1.relative.therm <= 1e-10);
    let scale = a1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (u, v) in a1.iter().zip(&a2) {
        assert!((u - v).abs() < 1e-9 * scale);
    }
    // the thermal part is non-trivial: the hot nodes sit above the linear-conduction solution
    let sol = HbSolution::from_unknowns(0.9, &basis, 10, &a1, &s1);
    assert!(sol.therm_coeffs(0)[0] > 0.0);
    // the paper's loose thermal tolerance (1e-3) stops earlier or at the same iteration
    let (_, s3) = solve_fixed(&hb, 0.9, &zero, &NewtonOptions::default()).expect("default");
    assert!(s3.iterations <= s1.iterations);
    assert!(s3.relative.therm <= 1e-3);
}

#[test]
fn newton_failure_reports_iterations_and_residuals() {
    let sys = Duffing::default();
    let basis = Basis::integer(3).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let opts = NewtonOptions {
        max_iterations: 1,
        ..NewtonOptions::default()
    };
    // a far start on the resonant branch cannot converge in one iteration
    let mut a = vec![0.0; 7];
    a[1] = 50.0;
    match solve_fixed(&hb, 1.2, &a, &opts) {
        Err(NewtonError::Diverged {
            iterations,
            residual_mech,
            ..
        }) => {
            assert_eq!(iterations, 1);
            assert!(residual_mech > 1e-8);
        }
        Err(NewtonError::NoDescent { residual_mech, .. }) => assert!(residual_mech > 1e-8),
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn rms_amplitude_is_eq35_and_max_abs_matches_dense_sampling() {
    let sys = Duffing::default();
    let basis = Basis::integer(5).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let (a, st) = solve_fixed(&hb, 1.0, &[0.0; 11], &NewtonOptions::default()).expect("newton");
    let sol = HbSolution::from_unknowns(1.0, &basis, 1, &a, &st);
    // Eq. 35 by quadrature over 20000 samples
    let n = 20_000;
    let p = sol.period();
    let xs: Vec<f64> = (0..n)
        .map(|j| basis.eval(&a, 1.0, p * j as f64 / n as f64).0)
        .collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let rms = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
    let max = xs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!((sol.rms_amplitude(0, None) - rms).abs() < 1e-12 * rms);
    assert!((sol.max_abs(0) - max).abs() < 1e-7 * max);
}

#[test]
fn continuation_steps_finish_on_the_bound_and_csv_lists_every_point() {
    let sys = Duffing::default();
    let basis = Basis::integer(3).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    // backwards sweep, from 1.6 down to 0.5
    let mut opts = ContinuationOptions::new(1.6, 0.5);
    opts.ds_max = 0.2;
    let mut cont = Continuation::new(hb, opts, None).expect("continuation");
    let mut accepted = 0;
    let mut last_omega = f64::NAN;
    loop {
        match cont.step().expect("step") {
            StepOutcome::Accepted { point, .. } => {
                accepted += 1;
                last_omega = point.solution.omega;
            }
            StepOutcome::Rejected(_) => {}
            StepOutcome::Finished(f) => {
                assert_eq!(f, FinishReason::Bound { omega: 0.5 });
                break;
            }
        }
    }
    assert_eq!(last_omega, 0.5);
    // a finished driver stays finished
    assert!(matches!(
        cont.step().expect("step"),
        StepOutcome::Finished(_)
    ));
    // run() on a fresh driver gives the same number of points; the CSV has one row each
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(1.6, 0.5);
    opts.ds_max = 0.2;
    let mut observed = 0;
    let branch = Continuation::new(hb, opts, None)
        .expect("continuation")
        .run(|o| observed += usize::from(matches!(o, StepOutcome::Accepted { .. })))
        .expect("run");
    assert_eq!(branch.points.len(), accepted);
    assert_eq!(observed, accepted);
    let csv = branch_csv(&branch, 0).expect("csv");
    let mut lines = csv.lines();
    assert!(
        lines
            .next()
            .expect("header")
            .starts_with("omega,amplitude,stable,bifurcation")
    );
    // one row per point and per located bifurcation: without a stability method the two
    // folds still come out as saddle-nodes (they need no multipliers)
    assert_eq!(branch.bifurcations.len(), 2);
    assert_eq!(lines.count(), accepted + 2);
    assert_eq!(csv.matches(",saddle_node").count(), 2);
    // no stability method: the stable column is empty, not guessed
    for row in csv.lines().skip(1) {
        assert_eq!(row.split(',').nth(2), Some(""));
    }
}

#[test]
fn settings_are_validated_with_field_names() {
    let sys = Duffing::default();
    let basis = Basis::integer(3).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let err = Continuation::new(hb, ContinuationOptions::new(1.0, 1.0), None)
        .err()
        .expect("equal bounds rejected");
    assert!(err.to_string().contains("omega_end"), "{err}");
    assert!(HarmonicBalance::new(&sys, &basis, Some(6)).is_err());
}

#[test]
fn csv_rejects_a_dof_the_system_does_not_have() {
    let sys = Duffing::default();
    let basis = Basis::integer(1).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.5, 0.6);
    opts.max_points = 3;
    let branch = Continuation::new(hb, opts, None)
        .expect("continuation")
        .run(|_| {})
        .expect("run");
    assert!(branch_csv(&branch, 1).is_err());
}

#[test]
fn corrector_distance_bound_rejects_far_corrections_and_the_branch_still_passes_the_folds() {
    let sys = Duffing::default();
    let basis = Basis::integer(3).expect("basis");
    let trace = |bound: f64| {
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let mut opts = ContinuationOptions::new(0.5, 1.6);
        opts.max_corrector_distance = bound;
        let mut rejections = vec![];
        let branch = Continuation::new(hb, opts, None)
            .expect("continuation")
            .run(|o| {
                if let StepOutcome::Rejected(RejectReason::Distance { ds, distance }) = o {
                    rejections.push((*ds, *distance));
                }
            })
            .expect("run");
        (branch, rejections)
    };
    let (loose, loose_rejections) = trace(1.0);
    let (tight, tight_rejections) = trace(0.02);
    assert!(loose_rejections.is_empty(), "{loose_rejections:?}");
    assert!(!tight_rejections.is_empty());
    for (ds, distance) in &tight_rejections {
        assert!(*distance > 0.02 * ds, "rejected {distance} at ds {ds}");
    }
    // both reach the end, through both folds (ω turns back twice)
    for branch in [&loose, &tight] {
        assert_eq!(branch.finish, FinishReason::Bound { omega: 1.6 });
        let turns = branch
            .points
            .windows(3)
            .filter(|w| {
                (w[1].solution.omega - w[0].solution.omega)
                    * (w[2].solution.omega - w[1].solution.omega)
                    < 0.0
            })
            .count();
        assert_eq!(turns, 2);
    }
    // shorter steps where the branch bends: more points
    assert!(tight.points.len() > loose.points.len());
    let err = Continuation::new(
        HarmonicBalance::new(&sys, &basis, None).expect("hb"),
        ContinuationOptions {
            max_corrector_distance: 0.0,
            ..ContinuationOptions::new(0.5, 1.6)
        },
        None,
    )
    .err()
    .expect("zero distance bound rejected");
    assert!(err.to_string().contains("max_corrector_distance"), "{err}");
}

#[test]
fn per_dof_scaling_changes_the_steps_not_the_solutions() {
    // The absorber's primary mass and absorber move with different amplitudes: scaling
    // each DoF by its own size changes the step lengths (a different number of points),
    // not the branch (both end on the same solution).
    let sys = Absorber::default();
    let basis = Basis::integer(5).expect("basis");
    let run = |per_dof: bool| {
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let mut opts = ContinuationOptions::new(0.8, 1.4);
        opts.scale_per_dof = per_dof;
        Continuation::new(hb, opts, None)
            .expect("continuation")
            .run(|_| {})
            .expect("run")
    };
    let (global, per_dof) = (run(false), run(true));
    for b in [&global, &per_dof] {
        assert_eq!(b.finish, FinishReason::Bound { omega: 1.4 });
    }
    let end =
        |b: &tmrotor::continuation::Branch| b.points.last().expect("points").solution.unknowns();
    let (ea, eb) = (end(&global), end(&per_dof));
    let diff = ea
        .iter()
        .zip(&eb)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-8, "end points differ by {diff:e}");
    assert_ne!(global.points.len(), per_dof.points.len());
}

/// Keller's corrector (first iteration with a factored matrix from the start point)
/// converges to the same point as Newton from the same predictor, and hands back the
/// Jacobian at the solution.
#[test]
fn keller_corrector_lands_where_newton_does() {
    use tmrotor::hb::newton::{ArcConstraint, solve_arclength, solve_arclength_from};
    use tmrotor::hb::{Border, LinearSolver};
    let sys = Chain::with_contacts(7, 5, 3, 2);
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let nu = hb.n_unknowns();
    let opts = NewtonOptions::default();
    let w0 = 0.9;
    let (a0, _) = solve_fixed(&hb, w0, &vec![0.0; nu], &opts).expect("start");
    // natural-parameter constraint ω − ω0 = ds, bordered into the start point's matrix
    let row = vec![0.0; nu];
    let mut r = vec![0.0; nu];
    let parts = hb.residual_jacobian(&a0, w0, &mut r).expect("jacobian");
    let mut r_omega = vec![0.0; nu];
    hb.d_residual_d_omega(&a0, w0, &mut r_omega).expect("dR/dω");
    let fact = LinearSolver::default()
        .factor(
            &hb,
            &parts,
            Some(Border {
                column: &r_omega,
                row: &row,
                corner: 1.0,
            }),
        )
        .expect("factor");
    let ds = 0.03;
    let arc = ArcConstraint {
        anchor: &a0,
        anchor_omega: w0,
        row: &row,
        corner: 1.0,
        ds,
    };
    let (an, wn, sn) = solve_arclength(&hb, &a0, w0 + ds, &arc, &opts).expect("newton");
    let k = solve_arclength_from(&hb, &a0, w0 + ds, &arc, Some(&fact), &opts).expect("keller");
    assert!((wn - (w0 + ds)).abs() < 1e-12 && (k.omega - (w0 + ds)).abs() < 1e-12);
    let scale = an.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let dev = an
        .iter()
        .zip(&k.a)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    // both meet the tolerance 1e-8 on the residual; the points agree to that order
    assert!(dev < 1e-6 * scale, "deviation {dev:e} of {scale:e}");
    assert!(k.stats.relative.mech <= opts.tol_mech && k.stats.relative.therm <= opts.tol_therm);
    assert!(k.stats.iterations >= 1 && sn.iterations >= 1);
    // the Jacobian at the solution comes back with the full-step trial that converged
    let (jp, jr) = k.jacobian.expect("jacobian at the solution");
    let mut r_check = vec![0.0; nu];
    let fresh = hb
        .residual_jacobian(&k.a, k.omega, &mut r_check)
        .expect("fresh");
    assert_eq!(jr, r_check);
    assert_eq!(jp.nonlinear, fresh.nonlinear);
}

/// Chord iterations (solves with the last Newton iteration's matrix while each cuts the
/// residual by the set factor) converge to the point Newton finds, with fewer
/// factorizations; a factor no iteration reaches leaves plain Newton.
#[test]
fn chord_iterations_land_where_newton_does_with_fewer_factorizations() {
    use tmrotor::hb::newton::{ArcConstraint, solve_arclength};
    let sys = Chain::with_contacts(7, 5, 3, 2);
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let nu = hb.n_unknowns();
    let newton = NewtonOptions::default();
    let chord = NewtonOptions {
        chord_contraction: 0.5,
        ..NewtonOptions::default()
    };
    let never = NewtonOptions {
        chord_contraction: 1e-300,
        ..NewtonOptions::default()
    };
    let w0 = 0.9;
    let zero = vec![0.0; nu];
    let (a0, s0) = solve_fixed(&hb, w0, &zero, &newton).expect("newton");
    let (a1, s1) = solve_fixed(&hb, w0, &zero, &chord).expect("chord");
    let (_, s2) = solve_fixed(&hb, w0, &zero, &never).expect("never");
    // each part within its tolerance's reach: mechanical 1e-8 on the residual, thermal
    // 1e-3 (the paper's), so the two solves' temperatures may differ far more
    let nm = hb.n_mech_unknowns();
    let maxabs = |a: &[f64]| a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let dev = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    };
    let close = |a: &[f64], b: &[f64]| {
        let (dm, dt) = (dev(&a[..nm], &b[..nm]), dev(&a[nm..], &b[nm..]));
        assert!(dm < 1e-6 * maxabs(&a0[..nm]), "mechanical {dm:e}");
        assert!(dt < 1e-3 * maxabs(&a0[nm..]), "thermal {dt:e}");
    };
    close(&a0, &a1);
    assert!(s1.relative.mech <= chord.tol_mech && s1.relative.therm <= chord.tol_therm);
    // Newton factors at every iteration, the chord solve less often
    assert_eq!(s0.factorizations, s0.iterations);
    assert_eq!(s0.chord_iterations, 0);
    assert!(s1.chord_iterations > 0, "{s1:?}");
    assert_eq!(s1.factorizations + s1.chord_iterations, s1.iterations);
    assert!(
        s1.factorizations < s0.factorizations,
        "{s1:?} against {s0:?}"
    );
    assert_eq!(
        s1.newton_equivalent(),
        s1.iterations - s1.chord_iterations + s1.chord_iterations.div_ceil(2)
    );
    assert_eq!((s2.chord_iterations, s2.factorizations), (0, s2.iterations));
    // the same with the arclength constraint (natural parameter, ω − ω0 = ds)
    let row = vec![0.0; nu];
    let ds = 0.03;
    let arc = ArcConstraint {
        anchor: &a0,
        anchor_omega: w0,
        row: &row,
        corner: 1.0,
        ds,
    };
    let (an, wn, _) = solve_arclength(&hb, &a0, w0 + ds, &arc, &newton).expect("newton");
    let (ac, wc, sc) = solve_arclength(&hb, &a0, w0 + ds, &arc, &chord).expect("chord");
    assert!((wn - wc).abs() < 1e-12, "{wn} {wc}");
    close(&an, &ac);
    assert!(sc.relative.mech <= chord.tol_mech);
}
