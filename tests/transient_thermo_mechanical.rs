//! The transient integrator past a thermo-mechanical Neimark–Sacker point of the
//! self-heated Duffing oscillator (`systems::thermo_duffing`): the temperature leaves the
//! orbit in a slow oscillation whose period is the one the tool's crossing pair of
//! exponents (Hill's eigenproblem at the located point) predicts; and where no stable
//! orbit exists, the oscillator hunts between the sheets of its frozen response.

use num_complex::Complex64;
use tmrotor::continuation::{Branch, Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance, HbSolution, NewtonOptions, newton};
use tmrotor::integrate::{SpeedProfile, ThermalStepping, Transient, TransientOptions};
use tmrotor::stability::{BifurcationKind, HillOptions, HillPencil, Variational};
use tmrotor::system::PeriodicOrbit;
use tmrotor::systems::thermo_duffing::ThermoDuffing;

const TAU: f64 = std::f64::consts::TAU;

/// Fixed steps (1000 a period, so that the period map is smooth), no numerical damping,
/// and the temperature advanced at every step: beside a fold the vibration is so sensitive
/// to the temperature that its ripple within a period matters (held over a period, as the
/// averaged macro steps do, it moves the orbit by 2e-3 here; docs/transient.md).
fn fixed_steps() -> TransientOptions {
    TransientOptions {
        rtol: 0.5,
        atol: 1.0,
        min_steps_per_revolution: 1000,
        alpha: 0.0,
        thermal: ThermalStepping::EveryStep,
        ..TransientOptions::default()
    }
}

/// The integrator's own periodic orbit at `w` by Newton on its period map, from `y`.
fn periodic_orbit(system: &ThermoDuffing, w: f64, mut y: [f64; 3]) -> [f64; 3] {
    let map = |y: [f64; 3]| {
        let mut tr = Transient::new(
            system,
            SpeedProfile::Constant(w),
            &[y[0]],
            &[y[1]],
            &[y[2]],
            fixed_steps(),
        )
        .expect("transient");
        tr.advance(TAU / w, &mut |_| true).expect("advance");
        let (x, v, t) = tr.state();
        [x[0], v[0], t[0]]
    };
    for _ in 0..10 {
        let fy = map(y);
        let r: Vec<f64> = (0..3).map(|i| fy[i] - y[i]).collect();
        let mut jac = nalgebra::Matrix3::<f64>::zeros();
        for j in 0..3 {
            let mut yp = y;
            let d = 1e-7 * y[j].abs().max(1e-3);
            yp[j] += d;
            let fp = map(yp);
            for i in 0..3 {
                jac[(i, j)] = (fp[i] - yp[i] - r[i]) / d;
            }
        }
        let dy = jac
            .lu()
            .solve(&nalgebra::Vector3::new(-r[0], -r[1], -r[2]))
            .expect("Newton step");
        for i in 0..3 {
            y[i] += dy[i];
        }
        if dy.norm() < 1e-13 {
            let m = jac + nalgebra::Matrix3::<f64>::identity();
            println!(
                "multipliers of the period map {:?}",
                m.complex_eigenvalues()
            );
            break;
        }
    }
    y
}

/// The self-heated oscillator's branch on `basis` from Ω = 0.8 to `end`, with the
/// variational equations' stability.
fn coupled_branch(system: &ThermoDuffing, basis: &Basis, end: f64) -> Branch {
    let hb = HarmonicBalance::new(system, basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.8, end);
    opts.ds_max = 0.05;
    opts.scale_mech = Some(1.0);
    opts.scale_therm = Some(1.0);
    opts.scale_omega = Some(1.0);
    let method = Variational::default();
    let mut cont = Continuation::new(hb, opts, Some(&method as _)).expect("continuation");
    cont.run(|_| {}).expect("branch")
}

