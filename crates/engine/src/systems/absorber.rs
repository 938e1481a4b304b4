//! Primary mass with a nonlinear tuned vibration absorber (two DoF):
//!
//! ```text
//!   m₁ ẍ₁ + c₁ ẋ₁ + c₂ (ẋ₁ − ẋ₂) + k₁ x₁ + k₂ (x₁ − x₂) + k₁₃ x₁³ + k₂₃ (x₁ − x₂)³ = F cos Ω t
//!   m₂ ẍ₂ + c₂ (ẋ₂ − ẋ₁) + k₂ (x₂ − x₁) + k₂₃ (x₂ − x₁)³ = 0
//! ```
//!
//! Default parameters (nondimensional): `m₁ = 1, m₂ = 0.05, k₁ = 1, k₂ = 0.0453,
//! c₁ = 0.002, c₂ = 0.013, k₁₃ = 1, k₂₃ = 0.0042, F = 0.11`, Ω from 0.8 to 1.4 — the
//! nonlinear tuned vibration absorber benchmark of Habib, Detroux, Viguié & Kerschen,
//! "Nonlinear generalization of Den Hartog's equal-peak method", MSSP 52–53 (2015), whose
//! response shows Neimark–Sacker bifurcations (detached and quasi-periodic regimes).

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Two-DoF primary system with a nonlinear tuned vibration absorber.
#[derive(Clone, Debug)]
pub struct Absorber {
    pub m1: f64,
    pub m2: f64,
    pub k1: f64,
    pub k2: f64,
    pub c1: f64,
    pub c2: f64,
    pub k1_cubic: f64,
    pub k2_cubic: f64,
    pub force: f64,
    nl: NonlinearDofs,
}

impl Default for Absorber {
    fn default() -> Self {
        Self {
            m1: 1.0,
            m2: 0.05,
            k1: 1.0,
            k2: 0.0453,
            c1: 0.002,
            c2: 0.013,
            k1_cubic: 1.0,
            k2_cubic: 0.0042,
            force: 0.11,
            nl: NonlinearDofs {
                mech: vec![0, 1],
                therm: vec![],
            },
        }
    }
}

impl Absorber {
    /// Reference frequency range (nondimensional).
    pub const OMEGA_RANGE: (f64, f64) = (0.8, 1.4);
}

impl System for Absorber {
    fn n_mech(&self) -> usize {
        2
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        let m = DenseMatrix {
            n: 2,
            data: vec![self.m1, 0.0, 0.0, self.m2],
        };
        let c = DenseMatrix {
            n: 2,
            data: vec![self.c1 + self.c2, -self.c2, -self.c2, self.c2],
        };
        let k = DenseMatrix {
            n: 2,
            data: vec![self.k1 + self.k2, -self.k2, -self.k2, self.k2],
        };
        LinearPart::mechanical(m, c, k)
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
        let d = x[0] - x[1];
        let g = self.k2_cubic * d.powi(3);
        let dg = 3.0 * self.k2_cubic * d * d;
        out.f[0] = self.k1_cubic * x[0].powi(3) + g;
        out.f[1] = -g;
        out.df_dx[0] = 3.0 * self.k1_cubic * x[0] * x[0] + dg;
        out.df_dx[1] = -dg;
        out.df_dx[2] = -dg;
        out.df_dx[3] = dg;
        out.df_dv.iter_mut().for_each(|v| *v = 0.0);
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = self.force * (omega * t).cos();
        out[1] = 0.0;
    }
}
