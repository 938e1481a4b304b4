//! Jeffcott rotor on a Hertzian ball bearing with clearance: harmonic-balance orbits
//! against RK4 time integration run to steady state.
//!
//! The ball passage (16/5 ω) and its harmonics excite the journal near its own resonance
//! on the bearing contact stiffness (~9e3 rad/s), so the journal motion carries harmonics
//! up to ~30ω: with multiples of ω/5 up to 4ω (20 harmonics) the maxima differ from time
//! integration by ~0.5 %, up to 20ω by ~1e-3, up to 32ω (160 harmonics) by ~3e-5. The test
//! uses 160 harmonics, started from the solution with 20, below (300 rad/s) and above
//! (550 rad/s) the primary resonance (~488 rad/s).
//!
//! Above ~555 rad/s the journal loses contact for part of each period. There the orbits
//! with 160 harmonics are checked against Dormand–Prince time integration run from rest
//! (580, 660, 700 rad/s, where it settles on a period-1 orbit that SIP finds stable), the
//! example's continuation is run through the fold cluster at 573–578 rad/s, and at 397
//! rad/s, inside a window where the period-1 branch is unstable, time integration settles
//! on a period-2 response and SIP finds a multiplier beyond −1.

// The example's continuation settings.
#[path = "../examples/jeffcott.rs"]
#[allow(dead_code)]
mod example;

mod engine_support;

use engine_support::steady_max_abs;
use tmrotor::continuation::{Continuation, FinishReason};
use tmrotor::hb::newton::{NewtonOptions, solve_fixed};
use tmrotor::hb::{HarmonicBalance, HbSolution};
use tmrotor::integrate::{
    Dopri5Options, SteadyState, SteadyStateOptions, poincare_samples, steady_state_with,
};
use tmrotor::stability::{BifurcationKind, Sip, StabilityMethod};
use tmrotor::system::PeriodicOrbit;
use tmrotor::systems::jeffcott::Jeffcott;

#[test]
fn harmonic_balance_orbits_match_time_integration() {
    let sys = Jeffcott::default();
    let basis = sys.basis(160).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    for omega in [300.0, 550.0] {
        // coarse solve (up to 4ω), embedded as the start of the fine one
        let coarse = sys.basis(20).expect("basis");
        let hb_c = HarmonicBalance::new(&sys, &coarse, None).expect("hb");
        let opts = NewtonOptions::default();
        let (ac, _) =
            solve_fixed(&hb_c, omega, &sys.start_guess(&coarse, omega), &opts).expect("coarse");
        let (ncc, nf) = (coarse.n_coeffs(), basis.n_coeffs());
        let (hc, hf) = (coarse.n_harmonics(), basis.n_harmonics());
        let mut guess = vec![0.0; 4 * nf];
        for d in 0..4 {
            guess[d * nf] = ac[d * ncc];
            for h in 0..hc {
                guess[d * nf + 1 + h] = ac[d * ncc + 1 + h];
                guess[d * nf + 1 + hf + h] = ac[d * ncc + 1 + hc + h];
            }
        }
        let (a, stats) = solve_fixed(&hb, omega, &guess, &opts).expect("newton");
        let sol = HbSolution::from_unknowns(omega, &basis, 4, &a, &stats);
        let period = sol.period();
        let (mut x, mut v) = ([0.0; 4], [0.0; 4]);
        sol.state_at(0.0, &mut x, &mut v, &mut []);
        let y0: Vec<f64> = x.iter().chain(&v).map(|s| 1.01 * s).collect();
        for dof in [0, 2] {
            let (ti, _) = steady_max_abs(&sys, omega, period, &y0, 30, 8192, dof);
            let hbv = sol.max_abs(dof);
            let rel = (hbv - ti).abs() / ti;
            eprintln!("ω = {omega}, DoF {dof}: HB {hbv:e}, time integration {ti:e}, rel {rel:e}");
            assert!(rel < 2e-4, "ω = {omega}, DoF {dof}: HB {hbv:e} vs {ti:e}");
        }
    }
}