#[test]
fn past_a_neimark_sacker_point_the_temperature_modulates_at_the_predicted_period() {
    let tau = 100.0 * TAU;
    let system = ThermoDuffing::new(tau);
    let basis = Basis::integer(9).expect("basis");
    let branch = coupled_branch(&system, &basis, 1.3);
    let ns = branch
        .bifurcations
        .iter()
        .find(|p| p.bifurcation == Some(BifurcationKind::NeimarkSacker))
        .expect("a located Neimark–Sacker point");
    let w_ns = ns.solution.omega;
    let w = w_ns + 2e-5;
    let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
    let (a, st) = newton::solve_fixed(&hb, w, &ns.solution.unknowns(), &NewtonOptions::default())
        .expect("the orbit past the point");
    let start = HbSolution::from_unknowns(w, &basis, 1, &a, &st);
    let lambda: Complex64 = HillPencil::new(&hb, &start, None)
        .expect("pencil")
        .near_zero(3, &HillOptions::default())
        .expect("near zero")
        .exponents
        .into_iter()
        .max_by(|a, b| a.re.total_cmp(&b.re))
        .expect("exponents");
    let predicted = w / lambda.im.abs(); // forcing periods
    println!(
        "Neimark–Sacker at {w_ns:.7}; at {w:.7} λ = {lambda:.4e}, predicted {predicted:.2} periods"
    );
    assert!(lambda.re > 0.0 && lambda.im.abs() > 0.0, "{lambda}");
    let (mut x, mut v, mut th) = ([0.0], [0.0], [0.0]);
    start.state_at(0.0, &mut x, &mut v, &mut th);
    let y = periodic_orbit(&system, w, [x[0], v[0], th[0]]);
    let theta0 = y[2];
    println!(
        "orbit of the map against the balance's: {:?}",
        [y[0] - x[0], y[1] - v[0], y[2] - th[0]]
    );
    let mut tr = Transient::new(
        &system,
        SpeedProfile::Constant(w),
        &[y[0]],
        &[y[1]],
        &[y[2] + 1e-6],
        fixed_steps(),
    )
    .expect("transient");
    let n_periods = (16.0 * predicted) as usize;
    let mut dev = Vec::with_capacity(n_periods);
    for p in 1..=n_periods {
        tr.advance(p as f64 * TAU / w, &mut |_| true)
            .expect("advance");
        let d = tr.state().2[0] - theta0;
        dev.push(d);
        if d.abs() > 1e-4 {
            break;
        }
    }
    let maxima: Vec<f64> = (1..dev.len() - 1)
        .filter(|&i| dev[i] > dev[i - 1] && dev[i] >= dev[i + 1] && dev[i] > 0.0)
        .map(|i| {
            let (a, b, c) = (dev[i - 1], dev[i], dev[i + 1]);
            i as f64 + 0.5 * (a - c) / (a - 2.0 * b + c)
        })
        .collect();
    println!(
        "{} periods, maxima at {maxima:.1?}, deviation at the end {:.3e}",
        dev.len(),
        dev[dev.len() - 1]
    );
    assert!(
        maxima.len() >= 4,
        "{} maxima: {:?}",
        maxima.len(),
        &dev[..dev.len().min(40)]
    );
    let measured = (maxima[maxima.len() - 1] - maxima[0]) / (maxima.len() - 1) as f64;
    println!("measured {measured:.2} periods against {predicted:.2}");
    assert!(
        (measured / predicted - 1.0).abs() < 0.01,
        "{measured} against {predicted}"
    );
}

