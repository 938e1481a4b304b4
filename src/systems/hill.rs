//! Floquet accuracy reference: the linear periodic system
//!
//! ```text
//!   ẏ = A(t) y,   A(t) = [[0, 1], [−10 cos t, −24 − 10 sin t]],   period 2π,
//! ```
//!
//! i.e. `ẍ + (24 + 10 sin t) ẋ + 10 cos t · x = 0`. Its Floquet exponents are 0 and −24
//! exactly (multipliers 1 and `e^{−48π}` ≈ 1.7e−66): the left side is the derivative of
//! `ẋ + (24 + 10 sin t) x`, so `ẋ + (24 + 10 sin t) x = c`; `c = 0` gives
//! `x = exp(−24 t + 10 cos t)` (exponent −24) and `c ≠ 0` a 2π-periodic solution
//! (exponent 0). The sum −24 also follows from Liouville's formula, `∫₀^{2π} tr A dt / 2π`.
//! The exponents are thus known in closed form, and the second one is strongly negative:
//! a Floquet method must resolve a multiplier of 1 next to one that underflows, and its
//! exponent sum must match Liouville's formula (see `tests/stability_hill.rs`).
//!
//! It is written as a [`System`] with one mechanical DoF, `M = 1`, `C = 24`, `K = 0` and the
//! time-varying terms as a "nonlinear" force `f = 10 cos t · x + 10 sin t · ẋ` with exact
//! derivatives, so that its linearisation around the trivial orbit `x ≡ 0`
//! ([`HillOrbit`], `ω = 1`, period 2π) is exactly `A(t)`.

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, PeriodicOrbit, System};

/// The Floquet exponents of the reference (1/s), sorted descending.
pub const EXPONENTS: [f64; 2] = [0.0, -24.0];

/// The period (s).
pub const PERIOD: f64 = 2.0 * std::f64::consts::PI;

/// The system `ẍ + (24 + 10 sin t) ẋ + 10 cos t · x = 0` (see the module docs).
#[derive(Clone, Debug)]
pub struct Hill {
    dofs: NonlinearDofs,
}

impl Default for Hill {
    fn default() -> Self {
        Self {
            dofs: NonlinearDofs {
                mech: vec![0],
                therm: vec![],
            },
        }
    }
}

impl System for Hill {
    fn n_mech(&self) -> usize {
        1
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        let scalar = |v: f64| DenseMatrix {
            n: 1,
            data: vec![v],
        };
        LinearPart {
            mass: scalar(1.0),
            damping: scalar(24.0),
            stiffness: scalar(0.0),
            thermal_capacity: DenseMatrix::zeros(0),
            thermal_conductance: DenseMatrix::zeros(0),
        }
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }

    fn eval_nonlinear(
        &self,
        _omega: f64,
        t: f64,
        x: &[f64],
        v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        let (s, c) = t.sin_cos();
        out.f[0] = 10.0 * c * x[0] + 10.0 * s * v[0];
        out.df_dx[0] = 10.0 * c;
        out.df_dv[0] = 10.0 * s;
    }

    fn forcing(&self, _omega: f64, _t: f64, out: &mut [f64]) {
        out[0] = 0.0;
    }
}

/// The trivial orbit `x ≡ 0` of [`Hill`], `ω = 1`, period 2π.
#[derive(Clone, Copy, Debug, Default)]
pub struct HillOrbit;

impl PeriodicOrbit for HillOrbit {
    fn omega(&self) -> f64 {
        1.0
    }

    fn period(&self) -> f64 {
        PERIOD
    }

    fn state_at(&self, _t: f64, x: &mut [f64], v: &mut [f64], _temp: &mut [f64]) {
        x[0] = 0.0;
        v[0] = 0.0;
    }
}
