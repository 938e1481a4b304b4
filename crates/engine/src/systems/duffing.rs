//! The forced Duffing oscillator `m ẍ + c ẋ + k x + k₃ x³ = F cos(Ω t)` with `ω = Ω`.
//!
//! Default parameters are the reference problem `ẍ + 0.05 ẋ + x + 0.1 x³ = 0.18 cos(Ω t)`,
//! Ω from 0.5 to 1.6 (a hardening frequency response with two folds and an unstable middle
//! branch; see e.g. Nayfeh & Mook, *Nonlinear Oscillations*, 1979, Ch. 4 for the
//! single-harmonic frequency-response equation used as a check in the tests).

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Forced Duffing oscillator (nondimensional).
#[derive(Clone, Debug)]
pub struct Duffing {
    pub mass: f64,
    pub damping: f64,
    pub stiffness: f64,
    pub cubic: f64,
    pub force: f64,
    nl: NonlinearDofs,
}

impl Default for Duffing {
    /// `m = 1, c = 0.05, k = 1, k₃ = 0.1, F = 0.18`.
    fn default() -> Self {
        Self::new(1.0, 0.05, 1.0, 0.1, 0.18)
    }
}

impl Duffing {
    /// Reference frequency range of the default problem (rad/s, nondimensional).
    pub const OMEGA_RANGE: (f64, f64) = (0.5, 1.6);

    pub fn new(mass: f64, damping: f64, stiffness: f64, cubic: f64, force: f64) -> Self {
        Self {
            mass,
            damping,
            stiffness,
            cubic,
            force,
            nl: NonlinearDofs {
                mech: vec![0],
                therm: vec![],
            },
        }
    }
}

impl System for Duffing {
    fn n_mech(&self) -> usize {
        1
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        LinearPart::mechanical(
            DenseMatrix::scalar(self.mass),
            DenseMatrix::scalar(self.damping),
            DenseMatrix::scalar(self.stiffness),
        )
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
        out.f[0] = self.cubic * x[0].powi(3);
        out.df_dx[0] = 3.0 * self.cubic * x[0] * x[0];
        out.df_dv[0] = 0.0;
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = self.force * (omega * t).cos();
    }
}