/// Thermal hunting: with stronger heating (`α = 3`) the coupled branch of the
/// self-heated oscillator does not fold, and between its two Neimark–Sacker points its
/// orbit, the only periodic orbit there, is unstable (the variational equations'
/// multipliers). In time the oscillator then relaxes back and forth between the two sheets
/// of the frozen-temperature response: it heats on the upper sheet until it falls off,
/// cools on the lower one until it jumps back up, over thermal time constants, and never
/// settles.
#[test]
fn where_no_stable_orbit_exists_the_oscillator_hunts_between_the_sheets() {
    let tau = 100.0 * TAU;
    let mut system = ThermoDuffing::new(tau);
    system.heating = 3.0;
    let basis = Basis::integer(9).expect("basis");
    let branch = coupled_branch(&system, &basis, 1.6);
    let kinds = |k| {
        branch
            .bifurcations
            .iter()
            .filter(|p| p.bifurcation == Some(k))
            .map(|p| p.solution.omega)
            .collect::<Vec<f64>>()
    };
    let (ns, folds) = (
        kinds(BifurcationKind::NeimarkSacker),
        kinds(BifurcationKind::SaddleNode),
    );
    println!("Neimark–Sacker points at {ns:.5?}, folds at {folds:.5?}");
    assert!(folds.is_empty(), "the coupled branch folds at {folds:?}");
    assert_eq!(ns.len(), 2, "{ns:?}");
    // midway between the points: the branch passes once, unstable
    let w = 0.5 * (ns[0] + ns[1]);
    let crossing: Vec<_> = branch
        .points
        .windows(2)
        .filter(|q| (q[0].solution.omega - w) * (q[1].solution.omega - w) <= 0.0)
        .collect();
    assert_eq!(crossing.len(), 1, "the branch passes {w} once");
    assert_eq!(crossing[0][0].stable(), Some(false));
    assert_eq!(crossing[0][1].stable(), Some(false));
    let orbit = &crossing[0][0].solution;
    let (mut x, mut v, mut th) = ([0.0], [0.0], [0.0]);
    orbit.state_at(0.0, &mut x, &mut v, &mut th);
    let hunt = |steps: u32| -> (f64, f64, usize, f64) {
        let mut tr = Transient::new(
            &system,
            SpeedProfile::Constant(w),
            &x,
            &v,
            &th,
            TransientOptions {
                min_steps_per_revolution: steps,
                ..fixed_steps()
            },
        )
        .expect("transient");
        // per forcing period: the largest |x| and the temperature at its end
        let period = TAU / w;
        let periods = 4000; // about 40 thermal time constants
        let mut amp = Vec::with_capacity(periods);
        let mut theta = Vec::with_capacity(periods);
        for p in 1..=periods {
            let mut peak: f64 = 0.0;
            tr.advance(p as f64 * period, &mut |s| {
                peak = peak.max(s.x[0].abs());
                true
            })
            .expect("advance");
            amp.push(peak);
            theta.push(tr.state().2[0]);
        }
        // after the first 10 τ: the amplitude keeps swinging between the sheets
        let late = &amp[1000..];
        // the sheets' levels: the 10th and 90th percentiles of the amplitude (the extremes
        // fall inside the jumps, where a period's peak depends on where it was sampled)
        let mut sorted = late.to_vec();
        sorted.sort_by(f64::total_cmp);
        let (lo, hi) = (sorted[sorted.len() / 10], sorted[sorted.len() * 9 / 10]);
        let (t_lo, t_hi) = theta[1000..]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        // jumps up: from within a quarter of the gap of the lower level to within a
        // quarter of the upper one (with that hysteresis, the ringing after a jump is not
        // counted as another)
        let (to_high, to_low) = (lo + 0.75 * (hi - lo), lo + 0.25 * (hi - lo));
        let mut high = late[0] > 0.5 * (lo + hi);
        let mut ups = Vec::new();
        for (i, &a) in late.iter().enumerate() {
            if !high && a > to_high {
                high = true;
                ups.push(i);
            } else if high && a < to_low {
                high = false;
            }
        }
        let cycle = if ups.len() >= 2 {
            (ups[ups.len() - 1] - ups[0]) as f64 / (ups.len() - 1) as f64
        } else {
            f64::NAN
        };
        println!(
            "{steps} steps a period, Ω = {w:.5}: amplitude levels {lo:.3} and {hi:.3}, temperature \
             {t_lo:.3} … {t_hi:.3}, {} jumps up, a cycle of {cycle:.1} periods ({:.2} τ); \
             the orbit's amplitude {:.3}",
            ups.len(),
            cycle * period / tau,
            orbit.max_abs(0)
        );
        (lo, hi, ups.len(), cycle * period / tau)
    };
    let (lo, hi, jumps, tau_cycles) = hunt(200);
    assert!(hi > 1.5 * lo, "no jump between the sheets: {lo} … {hi}");
    assert!(jumps >= 3, "{jumps} jumps up in 30 τ");
    // the cycle is thermal: of the order of the thermal time constant, not of the
    // vibration's period
    assert!(
        (0.1..20.0).contains(&tau_cycles),
        "a cycle of {tau_cycles} τ"
    );
    // and a property of the equations, not of the steps: twice as many give the same
    let (lo2, hi2, _, tau_cycles2) = hunt(400);
    assert!(
        (tau_cycles2 / tau_cycles - 1.0).abs() < 0.02
            && (hi2 / hi - 1.0).abs() < 0.02
            && (lo2 / lo - 1.0).abs() < 0.02,
        "{tau_cycles} τ, {lo} … {hi} against {tau_cycles2} τ, {lo2} … {hi2}"
    );
}

