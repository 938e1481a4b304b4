//! The time integrator against closed-form responses: a damped linear oscillator's steady
//! amplitude and phase, and a first-order thermal node's exponential approach; RK4 and
//! Dormand–Prince against each other on a nonlinear problem.

use tmrotor::integrate::{Dopri5, Dopri5Options, StateSpace, rk4, steady_state};
use tmrotor::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// `m ẍ + c ẋ + k x = F cos Ωt` and `C_T Ṫ + K_T T = Q`, uncoupled.
struct Linear {
    dofs: NonlinearDofs,
    cubic: f64,
}

const MASS: f64 = 2.0;
const DAMP: f64 = 0.3;
const STIFF: f64 = 5.0;
const FORCE: f64 = 0.7;
const CT: f64 = 3.0;
const KT: f64 = 0.5;
const Q: f64 = 2.0;

impl System for Linear {
    fn n_mech(&self) -> usize {
        1
    }
    fn n_therm(&self) -> usize {
        1
    }
    fn linear(&self, _omega: f64) -> LinearPart {
        let s = |v: f64| DenseMatrix {
            n: 1,
            data: vec![v],
        };
        LinearPart {
            mass: s(MASS),
            damping: s(DAMP),
            stiffness: s(STIFF),
            thermal_capacity: s(CT),
            thermal_conductance: s(KT),
        }
    }
    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }
    fn eval_nonlinear(
        &self,
        _omega: f64,
        _t: f64,
        x: &[f64],
        _v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        out.f[0] = self.cubic * x[0].powi(3);
        out.df_dx[0] = 3.0 * self.cubic * x[0] * x[0];
        out.df_dv[0] = 0.0;
    }
    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = FORCE * (omega * t).cos();
    }
    fn thermal_load(&self, _omega: f64, out: &mut [f64]) {
        out[0] = Q;
    }
}

fn linear() -> Linear {
    Linear {
        dofs: NonlinearDofs {
            mech: vec![0],
            therm: vec![],
        },
        cubic: 0.0,
    }
}

#[test]
fn steady_amplitude_and_phase_of_a_linear_oscillator() {
    let sys = linear();
    let omega = 1.3;
    let period = 2.0 * std::f64::consts::PI / omega;
    // Decay rate c/2m = 0.075: 150 periods ≈ 725 s ≈ e^{−54}.
    let ss = steady_state(&sys, omega, &[0.0, 0.0, 0.0], period, 150).expect("settles");
    let (re, im) = (STIFF - MASS * omega * omega, DAMP * omega);
    let amp = FORCE / re.hypot(im);
    // x(t) = amp cos(Ωt − φ), tan φ = cΩ / (k − mΩ²); t0 is a whole number of periods.
    let phi = im.atan2(re);
    let got = ss.amplitude(0);
    println!(
        "amplitude {got} vs {amp}, x(t0) {} vs {}",
        ss.samples[0][0],
        amp * phi.cos()
    );
    assert!((got - amp).abs() < 1e-9 * amp);
    assert!((ss.samples[0][0] - amp * phi.cos()).abs() < 1e-9 * amp);
    assert!((ss.samples[0][1] - amp * omega * phi.sin()).abs() < 1e-9 * amp * omega);
    assert!(ss.periodicity_error < 1e-9);
}

#[test]
fn thermal_node_relaxes_exponentially() {
    let sys = linear();
    let space = StateSpace::new(&sys, 1.0).expect("state space");
    let mut ws = space.workspace();
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| space.rhs(t, y, dy, &mut ws);
    let mut solver = Dopri5::new(3, Dopri5Options::default());
    let mut y = [0.0, 0.0, 1.0];
    solver
        .integrate(&mut rhs, 0.0, &mut y, 10.0)
        .expect("integrates");
    let t_inf = Q / KT;
    let exact = t_inf + (1.0 - t_inf) * (-10.0 * KT / CT).exp();
    assert!((y[2] - exact).abs() < 1e-9 * exact, "{} vs {exact}", y[2]);
}

#[test]
fn rk4_and_dormand_prince_agree_on_a_nonlinear_oscillator() {
    let sys = Linear {
        cubic: 0.4,
        ..linear()
    };
    let space = StateSpace::new(&sys, 1.3).expect("state space");
    let mut ws = space.workspace();
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| space.rhs(t, y, dy, &mut ws);
    let y0 = [1.0, 0.0, 0.0];
    let mut a = y0;
    let mut solver = Dopri5::new(3, Dopri5Options::default());
    solver
        .integrate(&mut rhs, 0.0, &mut a, 20.0)
        .expect("integrates");
    let mut b = y0;
    rk4(&mut rhs, 0.0, &mut b, 20.0, 20_000);
    // RK4 with h = 1e-3: global error ~ h⁴ · O(10) ≈ 1e-11.
    for i in 0..3 {
        assert!(
            (a[i] - b[i]).abs() < 1e-9,
            "component {i}: {} vs {}",
            a[i],
            b[i]
        );
    }
}
