//! The transient integrator (`integrate::Transient`) and `tmrotor transient`, each against
//! a reference that shares nothing with the code under test: the closed-form response of
//! a linear oscillator, the harmonic-balance orbit of a sweep, an adaptive Runge–Kutta
//! integration of the equations written out here, and the single-rate run for the
//! multi-rate thermal steps.

use tmrotor::hb::{Basis, HarmonicBalance, HbSolution, NewtonOptions, newton};
use tmrotor::integrate::{
    Dopri5, Dopri5Options, SpeedProfile, ThermalStepping, Transient, TransientOptions,
};
use tmrotor::record::MemoryTransient;
use tmrotor::sweep::{StudySettings, SweepProblem};
use tmrotor::system::{PeriodicOrbit, System};
use tmrotor::systems::duffing::Duffing;
use tmrotor::systems::thermo_duffing::ThermoDuffing;
use tmrotor::transient::{StartState, TransientSettings, run_transient};

const TAU: f64 = std::f64::consts::TAU;

fn tight() -> TransientOptions {
    TransientOptions {
        rtol: 1e-9,
        atol: 1e-14,
        ..TransientOptions::default()
    }
}

/// `ẍ + c ẋ + k x = F cos Ωt` from rest: the closed-form steady state plus the free
/// response that matches the start.
#[test]
fn a_linear_oscillator_from_rest_follows_the_closed_form() {
    let (c, k, f, w) = (0.1, 4.0, 0.5, 1.5);
    let sys = Duffing::new(1.0, c, k, 0.0, f);
    let mut tr = Transient::new(
        &sys,
        SpeedProfile::Constant(w),
        &[0.0],
        &[0.0],
        &[],
        tight(),
    )
    .expect("transient");
    // steady state X cos(Ωt − ψ)
    let (re, im) = (k - w * w, c * w);
    let den = re * re + im * im;
    let (a, b) = (f * re / den, f * im / den); // x_p = a cos + b sin
    let wn = k.sqrt();
    let zeta = c / (2.0 * wn);
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    // x_h = e^{−ζωn t}(C1 cos ωd t + C2 sin ωd t), x(0) = 0, v(0) = 0
    let c1 = -a;
    let c2 = (-(b * w) + zeta * wn * c1) / wd;
    let exact = |t: f64| {
        a * (w * t).cos()
            + b * (w * t).sin()
            + (-zeta * wn * t).exp() * (c1 * (wd * t).cos() + c2 * (wd * t).sin())
    };
    let mut worst: f64 = 0.0;
    for k in 1..=40 {
        let t = k as f64 * 0.5;
        tr.advance(t, &mut |_| true).expect("advance");
        worst = worst.max((tr.state().0[0] - exact(t)).abs());
    }
    let amplitude = (a * a + b * b).sqrt();
    println!("largest error over 20 s: {worst:.3e} (amplitude {amplitude:.3e})");
    // a second-order method: the global error goes like rtol^(2/3) (local errors of order
    // h³ over 1/h steps), 1e-6 of the amplitude at rtol 1e-9 … here about 1e-5
    assert!(worst < 3e-5 * amplitude, "{worst:e}");
}

/// The accuracy follows the tolerance: the local error is held to rtol, so the global
/// error of the second-order scheme falls like rtol^(2/3), 4.6× for 10× tighter rtol.
#[test]
fn the_error_follows_the_tolerance() {
    let (c, k, f, w) = (0.1, 4.0, 0.5, 1.5);
    let sys = Duffing::new(1.0, c, k, 0.0, f);
    let reference = {
        let mut tr = Transient::new(
            &sys,
            SpeedProfile::Constant(w),
            &[0.0],
            &[0.0],
            &[],
            tight(),
        )
        .expect("transient");
        tr.advance(10.0, &mut |_| true).expect("advance");
        tr.state().0[0]
    };
    let mut errors = Vec::new();
    for rtol in [1e-4, 1e-5, 1e-6] {
        let opts = TransientOptions {
            rtol,
            atol: 1e-14,
            ..TransientOptions::default()
        };
        let mut tr = Transient::new(&sys, SpeedProfile::Constant(w), &[0.0], &[0.0], &[], opts)
            .expect("transient");
        tr.advance(10.0, &mut |_| true).expect("advance");
        errors.push((tr.state().0[0] - reference).abs());
    }
    println!("errors at rtol 1e-4, 1e-5, 1e-6: {errors:?}");
    assert!(
        errors[0] > 3.0 * errors[1] && errors[1] > 3.0 * errors[2],
        "{errors:?}"
    );
    assert!(errors[0] < 2e-2 * 0.28, "{errors:?}");
}

