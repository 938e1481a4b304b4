//! Floquet accuracy reference: the linear periodic system
//!
//! ```text
//!   ẏ = A(t) y,   A(t) = [[0, 1], [−10 cos t, −24 − 10 sin t]],   period 2π,
//! ```
//!
//! i.e. `ẍ + (24 + 10 sin t) ẋ + 10 cos t · x = 0`. Its Floquet exponents are 0 and −24
//! exactly (multipliers 1 and `e^{−48π}` ≈ 3.2e−66): the left side is the derivative of
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

/// The exact Floquet multipliers `e^{λ P}`, sorted descending: `[1, e^{−48π}]`
/// (`e^{−48π}` ≈ 3.2e−66).
pub fn exact_multipliers() -> [f64; 2] {
    EXPONENTS.map(|l| (l * PERIOD).exp())
}

/// The exact monodromy matrix `Φ(2π)` of `y = (x, ẋ)`, row-major.
///
/// With `μ(t) = 24 t − 10 cos t` (so `μ̇ = 24 + 10 sin t`), the two solutions are the
/// decaying `x₁ = e^{−μ(t)}` (state `∝ (1, −24)` at `t = 0`) and the periodic solution of
/// `ẋ + μ̇ x = 1`, `x₂(t) = ∫_{−∞}^t e^{μ(s) − μ(t)} ds`, with state `(p₀, 1 − 24 p₀)` at
/// `t = 0`, `p₀ = ∫₀^∞ exp(−24u + 10 − 10 cos u) du`. In the basis
/// `Y = [[1, p₀], [−24, 1 − 24 p₀]]` (`det Y = 1`) the monodromy matrix is
/// `diag(e^{−48π}, 1)`, so `Φ = Y diag(e^{−48π}, 1) Y⁻¹`:
///
/// ```text
///   Φ = [[24 p₀, p₀], [24 (1 − 24 p₀), 1 − 24 p₀]]  +  O(e^{−48π}).
/// ```
///
/// `p₀` ≈ 0.0424 is computed by composite Simpson quadrature on `[0, 4]` with 2¹⁶ panels
/// (the integrand is below `e^{−76}` beyond 4; the quadrature error is ~1e−13).
pub fn exact_monodromy() -> [[f64; 2]; 2] {
    let n = 1usize << 16;
    let (a, b) = (0.0, 4.0);
    let h = (b - a) / n as f64;
    let f = |u: f64| (-24.0 * u + 10.0 - 10.0 * u.cos()).exp();
    let inner: f64 = (1..n)
        .map(|i| if i % 2 == 1 { 4.0 } else { 2.0 } * f(a + i as f64 * h))
        .sum();
    let p0 = (f(a) + f(b) + inner) * h / 3.0;
    // the e^{−48π} part is far below round-off of the O(1) entries; kept for completeness
    let eps = exact_multipliers()[1];
    let y = [[1.0, p0], [-24.0, 1.0 - 24.0 * p0]];
    let y_inv = [[1.0 - 24.0 * p0, -p0], [24.0, 1.0]];
    let d = [eps, 1.0];
    let mut phi = [[0.0; 2]; 2];
    for (i, row) in phi.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..2).map(|k| y[i][k] * d[k] * y_inv[k][j]).sum();
        }
    }
    phi
}

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
        LinearPart::mechanical(
            DenseMatrix::scalar(1.0),
            DenseMatrix::scalar(24.0),
            DenseMatrix::scalar(0.0),
        )
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
