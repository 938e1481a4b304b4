//! A forced Duffing oscillator heated by its own damping: the smallest system with the
//! structure of the thermo-mechanical rotor (fast nonlinear vibration, slow temperatures
//! heated by it, the temperatures acting back on the stiffness).
//!
//! ```text
//!   ẍ + c ẋ + k x + k₃ x³ − κ θ₁ x = F cos Ωt                      (ω = Ω)
//!   τ₁ θ̇₁ + θ₁ + g (θ₁ − θ₂)       = α c ẋ²                         (heat of the damping)
//!   τ₂ θ̇₂ + θ₂ + g (θ₂ − θ₁)       = 0                              (optional second state)
//! ```
//!
//! Heating softens the spring (`κ > 0`), opposing the cubic hardening: the coupled
//! branch bends less than the branch with the temperatures frozen, so the frozen branch
//! can fold where the coupled one does not. There the coupled orbit loses its stability
//! through a complex pair of slow multipliers (a Neimark–Sacker point beside the frozen
//! fold), the mechanism [`crate::stability::hill_near_zero`] resolves. The default
//! parameters are those of [`crate::systems::duffing::Duffing`] (`c = 0.05, k = 1,
//! k₃ = 0.1, F = 0.18`) with `κ = 1`, `α = 2`, `τ₁ = 100` forcing periods at `Ω = 1`
//! (`200π`), one thermal state.
//!
//! Nondimensional; the temperatures are rises above ambient.

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// The self-heated Duffing oscillator (see the module docs).
#[derive(Clone, Debug)]
pub struct ThermoDuffing {
    pub damping: f64,
    pub stiffness: f64,
    pub cubic: f64,
    pub force: f64,
    /// Softening per unit temperature `κ`.
    pub softening: f64,
    /// Heat per unit damping power `α`.
    pub heating: f64,
    /// Thermal time constants `τ₁` (and `τ₂` for a second state), s.
    pub tau: Vec<f64>,
    /// Conductance between the two states `g` (relative to the loss to ambient).
    pub link: f64,
    nl: NonlinearDofs,
}

impl Default for ThermoDuffing {
    fn default() -> Self {
        Self::new(100.0 * std::f64::consts::TAU)
    }
}

impl ThermoDuffing {
    /// The default oscillator with one thermal state of time constant `tau` (s).
    pub fn new(tau: f64) -> Self {
        Self {
            damping: 0.05,
            stiffness: 1.0,
            cubic: 0.1,
            force: 0.18,
            softening: 1.0,
            heating: 2.0,
            tau: vec![tau],
            link: 0.0,
            nl: NonlinearDofs {
                mech: vec![0],
                therm: vec![0],
            },
        }
    }

    /// The same with a second, passive thermal state of time constant `tau2` linked to
    /// the first by the conductance `link`.
    pub fn with_second_state(mut self, tau2: f64, link: f64) -> Self {
        self.tau.truncate(1);
        self.tau.push(tau2);
        self.link = link;
        self
    }
}

impl System for ThermoDuffing {
    fn n_mech(&self) -> usize {
        1
    }

    fn n_therm(&self) -> usize {
        self.tau.len()
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        let nt = self.tau.len();
        let mut cap = DenseMatrix::zeros(nt);
        let mut cond = DenseMatrix::zeros(nt);
        for (i, t) in self.tau.iter().enumerate() {
            *cap.get_mut(i, i) = *t;
            *cond.get_mut(i, i) = 1.0;
        }
        if nt == 2 {
            for (i, j) in [(0, 1), (1, 0)] {
                cond.add(i, i, self.link);
                cond.add(i, j, -self.link);
            }
        }
        LinearPart {
            mass: DenseMatrix::scalar(1.0),
            damping: DenseMatrix::scalar(self.damping),
            stiffness: DenseMatrix::scalar(self.stiffness),
            thermal_capacity: cap,
            thermal_conductance: cond,
        }
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
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        let (x, v, th) = (x[0], v[0], temp[0]);
        out.f[0] = self.cubic * x.powi(3) - self.softening * th * x;
        out.df_dx[0] = 3.0 * self.cubic * x * x - self.softening * th;
        out.df_dv[0] = 0.0;
        out.df_dt[0] = -self.softening * x;
        let q = self.heating * self.damping;
        out.g[0] = -q * v * v;
        out.dg_dx[0] = 0.0;
        out.dg_dv[0] = -2.0 * q * v;
        out.dg_dt[0] = 0.0;
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = self.force * (omega * t).cos();
    }
}
