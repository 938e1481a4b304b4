//! Period-doubling reference (`tmrotor::systems::period_doubling`): the forced double-well
//! Duffing oscillator `ẍ + 0.3ẋ − x + x³ = γ cos(1.2 t)`. The first period doubling of the
//! one-well orbit is located from the Floquet multipliers (a real multiplier through −1),
//! checked against the literature bracket 0.20 < γ < 0.28, against SIP, and against the
//! time integrator's stroboscopic samples (period 1 below, period 2 above). The
//! harmonic-balance continuation in γ of `examples/period_doubling.rs` must find the same
//! point.

// The example's continuation, exactly as `cargo run --example period_doubling` runs it.
#[path = "../examples/period_doubling.rs"]
#[allow(dead_code)]
mod example;

use tmrotor::continuation::csv::branch_csv_with_parameter;
use tmrotor::integrate::{
    Dopri5Options, FlowSensitivity, ShootingOptions, poincare_samples, shoot_periodic, steady_state,
};
use tmrotor::stability::{
    BifurcationKind, FloquetResult, Sip, StabilityMethod, bisect_crossing, classify_crossing,
};
use tmrotor::systems::period_doubling::{DoubleWellDuffing, GAMMA_BRACKET, OMEGA};

fn period() -> f64 {
    2.0 * std::f64::consts::PI / OMEGA
}

/// Period-1 orbit at `gamma` by shooting from `start`.
fn orbit_at(gamma: f64, start: &[f64]) -> FlowSensitivity {
    shoot_periodic(
        &DoubleWellDuffing::reference(gamma),
        OMEGA,
        start,
        period(),
        &ShootingOptions::default(),
    )
    .expect("shooting converges on the period-1 orbit")
}

/// Smallest real part among the multipliers of the shooting monodromy.
fn most_negative(orbit: &FlowSensitivity) -> f64 {
    orbit
        .phi
        .eigenvalues()
        .expect("eigenvalues")
        .iter()
        .map(|m| if m.im.abs() < 1e-9 { m.re } else { 0.0 })
        .fold(f64::INFINITY, f64::min)
}

/// Locates the period doubling: continuation in γ from 0.20 in steps of 0.005, then
/// bisection on `μ_min + 1` to 1e-6. Returns (γ*, orbit start at γ*).
fn locate() -> (f64, Vec<f64>) {
    let settled = steady_state(
        &DoubleWellDuffing::reference(0.20),
        OMEGA,
        &[1.0, 0.0],
        period(),
        300,
    )
    .expect("settles");
    let mut y = orbit_at(0.20, &settled.samples[0]).y;
    let mut lo = 0.20;
    let mut hi = None;
    let mut g = 0.20;
    while g < 0.30 {
        g += 0.005;
        let o = orbit_at(g, &y);
        if most_negative(&o) < -1.0 {
            hi = Some(g);
            break;
        }
        lo = g;
        y = o.y;
    }
    let mut hi = hi.expect("a multiplier reaches −1 below γ = 0.30");
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        let o = orbit_at(mid, &y);
        if most_negative(&o) < -1.0 {
            hi = mid;
        } else {
            lo = mid;
            y = o.y;
        }
    }
    (0.5 * (lo + hi), y)
}

fn sip_at(gamma: f64, start: &[f64]) -> FloquetResult {
    let sys = DoubleWellDuffing::reference(gamma);
    let o = orbit_at(gamma, start);
    let orbit = steady_state(&sys, OMEGA, &o.y, period(), 0)
        .expect("samples")
        .orbit();
    Sip::default().multipliers(&sys, &orbit).expect("SIP")
}

/// Largest distance between stroboscopic samples `lag` periods apart.
fn spread(samples: &[Vec<f64>], lag: usize) -> f64 {
    samples
        .windows(lag + 1)
        .map(|w| (w[0][0] - w[lag][0]).hypot(w[0][1] - w[lag][1]))
        .fold(0.0, f64::max)
}

#[test]
fn period_doubling_is_located_and_confirmed_by_time_integration() {
    let (gamma_pd, y_pd) = locate();
    println!("period doubling at γ* = {gamma_pd:.6}");
    assert!(gamma_pd > GAMMA_BRACKET.0 && gamma_pd < GAMMA_BRACKET.1);

    // SIP on both sides: stable below, one real multiplier below −1 above, and the
    // crossing classifies as period doubling.
    let dg = 0.002;
    let below = sip_at(gamma_pd - dg, &y_pd);
    let above = sip_at(gamma_pd + dg, &y_pd);
    println!(
        "SIP below {:?}\nSIP above {:?}",
        below.multipliers, above.multipliers
    );
    assert!(below.stable && !above.stable);
    assert_eq!(
        classify_crossing(&below, &above),
        Some(BifurcationKind::PeriodDoubling)
    );

    // Time integration from (near) the period-1 orbit: period 1 below γ*, period 2 above.
    let opts = Dopri5Options::default();
    for (gamma, expect_period_two) in [(gamma_pd - 0.005, false), (gamma_pd + 0.005, true)] {
        let start = [y_pd[0] + 1e-3, y_pd[1]];
        let samples = poincare_samples(
            &DoubleWellDuffing::reference(gamma),
            OMEGA,
            &start,
            period(),
            1500,
            8,
            &opts,
        )
        .expect("integrates");
        let (s1, s2) = (spread(&samples, 1), spread(&samples, 2));
        println!("γ = {gamma:.4}: |P(k+1) − P(k)| ≤ {s1:.3e}, |P(k+2) − P(k)| ≤ {s2:.3e}");
        if expect_period_two {
            assert!(s1 > 1e-2 && s2 < 1e-6, "period 2 expected");
        } else {
            assert!(s1 < 1e-6, "period 1 expected");
        }
    }
}

