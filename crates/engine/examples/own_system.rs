//! The engine on a system of your own: a two-mass chain whose second mass hangs on an
//! asymmetric, hardening spring with a cubic damper,
//!
//! ```text
//!   m ẍ₀ + c ẋ₀ + k (2x₀ − x₁)                           = F cos Ωt
//!   m ẍ₁ + c ẋ₁ + k (x₁ − x₀) + a₂ x₁² + a₃ x₁³ + d₃ ẋ₁³ = 0
//! ```
//!
//! followed in Ω through both resonances (linear natural frequencies 0.618 and 1.618)
//! by harmonic balance with continuation, with Floquet stability at every point; then one
//! stable orbit is checked against direct time integration.
//!
//! `cargo run --release -p tmrotor-engine --example own_system`
//!
//! Three steps make a system usable by the engine:
//! 1. the linear matrices (`System::linear`, allowed to depend on Ω);
//! 2. the DoFs the nonlinear terms touch (`System::nonlinear_dofs`): here only `x₁`, so
//!    the engine condenses `x₀` away and the cost grows with one DoF, not two;
//! 3. the nonlinear terms with their exact partial derivatives (`System::eval_nonlinear`),
//!    from which the engine builds the exact harmonic-balance Jacobian.

use tmrotor_engine::continuation::{Continuation, ContinuationOptions, FinishReason};
use tmrotor_engine::hb::{Basis, HarmonicBalance};
use tmrotor_engine::integrate::steady_state;
use tmrotor_engine::stability::ExpSip;
use tmrotor_engine::system::{
    DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, PeriodicOrbit, System,
};

/// The two-mass chain with a nonlinear spring and damper at the second mass.
struct Chain2 {
    m: f64,
    c: f64,
    k: f64,
    a2: f64,
    a3: f64,
    d3: f64,
    force: f64,
    nl: NonlinearDofs,
}

impl System for Chain2 {
    fn n_mech(&self) -> usize {
        2
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        let diag = |v: f64| DenseMatrix {
            n: 2,
            data: vec![v, 0.0, 0.0, v],
        };
        let k = self.k;
        let stiffness = DenseMatrix {
            n: 2,
            data: vec![2.0 * k, -k, -k, k],
        };
        LinearPart::mechanical(diag(self.m), diag(self.c), stiffness)
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.nl
    }

    fn eval_nonlinear(
        &self,
        _omega: f64,
        _t: f64,
        x: &[f64],
        v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        // x and v hold the nonlinear DoFs only, in the order of `nonlinear_dofs` (x₁)
        let (x1, v1) = (x[0], v[0]);
        out.f[0] = self.a2 * x1 * x1 + self.a3 * x1.powi(3) + self.d3 * v1.powi(3);
        out.df_dx[0] = 2.0 * self.a2 * x1 + 3.0 * self.a3 * x1 * x1;
        out.df_dv[0] = 3.0 * self.d3 * v1 * v1;
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = self.force * (omega * t).cos();
        out[1] = 0.0;
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    check()
}

/// Runs the example; an error if the branch stops early or the harmonic-balance
/// amplitude and the time-integrated one differ by more than 1e-6 relative.
pub fn check() -> Result<(), Box<dyn std::error::Error>> {
    let system = Chain2 {
        m: 1.0,
        c: 0.02,
        k: 1.0,
        a2: 0.3,
        a3: 0.5,
        d3: 0.05,
        force: 0.04,
        nl: NonlinearDofs {
            mech: vec![1],
            therm: vec![],
        },
    };
    // harmonics 0..=7: the quadratic term needs the constant and the even harmonics
    let basis = Basis::integer(7)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let stability = ExpSip::default();
    let mut cont = Continuation::new(hb, ContinuationOptions::new(0.3, 2.2), Some(&stability))?;
    let branch = cont.run(|_| {})?;

    println!(
        "{} points from Ω = 0.3 to 2.2 ({:?}), {} unstable",
        branch.points.len(),
        branch.finish,
        branch
            .points
            .iter()
            .filter(|p| p.stable() == Some(false))
            .count()
    );
    for b in &branch.bifurcations {
        if let Some(kind) = b.bifurcation {
            println!(
                "  {kind:?} at Ω = {:.4}, max |x₁| = {:.4}",
                b.solution.omega,
                b.solution.max_abs(1)
            );
        }
    }

    // an independent check: integrate the equations from the orbit's state at t = 0 and
    // compare the settled amplitude with the harmonic-balance one
    let Some(point) = branch
        .points
        .iter()
        .find(|p| p.stable() == Some(true) && p.solution.omega > 1.0)
    else {
        return Err("no stable point above Ω = 1".into());
    };
    let orbit = &point.solution;
    let (mut x, mut v, mut temp) = (vec![0.0; 2], vec![0.0; 2], vec![]);
    orbit.state_at(0.0, &mut x, &mut v, &mut temp);
    let y0: Vec<f64> = x.iter().chain(&v).copied().collect();
    let settled = steady_state(&system, orbit.omega, &y0, orbit.period(), 200)?;
    println!(
        "at Ω = {:.4}: max |x₁| = {:.6} by harmonic balance, {:.6} by time integration \
         (periodicity error {:.1e})",
        orbit.omega,
        orbit.max_abs(1),
        settled.amplitude(1),
        settled.periodicity_error
    );
    if !matches!(branch.finish, FinishReason::Bound { .. }) {
        return Err(format!("the branch stopped early: {:?}", branch.finish).into());
    }
    let (hb_amp, td_amp) = (orbit.max_abs(1), settled.amplitude(1));
    if (hb_amp - td_amp).abs() > 1e-6 * td_amp {
        return Err(format!("amplitudes differ: {hb_amp} against {td_amp}").into());
    }
    Ok(())
}
