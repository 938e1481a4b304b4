//! Floquet multipliers from the variational equations integrated over one period: the
//! independent cross-check of the SIP product ([`super::Sip`]).
//!
//! `Φ̇ = B(t) Φ`, `Φ(0) = I` is integrated along the orbit with the adaptive
//! Dormand–Prince 5(4) integrator of [`crate::integrate`] (as one matrix ODE, see
//! [`monodromy_along_orbit`]); the multipliers are the eigenvalues of `Φ(P)`. The state
//! matrix `B(t)` is the same as SIP's (paper Eq. 30), but evaluated at every stage instead
//! of averaged per interval, and the propagator is a 5th-order Runge–Kutta step with error
//! control instead of a truncated series: the two share no approximation, so agreement
//! of their multipliers checks both.
//!
//! Defaults `rtol = 1e-10`, `atol = 1e-12`: `Φ` has entries of order 1 for the reference
//! problems, so the monodromy matrix is accurate to ~1e-9 and multipliers of modulus near 1
//! (the ones that decide stability) to about that, well inside
//! [`UNIT_CIRCLE_TOL`](super::UNIT_CIRCLE_TOL) = 1e-6.

use faer::Mat;

use super::{FloquetResult, StabilityError, StabilityMethod, eigenvalues_checked};
use crate::integrate::{Dopri5Options, StateSpace, monodromy_along_orbit};
use crate::system::{PeriodicOrbit, System};

/// Monodromy by integrating the variational equations (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variational {
    /// Relative tolerance of the integrator. Default 1e-10.
    pub rtol: f64,
    /// Absolute tolerance of the integrator. Default 1e-12.
    pub atol: f64,
}

impl Default for Variational {
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            atol: 1e-12,
        }
    }
}

impl Variational {
    /// The monodromy matrix `Φ(P)` of `orbit`.
    pub fn monodromy(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<Mat<f64>, StabilityError> {
        let omega = orbit.omega();
        for (field, value) in [
            ("variational.rtol", self.rtol),
            ("variational.atol", self.atol),
        ] {
            if value.is_nan() || value <= 0.0 {
                return Err(StabilityError::Setting {
                    field,
                    value: value.to_string(),
                    reason: "must be positive",
                });
            }
        }
        let setup = |e: crate::integrate::IntegrateError| StabilityError::Setup {
            omega,
            reason: e.to_string(),
        };
        let space = StateSpace::new(system, omega).map_err(setup)?;
        let opts = Dopri5Options {
            rtol: self.rtol,
            atol: self.atol,
            ..Dopri5Options::default()
        };
        monodromy_along_orbit(&space, orbit, &opts).map_err(setup)
    }
}

impl StabilityMethod for Variational {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        let mono = self.monodromy(system, orbit)?;
        eigenvalues_checked(mono.as_ref(), orbit.omega()).map(FloquetResult::new)
    }
}
