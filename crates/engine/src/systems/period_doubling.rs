//! Period-doubling reference: the forced double-well Duffing oscillator
//!
//! ```text
//!   ẍ + δ ẋ − x + x³ = γ cos(ω t),   δ = 0.3, ω = 1.2,
//! ```
//!
//! with the forcing amplitude `γ` as the bifurcation parameter. This is the classical
//! example of a period-doubling cascade (J. Guckenheimer, P. Holmes, *Nonlinear
//! Oscillations, Dynamical Systems, and Bifurcations of Vector Fields*, Springer 1983,
//! Sec. 2.2; the same parameters are used for the Poincaré sections in the Wikipedia
//! article "Duffing equation": one-well period-1 response at `γ = 0.20`, period 2 at
//! `γ = 0.28`, period 4 at `γ = 0.29`, chaos at `γ = 0.50`). The first period doubling of
//! the one-well orbit therefore lies in `0.20 < γ < 0.28`; the tests locate it from the
//! Floquet multipliers (a real multiplier leaving the unit circle through −1) and confirm
//! with the time integrator that the stroboscopic samples are constant below it and
//! alternate above it.
//!
//! Located here (`tests/stability_period_doubling.rs`, shooting + variational multipliers,
//! bisection to 1e-6): `γ* = 0.26558`, multipliers there ≈ −0.21 and −1 (their product is
//! `exp(−0.3·2π/1.2)` = 0.2079 by Liouville's formula); the time integrator shows constant
//! stroboscopic samples at `γ* − 0.005` and samples alternating between two points 0.22
//! apart at `γ* + 0.005`.
//!
//! The continuation parameter `ω` of [`System`] is the forcing frequency; `γ` and `δ` are
//! fields of [`DoubleWellDuffing`].
//!
//! ## Continuation in γ
//! The engine continues periodic orbits in the base frequency of their basis. To continue
//! in `γ` at the fixed forcing frequency `Ω` ([`OMEGA`]), [`GammaParametrized`] writes the
//! same equation in the rescaled time `s = γ t / Ω`, in which the forcing frequency *is*
//! `γ`. With `X(s) = x(t)`, `d/dt = (Ω/γ) d/ds`:
//!
//! ```text
//!   (Ω/γ)² X'' + δ (Ω/γ) X' − X + X³ = γ cos(γ s),
//! ```
//!
//! so its continuation parameter (`omega` in the engine's API) is `γ`, its mass and damping
//! depend on it, and its orbits are those of the original with time stretched by `Ω/γ`:
//! displacements, amplitudes and Floquet multipliers (the monodromy matrices are similar,
//! `(X, X') = (x, (γ/Ω) ẋ)`) are the same. Velocities and times differ by the factor.

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Damping of the reference (Guckenheimer & Holmes).
pub const DELTA: f64 = 0.3;
/// Forcing frequency of the reference (rad/s).
pub const OMEGA: f64 = 1.2;
/// Literature bracket of the first period doubling in `γ` at `δ = 0.3`, `ω = 1.2`.
pub const GAMMA_BRACKET: (f64, f64) = (0.20, 0.28);

/// `ẍ + δ ẋ − x + x³ = γ cos(ω t)` (see the module docs).
#[derive(Clone, Debug)]
pub struct DoubleWellDuffing {
    /// Linear damping `δ`.
    pub delta: f64,
    /// Forcing amplitude `γ`.
    pub gamma: f64,
    dofs: NonlinearDofs,
}

impl DoubleWellDuffing {
    /// The oscillator with damping `delta` and forcing amplitude `gamma`.
    pub fn new(delta: f64, gamma: f64) -> Self {
        Self {
            delta,
            gamma,
            dofs: NonlinearDofs {
                mech: vec![0],
                therm: vec![],
            },
        }
    }

    /// The reference damping [`DELTA`] with forcing amplitude `gamma`.
    pub fn reference(gamma: f64) -> Self {
        Self::new(DELTA, gamma)
    }
}

impl System for DoubleWellDuffing {
    fn n_mech(&self) -> usize {
        1
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        LinearPart::mechanical(
            DenseMatrix::scalar(1.0),
            DenseMatrix::scalar(self.delta),
            DenseMatrix::scalar(-1.0),
        )
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
        out.f[0] = x[0] * x[0] * x[0];
        out.df_dx[0] = 3.0 * x[0] * x[0];
        out.df_dv[0] = 0.0;
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = self.gamma * (omega * t).cos();
    }
}

/// The double-well Duffing oscillator at fixed forcing frequency with the forcing
/// amplitude `γ` as continuation parameter, in the rescaled time `s = γ t / Ω` (see
/// "Continuation in γ" in the module docs). Every `omega` argument of its [`System`]
/// methods, and the `omega` of its orbits, is `γ`.
#[derive(Clone, Debug)]
pub struct GammaParametrized {
    /// Linear damping `δ`.
    pub delta: f64,
    /// Fixed forcing frequency `Ω` in physical time (rad/s).
    pub forcing_frequency: f64,
    dofs: NonlinearDofs,
}

impl GammaParametrized {
    /// The oscillator with damping `delta`, forced at `forcing_frequency`.
    pub fn new(delta: f64, forcing_frequency: f64) -> Self {
        Self {
            delta,
            forcing_frequency,
            dofs: NonlinearDofs {
                mech: vec![0],
                therm: vec![],
            },
        }
    }

    /// The reference: damping [`DELTA`], forcing frequency [`OMEGA`].
    pub fn reference() -> Self {
        Self::new(DELTA, OMEGA)
    }

    /// `Ω / γ`: physical time `t = s / (Ω/γ)`, physical velocity `ẋ = (Ω/γ) X'`.
    pub fn time_scale(&self, gamma: f64) -> f64 {
        self.forcing_frequency / gamma
    }
}

impl System for GammaParametrized {
    fn n_mech(&self) -> usize {
        1
    }

    fn linear(&self, gamma: f64) -> LinearPart {
        let r = self.time_scale(gamma);
        LinearPart::mechanical(
            DenseMatrix::scalar(r * r),
            DenseMatrix::scalar(self.delta * r),
            DenseMatrix::scalar(-1.0),
        )
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }

    fn eval_nonlinear(
        &self,
        _gamma: f64,
        _s: f64,
        x: &[f64],
        _v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        out.f[0] = x[0] * x[0] * x[0];
        out.df_dx[0] = 3.0 * x[0] * x[0];
        out.df_dv[0] = 0.0;
    }

    fn forcing(&self, gamma: f64, s: f64, out: &mut [f64]) {
        out[0] = gamma * (gamma * s).cos();
    }
}
