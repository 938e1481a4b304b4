//! SIP and variational Floquet multipliers cross-checked on the Duffing and nonlinear
//! absorber reference oscillators, on orbits computed by direct time integration
//! (settling + Newton shooting), with the shooting monodromy as a third, independent value.

use num_complex::Complex64;
use tmrotor::integrate::{
    Dopri5Options, ShootingOptions, SteadyStateOptions, poincare_samples, shoot_periodic,
    steady_state, steady_state_with,
};
use tmrotor::stability::{BifurcationKind, Sip, StabilityMethod, Variational, classify_crossing};
use tmrotor::system::System;
use tmrotor::systems::absorber::Absorber;
use tmrotor::systems::duffing::Duffing;

/// Pairs every multiplier of `a` with its nearest unused one in `b`; returns the largest
/// distance.
fn max_pair_distance(a: &[Complex64], b: &[Complex64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let mut used = vec![false; b.len()];
    let mut worst: f64 = 0.0;
    for x in a {
        let (j, d) = b
            .iter()
            .enumerate()
            .filter(|(j, _)| !used[*j])
            .map(|(j, y)| (j, (x - y).norm()))
            .min_by(|p, q| p.1.total_cmp(&q.1))
            .expect("same length");
        used[j] = true;
        worst = worst.max(d);
    }
    worst
}

/// Periodic orbit by settling then shooting; returns (SIP, variational, shooting)
/// multipliers and the stable flags.
fn three_ways(system: &dyn System, omega: f64, y0: &[f64], settle: usize) -> [Vec<Complex64>; 3] {
    let period = 2.0 * std::f64::consts::PI / omega;
    let settled = steady_state(system, omega, y0, period, settle).expect("settles");
    let shot = shoot_periodic(
        system,
        omega,
        &settled.samples[0],
        period,
        &ShootingOptions::default(),
    )
    .expect("shooting converges");
    three_ways_from_orbit_start(system, omega, &shot.y, shot.phi.eigenvalues().expect("eig"))
}

fn three_ways_from_orbit_start(
    system: &dyn System,
    omega: f64,
    y_orbit: &[f64],
    shooting: Vec<Complex64>,
) -> [Vec<Complex64>; 3] {
    let period = 2.0 * std::f64::consts::PI / omega;
    let orbit = steady_state(system, omega, y_orbit, period, 0)
        .expect("samples")
        .orbit();
    let sip = accurate_sip()
        .multipliers(system, &orbit)
        .expect("SIP")
        .multipliers;
    let var = Variational::default()
        .multipliers(system, &orbit)
        .expect("variational")
        .multipliers;
    [sip, var, shooting]
}

#[test]
fn duffing_multipliers_agree_on_both_stable_branches() {
    let sys = Duffing::default();
    // Below resonance, the resonant (upper) branch inside the fold pair, the lower branch
    // there, and above the upper fold. Starts from the one-term balance of each branch.
    for (omega, a0, b0) in [
        (0.8, 0.0, 0.0),
        (1.2, 1.36, 2.13),
        (1.2, -0.417, 0.0),
        (1.6, 0.0, 0.0),
    ] {
        let (a, b) = one_term_hb(omega, a0, b0);
        let [sip, var, shoot] = three_ways(&sys, omega, &[a, b * omega], 200);
        let d_sv = max_pair_distance(&sip, &var);
        let d_vs = max_pair_distance(&var, &shoot);
        println!(
            "Duffing Ω = {omega}: SIP {sip:?}\n  var {var:?}\n  |SIP−var| = {d_sv:.2e}, |var−shoot| = {d_vs:.2e}"
        );
        // Liouville: μ1 μ2 = exp(−0.05 P) exactly for this system (trace of B is −0.05).
        let exact = (-0.05 * 2.0 * std::f64::consts::PI / omega).exp();
        let (det_sip, det_var) = ((sip[0] * sip[1]).re, (var[0] * var[1]).re);
        assert!((det_var - exact).abs() < 1e-9, "det {det_var} vs {exact}");
        assert!((det_sip - exact).abs() < 1e-6, "det {det_sip} vs {exact}");
        // SIP (512 intervals, extrapolated) against
        // the variational monodromy (rtol 1e-10) and shooting along the integrated
        // trajectory (both ~1e-10).
        assert!(d_sv < 1e-6 && d_vs < 1e-8, "Ω = {omega}");
        assert!(sip.iter().all(|m| m.norm() < 1.0));
    }
}

/// One-harmonic balance of the Duffing equation, `x ≈ a cos Ωt + b sin Ωt`, solved by
/// Newton from `(a, b)`: a starting guess for shooting onto a particular branch.
fn one_term_hb(omega: f64, mut a: f64, mut b: f64) -> (f64, f64) {
    for _ in 0..100 {
        let r2 = a * a + b * b;
        let k = 1.0 - omega * omega + 0.075 * r2;
        let (c, f) = (0.05 * omega, 0.18);
        let r1 = k * a + c * b - f;
        let r2b = k * b - c * a;
        let (j11, j12) = (k + 0.15 * a * a, c + 0.15 * a * b);
        let (j21, j22) = (-c + 0.15 * a * b, k + 0.15 * b * b);
        let det = j11 * j22 - j12 * j21;
        a -= (j22 * r1 - j12 * r2b) / det;
        b -= (-j21 * r1 + j11 * r2b) / det;
    }
    (a, b)
}

#[test]
fn duffing_middle_branch_is_unstable_through_plus_one() {
    let sys = Duffing::default();
    let omega = 1.2;
    let period = 2.0 * std::f64::consts::PI / omega;
    // The three one-term amplitudes at Ω = 1.2 are 0.417, 2.276 and 2.526; the middle one
    // lags the force by about 131° (a ≈ −1.48, b ≈ 1.73); start Newton near it.
    let (a, b) = one_term_hb(omega, -1.48, 1.73);
    let amp = a.hypot(b);
    assert!(amp > 2.2 && amp < 2.35, "middle one-term amplitude {amp}");
    let shot = shoot_periodic(
        &sys,
        omega,
        &[a, b * omega],
        period,
        &ShootingOptions::default(),
    )
    .expect("shooting converges on the unstable orbit");
    let shoot_mult = shot.phi.eigenvalues().expect("eig");
    let [sip, var, shoot] = three_ways_from_orbit_start(&sys, omega, &shot.y, shoot_mult);
    println!("Duffing middle branch Ω = {omega}: SIP {sip:?}, var {var:?}, shoot {shoot:?}");
    assert!(max_pair_distance(&sip, &var) < 1e-6 * largest_norm(&var));
    assert!(max_pair_distance(&var, &shoot) < 1e-8 * largest_norm(&var));
    let largest = sip
        .iter()
        .max_by(|p, q| p.norm().total_cmp(&q.norm()))
        .expect("two multipliers");
    assert!(
        largest.re > 1.0 && largest.im.abs() < 1e-9,
        "real multiplier above +1"
    );
    // Against the stable upper branch at the same Ω, the crossing classifies as a fold.
    let upper = accurate_sip()
        .multipliers(
            &sys,
            &steady_state(&sys, omega, &[2.526, 0.0], period, 300)
                .expect("settles")
                .orbit(),
        )
        .expect("SIP");
    let middle = accurate_sip()
        .multipliers(
            &sys,
            &steady_state(&sys, omega, &shot.y, period, 0)
                .expect("samples")
                .orbit(),
        )
        .expect("SIP");
    assert!(upper.stable && !middle.stable);
    assert_eq!(
        classify_crossing(&upper, &middle),
        Some(BifurcationKind::SaddleNode)
    );
}

#[test]
fn absorber_multipliers_agree() {
    let sys = Absorber::default();
    // Extrapolated SIP; the plain product at 256 intervals would leave an O(Δ²)
    // error of 3.8e-6 here (see sip_converges_to_the_variational_multipliers).
    let sip_fine = accurate_sip();
    for omega in [0.8, 1.3] {
        let [_, var, shoot] = three_ways(&sys, omega, &[0.0; 4], 400);
        let period = 2.0 * std::f64::consts::PI / omega;
        let settled = steady_state(&sys, omega, &[0.0; 4], period, 400).expect("settles");
        let sip = sip_fine
            .multipliers(&sys, &settled.orbit())
            .expect("SIP")
            .multipliers;
        let d_sv = max_pair_distance(&sip, &var);
        let d_vs = max_pair_distance(&var, &shoot);
        println!(
            "absorber Ω = {omega}: SIP {sip:?}\n  |SIP−var| = {d_sv:.2e}, |var−shoot| = {d_vs:.2e}"
        );
        assert!(d_sv < 1e-6 && d_vs < 1e-8, "Ω = {omega}");
    }
}

#[test]
fn steady_state_amplitude_matches_the_shooting_orbit() {
    // The steady-state sampler and the shooting orbit are two routes to the same periodic
    // solution; their amplitudes agree far inside the 1e-4 the HB comparison needs.
    let sys = Duffing::default();
    let omega = 1.3;
    let period = 2.0 * std::f64::consts::PI / omega;
    let settled = steady_state_with(
        &sys,
        omega,
        &[1.5, 0.0],
        period,
        400,
        &SteadyStateOptions::default(),
    )
    .expect("settles");
    let shot = shoot_periodic(
        &sys,
        omega,
        &settled.samples[0],
        period,
        &ShootingOptions::default(),
    )
    .expect("shoots");
    let exact = steady_state(&sys, omega, &shot.y, period, 0).expect("samples");
    let (a1, a2) = (settled.amplitude(0), exact.amplitude(0));
    println!(
        "amplitudes {a1} {a2}, periodicity error {}",
        settled.periodicity_error
    );
    assert!(settled.periodicity_error < 1e-8);
    assert!((a1 - a2).abs() < 1e-8 * a2);
}

fn largest_norm(m: &[Complex64]) -> f64 {
    m.iter().map(|z| z.norm()).fold(0.0, f64::max)
}

#[test]
fn sip_converges_to_the_variational_multipliers() {
    // Absorber at Ω = 0.8: SIP error against the variational multipliers for
    // N_k = 256..2048 falls by 4 per doubling (second order, paper Eq. 32 keeps only the
    // first Magnus term); measured 3.8e-6, 9.7e-7, 2.4e-7, 6.1e-8.
    let sys = Absorber::default();
    let omega = 0.8;
    let period = 2.0 * std::f64::consts::PI / omega;
    let settled = steady_state(&sys, omega, &[0.0; 4], period, 400).expect("settles");
    let shot = shoot_periodic(
        &sys,
        omega,
        &settled.samples[0],
        period,
        &ShootingOptions::default(),
    )
    .expect("shoots");
    let orbit = steady_state(&sys, omega, &shot.y, period, 0)
        .expect("samples")
        .orbit();
    let var = Variational::default()
        .multipliers(&sys, &orbit)
        .expect("variational")
        .multipliers;
    let errs: Vec<f64> = [256, 512, 1024, 2048]
        .iter()
        .map(|&n| {
            let m = Sip::fixed(n, 4)
                .multipliers(&sys, &orbit)
                .expect("SIP")
                .multipliers;
            max_pair_distance(&m, &var)
        })
        .collect();
    println!("SIP error vs N_k = 256..2048: {errs:?}");
    assert!(errs[0] < 1e-5);
    for w in errs.windows(2) {
        let ratio = w[0] / w[1];
        assert!(ratio > 3.6 && ratio < 4.4, "ratio {ratio} in {errs:?}");
    }
}

/// Natural-parameter continuation of the absorber's resonant branch from Ω = 0.8 upward
/// by shooting; returns the orbit start at `target` (the branch has no fold below 1.2).
fn absorber_branch_start(target: f64) -> Vec<f64> {
    let sys = Absorber::default();
    let mut omega = 0.8;
    let period = 2.0 * std::f64::consts::PI / omega;
    let mut y = steady_state(&sys, omega, &[0.0; 4], period, 2000)
        .expect("settles")
        .samples[0]
        .clone();
    loop {
        let period = 2.0 * std::f64::consts::PI / omega;
        y = shoot_periodic(&sys, omega, &y, period, &ShootingOptions::default())
            .expect("shooting follows the branch")
            .y;
        if omega >= target - 1e-12 {
            return y;
        }
        omega = (omega + 0.01).min(target);
    }
}

#[test]
fn absorber_neimark_sacker_is_detected_and_the_response_past_it_is_not_periodic() {
    let sys = Absorber::default();
    // A shooting sweep of the resonant branch (0.8 → 1.2) shows the leading multipliers
    // as a complex pair whose modulus passes 1 between Ω = 1.11 (0.994) and 1.12 (1.013)
    // at μ ≈ 0.85 ± 0.53i, and returns inside between 1.19 and 1.20.
    let (w_before, w_after) = (1.11, 1.12);
    let y_before = absorber_branch_start(w_before);
    let y_after = absorber_branch_start(w_after);
    let sip_at = |omega: f64, y: &[f64]| {
        let period = 2.0 * std::f64::consts::PI / omega;
        let orbit = steady_state(&sys, omega, y, period, 0)
            .expect("samples")
            .orbit();
        // The plain product at its defaults, as the continuation uses it.
        Sip::default().multipliers(&sys, &orbit).expect("SIP")
    };
    let (before, after) = (sip_at(w_before, &y_before), sip_at(w_after, &y_after));
    println!(
        "NS: before {:?}\n after {:?}",
        before.multipliers, after.multipliers
    );
    assert!(before.stable && !after.stable);
    assert_eq!(
        classify_crossing(&before, &after),
        Some(BifurcationKind::NeimarkSacker)
    );

    // Time integration just past the crossing, from the (now unstable) periodic orbit
    // slightly perturbed: after 3000 periods the stroboscopic samples neither settle to a
    // point (period 1) nor cycle with any period up to 8, do not return to the periodic
    // orbit, and stay bounded (measured: samples 0.21..0.99 away from the orbit start).
    let omega = 1.13;
    let y_orbit = absorber_branch_start(omega);
    let period = 2.0 * std::f64::consts::PI / omega;
    let start: Vec<f64> = y_orbit.iter().map(|v| v + 1e-3).collect();
    let samples = poincare_samples(
        &sys,
        omega,
        &start,
        period,
        3000,
        400,
        &Dopri5Options::default(),
    )
    .expect("integrates");
    let dist = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p - q) * (p - q))
            .sum::<f64>()
            .sqrt()
    };
    let min_lag = |lag: usize| {
        samples
            .windows(lag + 1)
            .map(|w| dist(&w[0], &w[lag]))
            .fold(f64::INFINITY, f64::min)
    };
    let radius: Vec<f64> = samples.iter().map(|s| dist(s, &y_orbit)).collect();
    let (rmin, rmax) = (
        radius.iter().copied().fold(f64::INFINITY, f64::min),
        radius.iter().copied().fold(0.0, f64::max),
    );
    let lags: Vec<f64> = (1..=8).map(min_lag).collect();
    println!(
        "Ω = {omega}: min |P(k+j)−P(k)|, j = 1..8: {lags:.3?}, distance to the periodic orbit {rmin:.3e}..{rmax:.3e}"
    );
    assert!(
        lags.iter().all(|&d| d > 1e-4),
        "not periodic with period ≤ 8P"
    );
    assert!(
        rmin > 1e-3,
        "does not return to the unstable periodic orbit"
    );
    assert!(rmax < 10.0, "bounded");
}

/// SIP for the small reference oscillators: 512 intervals with Richardson extrapolation
/// (safe here: one or two modes with `ω·P` of a few radians, so the series truncation is
/// negligible; see `tmrotor::stability::sip`). Error O(Δ⁴) instead of O(Δ²).
fn accurate_sip() -> Sip {
    Sip {
        intervals: 512,
        extrapolate: true,
        ..Sip::default()
    }
}