fn sip_with(sip: &Sip, gamma: f64, start: &[f64]) -> FloquetResult {
    let sys = DoubleWellDuffing::reference(gamma);
    let o = orbit_at(gamma, start);
    let orbit = steady_state(&sys, OMEGA, &o.y, period(), 0)
        .expect("samples")
        .orbit();
    sip.multipliers(&sys, &orbit).expect("SIP")
}

#[test]
fn sip_bisection_locates_the_same_period_doubling() {
    // Reference: γ* from the shooting (variational) multipliers. Bisection on the SIP
    // stable flag finds the crossing shifted by (SIP error of the multiplier near −1) /
    // (dμ/dγ); the shift must be explained by that error and vanish with a more accurate
    // SIP (extrapolated, 512 intervals: O(Δ⁴)).
    let (gamma_ref, y_ref) = locate();
    let slope = {
        let (a, b) = (
            most_negative(&orbit_at(gamma_ref - 1e-3, &y_ref)),
            most_negative(&orbit_at(gamma_ref + 1e-3, &y_ref)),
        );
        (b - a) / 2e-3
    };
    let mu_ref = most_negative(&orbit_at(gamma_ref, &y_ref));
    let mu_sip = sip_with(&Sip::default(), gamma_ref, &y_ref)
        .multipliers
        .iter()
        .map(|m| m.re)
        .fold(f64::INFINITY, f64::min);
    // SIP reaches −1 where the exact multiplier is −1 − (μ_sip − μ_ref).
    let predicted_shift = -(mu_sip - mu_ref) / slope;
    let accurate = Sip {
        intervals: 512,
        extrapolate: true,
        ..Sip::default()
    };
    let mut found = vec![];
    for sip in [Sip::default(), accurate] {
        let crossing = bisect_crossing(
            |g| Ok(sip_with(&sip, g, &y_ref)),
            gamma_ref - 0.01,
            gamma_ref + 0.01,
            1e-8,
        )
        .expect("bracket holds a crossing");
        assert_eq!(crossing.kind, Some(BifurcationKind::PeriodDoubling));
        found.push(crossing.parameter());
    }
    println!(
        "γ* reference {gamma_ref:.8}; SIP default {:.8} (μ error {:.2e}, dμ/dγ {slope:.2}, predicted shift {predicted_shift:.2e}); SIP extrapolated {:.8}",
        found[0],
        mu_sip - mu_ref,
        found[1]
    );
    let shift = found[0] - gamma_ref;
    assert!(
        (shift - predicted_shift).abs() < 0.1 * predicted_shift.abs() + 2e-6,
        "shift {shift:.3e} vs predicted {predicted_shift:.3e}"
    );
    // The reference itself is bisected to 1e-6.
    assert!((found[1] - gamma_ref).abs() < 2e-6);
}

#[test]
fn example_continuation_locates_the_shooting_period_doubling() {
    let (gamma_ref, y_ref) = locate();
    let branch = example::branch().expect("the example's continuation runs");
    assert!(
        matches!(branch.finish, tmrotor::continuation::FinishReason::Bound { omega } if omega == GAMMA_BRACKET.1),
        "the branch reaches the end of the range: {:?}",
        branch.finish
    );
    let kinds: Vec<_> = branch.bifurcations.iter().map(|b| b.bifurcation).collect();
    assert_eq!(kinds, vec![Some(BifurcationKind::PeriodDoubling)]);
    let gamma_hb = branch.bifurcations[0].solution.omega;
    let csv = branch_csv_with_parameter(&branch, 0, "gamma").expect("csv");
    assert!(
        csv.lines()
            .next()
            .is_some_and(|h| h.starts_with("gamma,amplitude,stable,bifurcation,"))
    );
    assert_eq!(csv.matches(",period_doubling,").count(), 1);
    println!("γ* shooting {gamma_ref:.8}, example (HB + extrapolated SIP) {gamma_hb:.8}");
    // The reference is bisected to 1e-6; the extrapolated SIP shifts the crossing by
    // ~1e-7 (see the SIP test above) and 16 harmonics leave residuals below 1e-11.
    assert!(
        (gamma_hb - gamma_ref).abs() < 2e-6,
        "γ* example {gamma_hb} vs shooting {gamma_ref}"
    );
    // Stable before the located point, unstable after it.
    for p in &branch.points {
        let expect_stable = p.solution.omega < gamma_hb;
        assert_eq!(p.stable(), Some(expect_stable), "γ = {}", p.solution.omega);
    }
    // Amplitudes equal those of the shooting orbit (stable or not) on both sides.
    for target in [0.22, 0.275] {
        let p = branch
            .points
            .iter()
            .min_by(|a, b| {
                (a.solution.omega - target)
                    .abs()
                    .total_cmp(&(b.solution.omega - target).abs())
            })
            .expect("points");
        let gamma = p.solution.omega;
        let o = orbit_at(gamma, &y_ref);
        let ti = steady_state(
            &DoubleWellDuffing::reference(gamma),
            OMEGA,
            &o.y,
            period(),
            0,
        )
        .expect("samples")
        .amplitude(0);
        let hb = p.solution.max_abs(0);
        println!("γ = {gamma:.5}: max|x| HB {hb:.10}, shooting {ti:.10}");
        // The sampled orbit's maximum is read on a 4096-point grid (under-estimate up to
        // (2π/4096)²/8 · max|d²x/dθ²| ≈ 1.5e-7); the HB maximum is refined to ~Δt⁴.
        assert!(
            (hb - ti).abs() < 3e-7,
            "γ = {gamma}: HB {hb} vs shooting {ti}"
        );
    }
}