/// Period of the response (five revolutions: the cage ratio is 2/5).
fn period(omega: f64) -> f64 {
    5.0 * 2.0 * std::f64::consts::PI / omega
}

/// State at rest in the static equilibrium (disk and journal sagged under gravity).
fn at_rest(sys: &Jeffcott, omega: f64) -> Vec<f64> {
    let basis = sys.basis(20).expect("basis");
    let g = sys.start_guess(&basis, omega);
    let nc = basis.n_coeffs();
    vec![g[0], 0.0, g[2 * nc], 0.0, 0.0, 0.0, 0.0, 0.0]
}

/// Time integration from rest over 150 periods (~45 decay times of the disk mode), then
/// one period sampled at the AFT instants of `hb`.
fn settle(sys: &Jeffcott, hb: &HarmonicBalance<'_>, omega: f64) -> SteadyState {
    steady_state_with(
        sys,
        omega,
        &at_rest(sys, omega),
        period(omega),
        150,
        &SteadyStateOptions {
            samples_per_period: hb.aft().n_samples(),
            ..SteadyStateOptions::default()
        },
    )
    .expect("integrates")
}

/// The samples projected on the basis (all four DoFs): a start for Newton.
fn project(hb: &HarmonicBalance<'_>, ss: &SteadyState) -> Vec<f64> {
    let nc = hb.n_coeffs();
    let mut a = vec![0.0; 4 * nc];
    for (d, block) in a.chunks_mut(nc).enumerate() {
        let x: Vec<f64> = ss.samples.iter().map(|y| y[d]).collect();
        hb.aft().project(&x, block, &mut Vec::new());
    }
    a
}

#[test]
fn orbits_above_contact_loss_match_time_integration_and_are_stable() {
    let sys = Jeffcott::default();
    let basis = sys.basis(example::HARMONICS).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    for omega in [580.0, 660.0, 700.0] {
        let ss = settle(&sys, &hb, omega);
        // settled on a period-1 orbit (velocities ~0.1 m/s, displacements ~1e-5 m)
        assert!(ss.periodicity_error < 1e-6, "ω = {omega}: {ss:?}");
        let (a, stats) =
            solve_fixed(&hb, omega, &project(&hb, &ss), &NewtonOptions::default()).expect("newton");
        let sol = HbSolution::from_unknowns(omega, &basis, 4, &a, &stats);
        // the journal loses contact for part of the period here
        let nc = basis.n_coeffs();
        let free = (0..1024)
            .filter(|&j| {
                let t = period(omega) * j as f64 / 1024.0;
                let x = basis.eval(&a[2 * nc..3 * nc], omega, t).0;
                let y = basis.eval(&a[3 * nc..4 * nc], omega, t).0;
                (0..sys.n_balls).all(|b| {
                    let th = 2.0 * std::f64::consts::PI * b as f64 / sys.n_balls as f64
                        + omega * sys.cage_ratio() * t;
                    x * th.cos() + y * th.sin() <= sys.clearance_m
                })
            })
            .count();
        for dof in [0, 2] {
            let (hbv, ti) = (sol.max_abs(dof), ss.amplitude(dof));
            let rel = (hbv - ti).abs() / ti;
            eprintln!(
                "ω = {omega}, DoF {dof}: HB {hbv:e}, time integration {ti:e}, rel {rel:e}; no contact {free}/1024 of the period"
            );
            // 160 harmonics: ~5e-4 on the journal once it impacts (module docs)
            assert!(rel < 1e-3, "ω = {omega}, DoF {dof}: HB {hbv:e} vs {ti:e}");
        }
        assert!(free > 0, "ω = {omega}: expected contact loss");
        let f = Sip::default().multipliers(&sys, &sol).expect("SIP");
        assert!(
            f.stable,
            "ω = {omega}: spectral radius {}",
            f.spectral_radius()
        );
    }
}

