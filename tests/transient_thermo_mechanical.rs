//! The transient integrator past a thermo-mechanical Neimark–Sacker point of the
//! self-heated Duffing oscillator (`systems::thermo_duffing`): the temperature leaves the
//! orbit in a slow oscillation whose period is the one the tool's crossing pair of
//! exponents (Hill's eigenproblem at the located point) predicts.

use num_complex::Complex64;
use tmrotor::continuation::{Continuation, ContinuationOptions};
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

#[test]
fn past_a_neimark_sacker_point_the_temperature_modulates_at_the_predicted_period() {
    let tau = 100.0 * TAU;
    let system = ThermoDuffing::new(tau);
    let basis = Basis::integer(9).expect("basis");
    let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.8, 1.3);
    opts.ds_max = 0.05;
    opts.scale_mech = Some(1.0);
    opts.scale_therm = Some(1.0);
    opts.scale_omega = Some(1.0);
    let method = Variational::default();
    let mut cont = Continuation::new(hb, opts, Some(&method as _)).expect("continuation");
    let branch = cont.run(|_| {}).expect("branch");
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
