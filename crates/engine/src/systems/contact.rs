//! Two masses with a unilateral spring (NLvib's example 3: Krack & Gross, *Harmonic
//! Balance for Nonlinear Vibration Problems*, Springer 2019, and the NLvib toolbox's
//! `EXAMPLE 03`):
//!
//! ```text
//!   M q̈ + D q̇ + K q + f(q₁) e₁ = [0, 0.1 cos Ωt]ᵀ,   M = I,   K = [[1, −1], [−1, 2]],
//!   D = 0.03 K,   f(q₁) = 100 (q₁ − 1) for q₁ ≥ 1, else 0
//! ```
//!
//! with `ω = Ω`. Near its first resonance the response leans towards higher frequencies
//! (the contact stiffens it) with two folds, and a Neimark–Sacker point on the upper branch.
//! Published reference values (NLvib, H = 21 harmonics): folds at Ω = 0.6534401 and
//! 0.755664, Neimark–Sacker at Ω = 0.618354.

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// The two-mass oscillator with a unilateral spring on DoF 0.
#[derive(Clone, Debug)]
pub struct UnilateralContact {
    /// Contact stiffness (100).
    pub contact_stiffness: f64,
    /// Gap before contact (1).
    pub gap: f64,
    /// Forcing amplitude on DoF 1 (0.1).
    pub force: f64,
    /// Stiffness-proportional damping factor, `D = β K` (0.03).
    pub beta: f64,
    nl: NonlinearDofs,
}

impl Default for UnilateralContact {
    fn default() -> Self {
        Self {
            contact_stiffness: 100.0,
            gap: 1.0,
            force: 0.1,
            beta: 0.03,
            nl: NonlinearDofs {
                mech: vec![0],
                therm: vec![],
            },
        }
    }
}

impl UnilateralContact {
    /// The reference range, swept downwards (rad/s, nondimensional).
    pub const OMEGA_RANGE: (f64, f64) = (0.8, 0.5);

    fn stiffness() -> DenseMatrix {
        DenseMatrix {
            n: 2,
            data: vec![1.0, -1.0, -1.0, 2.0],
        }
    }
}

impl System for UnilateralContact {
    fn n_mech(&self) -> usize {
        2
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        let k = Self::stiffness();
        let mut d = k.clone();
        d.data.iter_mut().for_each(|v| *v *= self.beta);
        let mut m = DenseMatrix::zeros(2);
        *m.get_mut(0, 0) = 1.0;
        *m.get_mut(1, 1) = 1.0;
        LinearPart::mechanical(m, d, k)
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.nl
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
        let pen = x[0] - self.gap;
        if pen >= 0.0 {
            out.f[0] = self.contact_stiffness * pen;
            out.df_dx[0] = self.contact_stiffness;
        } else {
            out.f[0] = 0.0;
            out.df_dx[0] = 0.0;
        }
        out.df_dv[0] = 0.0;
    }

    fn n_switching(&self) -> usize {
        1
    }

    /// The penetration `q₁ − gap`: the contact closes and opens at its zeros.
    fn switching(
        &self,
        _omega: f64,
        _t: f64,
        x: &[f64],
        _v: &[f64],
        _temp: &[f64],
        out: &mut [f64],
    ) {
        out[0] = x[0] - self.gap;
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = 0.0;
        out[1] = self.force * (omega * t).cos();
    }
}