/// A start along a Floquet mode (`StartState::along_mode`, `tmrotor transient
/// --perturb-mode`): on the middle, unstable segment of the self-heated oscillator's
/// branch the mode of the real positive exponent λ leads away from the orbit at the rate
/// λ (the time integration's own, measured) and in the direction of its sign: one side
/// towards the upper sheet, the other towards the lower (at this speed the lower sheet is
/// unstable too, beyond its Neimark–Sacker point, and both runs end on the upper one).
#[test]
fn a_start_along_the_unstable_mode_leaves_at_its_rate_to_either_side() {
    let tau = 100.0 * TAU;
    let system = ThermoDuffing::new(tau);
    let basis = Basis::integer(9).expect("basis");
    let branch = coupled_branch(&system, &basis, 1.3);
    let folds: Vec<&HbSolution> = branch
        .bifurcations
        .iter()
        .filter(|p| p.bifurcation == Some(BifurcationKind::SaddleNode))
        .map(|p| &p.solution)
        .collect();
    assert_eq!(folds.len(), 2);
    // a point of the middle segment, between the folds along the branch
    let (a0, a1) = (folds[0].max_abs(0), folds[1].max_abs(0));
    let mid = branch
        .points
        .iter()
        .filter(|p| p.stable() == Some(false))
        .map(|p| &p.solution)
        .min_by(|p, q| {
            let m = 0.5 * (a0 + a1);
            (p.max_abs(0) - m)
                .abs()
                .total_cmp(&(q.max_abs(0) - m).abs())
        })
        .expect("a middle point");
    let w = mid.omega;
    let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
    let run = |size: f64| -> (f64, Vec<f64>, Vec<f64>) {
        let (start, mode) =
            tmrotor::transient::StartState::along_mode(mid, &hb, 0, size, "middle".into())
                .expect("start along the mode");
        let mut tr = Transient::new(
            &system,
            SpeedProfile::Constant(w),
            &start.x,
            &start.v,
            &start.temp,
            fixed_steps(),
        )
        .expect("transient");
        // the temperature's distance from the orbit's at the same phase, once a period
        let (mut x, mut v, mut th) = ([0.0], [0.0], [0.0]);
        mid.state_at(0.0, &mut x, &mut v, &mut th);
        let theta0 = th[0];
        let mut dev = vec![start.temp[0] - theta0];
        let period = TAU / w;
        let mut amp = Vec::new();
        for p in 1..=300 {
            let mut peak: f64 = 0.0;
            tr.advance(p as f64 * period, &mut |s| {
                peak = peak.max(s.x[0].abs());
                true
            })
            .expect("advance");
            dev.push(tr.state().2[0] - theta0);
            amp.push(peak);
        }
        (mode.exponent.re, dev, amp)
    };
    let (lambda, up, amp_plus) = run(1e-3);
    let (_, down, amp_minus) = run(-1e-3);
    assert!(lambda > 0.0, "the middle point's leading exponent {lambda}");
    // the rate: the deviation's growth between 3 and 100 times its start, where it is
    // still small against the orbit
    let period = TAU / w;
    let rate = |dev: &[f64]| -> f64 {
        let d0 = dev[0].abs();
        let i = dev.iter().position(|d| d.abs() > 3.0 * d0).expect("growth");
        let j = dev
            .iter()
            .position(|d| d.abs() > 100.0 * d0)
            .expect("growth");
        println!(
            "deviation {:.2e} → {:.2e} (periods {i} → {j})",
            dev[i], dev[j]
        );
        (dev[j].abs() / dev[i].abs()).ln() / ((j - i) as f64 * period)
    };
    let (r_up, r_down) = (rate(&up), rate(&down));
    // where the deviation first reaches a hundred times its start: the vibration there
    let at = |dev: &[f64], amp: &[f64]| {
        let j = dev
            .iter()
            .position(|d| d.abs() > 100.0 * dev[0].abs())
            .expect("growth");
        amp[j - 1]
    };
    let (a_up, a_down) = (at(&up, &amp_plus), at(&down, &amp_minus));
    let orbit_amp = mid.max_abs(0);
    println!(
        "Ω = {w:.5}: λ = {lambda:.5e} 1/s; measured {r_up:.5e} and {r_down:.5e}; amplitudes \
         {a_up:.4} and {a_down:.4} against the orbit's {orbit_amp:.4} (folds {a0:.4}, {a1:.4})"
    );
    for r in [r_up, r_down] {
        assert!((r / lambda - 1.0).abs() < 0.02, "{r} against {lambda}");
    }
    // opposite sides: the deviations grow with opposite signs, the vibration one side
    // above the orbit's and the other below
    assert!(up[10].signum() != down[10].signum());
    assert!(
        (a_up - orbit_amp) * (a_down - orbit_amp) < 0.0,
        "{a_up} and {a_down} around {orbit_amp}"
    );
}