/// From rest the Duffing oscillator settles onto its harmonic-balance orbit; the
/// difference falls with the truncation order until it reaches the integrator's error.
#[test]
fn a_duffing_oscillator_settles_on_its_harmonic_balance_orbit() {
    let sys = Duffing::default();
    let w = 0.7; // below the fold: one stable orbit
    let periods = 400.0;
    let mut tr = Transient::new(
        &sys,
        SpeedProfile::Constant(w),
        &[0.0],
        &[0.0],
        &[],
        tight(),
    )
    .expect("transient");
    let t_end = periods * TAU / w;
    tr.advance(t_end, &mut |_| true).expect("advance");
    let (x, v, _) = tr.state();
    let (x, v) = (x[0], v[0]);
    let mut diffs = Vec::new();
    for order in [1, 3, 5, 7] {
        let basis = Basis::integer(order).expect("basis");
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let a0 = vec![0.0; basis.n_coeffs()];
        let (a, st) = newton::solve_fixed(&hb, w, &a0, &NewtonOptions::default()).expect("hb");
        let sol = HbSolution::from_unknowns(w, &basis, 1, &a, &st);
        let (mut xs, mut vs, mut ts) = ([0.0], [0.0], [0.0; 0]);
        sol.state_at(t_end, &mut xs, &mut vs, &mut ts);
        diffs.push((xs[0] - x).abs().max((vs[0] - v).abs() / w));
    }
    println!("|transient − HB| at orders 1, 3, 5, 7: {diffs:?} (x = {x:.5})");
    // order 1 is far off; from order 5 on the truncation error is below the integrator's
    // (rtol 1e-9: about 2.5e-7 here)
    assert!(diffs[0] > 100.0 * diffs[3], "{diffs:?}");
    assert!(diffs[1] > diffs[2], "{diffs:?}");
    assert!(diffs[3] < 1e-6, "{diffs:?}");
}

/// A run-up of a linear oscillator through its resonance at a constant acceleration
/// (`ẍ + c ẋ + k x = F cos φ(t)`, `φ = ω₀t + at²/2`) against Dormand–Prince on the
/// same equation written here: the peak's size and the speed where it occurs, which
/// lies past the resonance (the lag of a passage at finite acceleration).
#[test]
fn a_run_up_through_resonance_matches_runge_kutta() {
    let (c, k, f) = (0.04, 1.0, 0.1);
    let (w0, w1, accel) = (0.5, 1.5, 0.002);
    let sys = Duffing::new(1.0, c, k, 0.0, f);
    let profile = SpeedProfile::Ramp {
        from: w0,
        to: w1,
        accel,
    };
    let t_end = (w1 - w0) / accel;
    let opts = TransientOptions {
        rtol: 1e-7,
        atol: 1e-12,
        ..TransientOptions::default()
    };
    let mut tr =
        Transient::new(&sys, profile.clone(), &[0.0], &[0.0], &[], opts).expect("transient");
    let mut peak = (0.0f64, 0.0f64);
    tr.advance(t_end, &mut |s| {
        if s.x[0].abs() > peak.0 {
            peak = (s.x[0].abs(), s.omega);
        }
        true
    })
    .expect("advance");
    let mut rk = Dopri5::new(
        2,
        Dopri5Options {
            rtol: 1e-11,
            atol: 1e-13,
            h_max: 0.05,
            ..Dopri5Options::default()
        },
    );
    let mut y = [0.0, 0.0];
    let mut rk_peak = (0.0f64, 0.0f64);
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        let phi = w0 * t + 0.5 * accel * t * t;
        dy[0] = y[1];
        dy[1] = f * phi.cos() - c * y[1] - k * y[0];
    };
    rk.integrate_observed(&mut rhs, 0.0, &mut y, t_end, &mut |s| {
        if s.y1[0].abs() > rk_peak.0 {
            rk_peak = (s.y1[0].abs(), w0 + accel * s.t1);
        }
    })
    .expect("dopri");
    let steady_peak = f / (c * 1.0);
    println!(
        "peak {:.6} at ω {:.5} (Runge–Kutta {:.6} at {:.5}); steady-state peak {steady_peak:.4} at 1",
        peak.0, peak.1, rk_peak.0, rk_peak.1
    );
    assert!(
        (peak.0 / rk_peak.0 - 1.0).abs() < 2e-3,
        "{peak:?} {rk_peak:?}"
    );
    assert!((peak.1 - rk_peak.1).abs() < 2e-3, "{peak:?} {rk_peak:?}");
    assert!(peak.1 > 1.0 && peak.0 < steady_peak, "{peak:?}");
}