#[test]
fn example_continuation_passes_the_fold_cluster_and_arrives_on_the_time_integrated_orbit() {
    let sys = Jeffcott::default();
    let basis = sys.basis(example::HARMONICS).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let (w0, w1) = (570.0, 580.0);
    let start = project(&hb, &settle(&sys, &hb, w0));
    let end = settle(&sys, &hb, w1);
    let mut opts = example::options(w0, w1);
    opts.initial_guess = Some(start);
    let branch = Continuation::new(hb, opts, None)
        .expect("continuation")
        .run(|_| {})
        .expect("run");
    assert_eq!(branch.finish, FinishReason::Bound { omega: w1 });
    let omegas: Vec<f64> = branch.points.iter().map(|p| p.solution.omega).collect();
    let folds: Vec<f64> = omegas
        .windows(3)
        .filter(|w| (w[1] - w[0]) * (w[2] - w[1]) < 0.0)
        .map(|w| w[1])
        .collect();
    eprintln!("{} points, turning points at {folds:?}", omegas.len());
    // super-harmonic resonances bent into fold pairs between 573.9 and 577.1 rad/s
    assert!(
        folds.len() >= 6 && folds.len().is_multiple_of(2),
        "{folds:?}"
    );
    assert!(
        folds.iter().all(|w| (573.5..577.5).contains(w)),
        "{folds:?}"
    );
    let last = &branch.points.last().expect("points").solution;
    for dof in [0, 2] {
        let (hbv, ti) = (last.max_abs(dof), end.amplitude(dof));
        assert!(
            (hbv - ti).abs() < 1e-3 * ti,
            "DoF {dof} at {w1}: branch {hbv:e} vs time integration {ti:e}"
        );
    }
}

#[test]
fn unstable_window_near_397_gives_period_two_in_time_and_a_multiplier_beyond_minus_one() {
    let sys = Jeffcott::default();
    let omega = 397.0;
    // time integration from rest: stroboscopic samples alternate between two points
    let samples = poincare_samples(
        &sys,
        omega,
        &at_rest(&sys, omega),
        period(omega),
        200,
        6,
        &Dopri5Options::default(),
    )
    .expect("integrates");
    let spread = |lag: usize| {
        samples
            .windows(lag + 1)
            .map(|w| (w[0][2] - w[lag][2]).abs().max((w[0][0] - w[lag][0]).abs()))
            .fold(0.0, f64::max)
    };
    let (s1, s2) = (spread(1), spread(2));
    eprintln!("ω = {omega}: |P(k+1) − P(k)| ≤ {s1:e} m, |P(k+2) − P(k)| ≤ {s2:e} m");
    assert!(s1 > 1e-7 && s2 < 1e-9, "period 2 expected");
    // The period-1 branch, continued with the example's settings from the stable orbit at
    // 394 rad/s (from time integration), loses stability through −1 and is unstable
    // through −1 at 397 rad/s.
    let basis = sys.basis(example::HARMONICS).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let w0 = 394.0;
    let mut opts = example::options(w0, omega);
    opts.initial_guess = Some(project(&hb, &settle(&sys, &hb, w0)));
    let sip = Sip::default();
    let branch = Continuation::new(hb, opts, Some(&sip))
        .expect("continuation")
        .run(|_| {})
        .expect("run");
    assert_eq!(branch.finish, FinishReason::Bound { omega });
    assert_eq!(branch.points[0].stable(), Some(true));
    let first = branch.bifurcations.first().expect("a bifurcation");
    eprintln!(
        "{} points; first bifurcation {:?} at {} rad/s; {} located",
        branch.points.len(),
        first.bifurcation,
        first.solution.omega,
        branch.bifurcations.len()
    );
    assert_eq!(first.bifurcation, Some(BifurcationKind::PeriodDoubling));
    let f = branch
        .points
        .last()
        .and_then(|p| p.stability.clone())
        .expect("stability at the end");
    let flip = f
        .multipliers
        .iter()
        .filter(|m| m.im.abs() < 1e-9 && m.re < -1.0)
        .count();
    eprintln!("ω = {omega}: multipliers {:?}", f.multipliers);
    assert!(
        !f.stable && flip >= 1,
        "a real multiplier below −1 expected"
    );
}