/// The multi-rate thermal steps (heat averaged over up to 50 revolutions) against the
/// single-rate run (temperatures advanced after every step), the self-heated Duffing
/// oscillator warming up from cold over three thermal time constants.
#[test]
fn averaged_thermal_steps_agree_with_the_single_rate_run() {
    let tau = 100.0 * TAU;
    let system = ThermoDuffing::new(tau);
    let w = 0.9;
    let t_end = 3.0 * tau;
    let run = |thermal| {
        let opts = TransientOptions {
            rtol: 1e-6,
            thermal,
            ..TransientOptions::default()
        };
        let mut tr = Transient::new(
            &system,
            SpeedProfile::Constant(w),
            &[0.0],
            &[0.0],
            &[0.0],
            opts,
        )
        .expect("transient");
        tr.advance(t_end, &mut |_| true).expect("advance");
        (tr.state().2[0], tr.stats().thermal_steps)
    };
    let (single, n_single) = run(ThermalStepping::EveryStep);
    // the default tolerances are in kelvin for rotor temperatures of tens of degrees;
    // this oscillator's temperatures are nondimensional rises of about 0.03
    let (averaged, n_averaged) = run(ThermalStepping::Averaged {
        max_revolutions: 50,
        temp_tol: 1e-7,
        max_temp_step: 1e-3,
    });
    println!(
        "temperature after 3τ: single rate {single:.6} ({n_single} thermal steps), averaged {averaged:.6} ({n_averaged})"
    );
    assert!(single > 0.01, "{single}");
    assert!(
        (averaged - single).abs() < 2e-3 * single,
        "{averaged} against {single}"
    );
    assert!(
        n_averaged * 20 < n_single,
        "{n_averaged} against {n_single}"
    );
}

/// The dual rotor started on a recorded harmonic-balance point stays on it: the RMS
/// amplitudes of the last basis period against the point's (Eq. 35), and the recording's
/// revolutions in time order.
#[test]
fn the_dual_rotor_stays_on_its_harmonic_balance_point() {
    let settings = StudySettings::default();
    let problem = SweepProblem::new(&settings).expect("problem");
    let sys = &problem.system;
    let w = 400.0;
    let hb = HarmonicBalance::new(sys, &problem.basis, None).expect("hb");
    let a0 = sys.initial_guess(problem.basis.n_coeffs());
    let (a, st) = newton::solve_fixed(&hb, w, &a0, &NewtonOptions::default()).expect("hb");
    let sol = HbSolution::from_unknowns(w, &problem.basis, sys.n_mech(), &a, &st);
    let amplitude = tmrotor::derive::amplitude_rms(&problem.run, &sol.mech).expect("amplitudes");
    let start = StartState::on_orbit(&sol, sys.n_mech(), sys.n_therm(), "HB point".into());
    let t = TransientSettings {
        profile: SpeedProfile::Constant(w),
        duration_s: 20.0 * TAU / w,
        options: TransientOptions::default(),
        samples_per_revolution: 8,
    };
    let mut sink = MemoryTransient::default();
    let report = run_transient(&problem, &start, &t, &mut sink, &mut |_| {}, None).expect("run");
    assert_eq!(report.revolutions, 20);
    assert_eq!(sink.revolutions.len(), 20);
    assert!(
        sink.revolutions
            .windows(2)
            .all(|r| r[1].time_s > r[0].time_s)
    );
    let last = &sink.revolutions[19];
    let worst = amplitude
        .iter()
        .zip(&last.amplitude_rms_m)
        .map(|(a, b)| (a - b).abs() / amplitude.iter().cloned().fold(0.0, f64::max))
        .fold(0.0, f64::max);
    println!("RMS amplitudes, largest difference {worst:.3e} of the largest amplitude");
    // 1e-2 at 400 rad/s: not the integrator (the same at rtol 1e-3 … 1e-6, and Dormand–Prince
    // at rtol 1e-8 leaves the harmonic-balance orbit by the same 1e-8 m within one
    // revolution) but the cages' varying compliance, whose frequency N_b·ω_c no basis holds:
    // the time response carries it, the balance only its alias (docs/transient.md)
    assert!(worst < 2e-2, "{worst}");
    // temperatures stay at the point's mean (their harmonics are below 1e-3 K)
    let therm = |n: usize| sol.therm[n * problem.basis.n_coeffs()];
    let dt = problem
        .run
        .thermal_nodes
        .iter()
        .zip(&last.temperature_c)
        .map(|(n, t)| (t - therm(n.dof)).abs())
        .fold(0.0, f64::max);
    assert!(dt < 1e-2, "{dt} K");
    assert!(sink.samples.len() >= 8 * 19, "{}", sink.samples.len());
}

/// Near the 522 rad/s resonance of the built-in model the time response carries the
/// combination tones of the two rotors' speeds (ω/5, 4ω/5, 11ω/5, …) that the paper's
/// basis (Eq. 34) lacks: started on the balance with them, the transient stays within
/// about 1 % of it, while the paper's basis is about 10 % off at every order.
#[test]
fn the_time_response_needs_the_combination_tones() {
    let w = 522.5;
    let node = 13; // node 14, the largest amplitude there
    // the sweep's own start at 522.5 rad/s (its first point), without stability
    let solve = |combination_tones: bool| {
        let mut settings = StudySettings::default();
        settings.harmonic.combination_tones = combination_tones;
        settings.sweep.omega_start = w;
        settings.sweep.omega_end = w + 0.5;
        settings.sweep.max_points = 2;
        settings.floquet.stability = false;
        let problem = SweepProblem::new(&settings).expect("problem");
        let mut sink = tmrotor::record::MemorySink::default();
        problem.run(&mut sink, None, |_| {}).expect("sweep");
        let point = sink.points[0].clone();
        assert_eq!(point.omega_rad_s, w);
        let sol = tmrotor::derive::CoupledRederive::from_run(&problem.run)
            .expect("rederive")
            .solution(&point);
        (problem, sol, point.amplitude_rms_m[node])
    };
    let (_, _, paper) = solve(false);
    let (problem, sol, combined) = solve(true);
    let sys = &problem.system;
    let start = StartState::on_orbit(&sol, sys.n_mech(), sys.n_therm(), "HB point".into());
    let t = TransientSettings {
        profile: SpeedProfile::Constant(w),
        duration_s: 30.0 * TAU / w,
        options: TransientOptions::default(),
        samples_per_revolution: 0,
    };
    let mut sink = MemoryTransient::default();
    run_transient(&problem, &start, &t, &mut sink, &mut |_| {}, None).expect("run");
    let timed = sink
        .revolutions
        .last()
        .expect("revolutions")
        .amplitude_rms_m[node];
    println!(
        "node 14 at {w} rad/s: time response {:.4} µm, balance with combination tones {:.4} µm, paper's basis {:.4} µm",
        timed * 1e6,
        combined * 1e6,
        paper * 1e6
    );
    assert!((timed / combined - 1.0).abs() < 0.015, "{timed} {combined}");
    assert!((timed / paper - 1.0).abs() > 0.05, "{timed} {paper}");
}
