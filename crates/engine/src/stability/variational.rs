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

/// Floquet multipliers of the periodic orbit of the equations of motion themselves, found
/// by Newton shooting from the given orbit's state at `t = 0`
/// ([`crate::integrate::shoot_periodic`]): the monodromy of the variational equations
/// along the corrected orbit.
///
/// Why: [`Variational`] linearises around the orbit it is given. For a harmonic-balance
/// orbit that is the truncated one, and where the truncation error matters to stability
/// (a grazing contact, whose short penetrations a finite Fourier series smooths out) its
/// multipliers differ from those of the true orbit: on NLvib's unilateral-contact example
/// (`systems::contact`, H = 21) the Neimark–Sacker point of the variational equations
/// around the balance lies at Ω = 0.6115, that of the shot orbit at 0.6184, the published
/// 0.618354. For small systems only: each Newton step integrates `d + d²` equations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shooting {
    /// Relative and absolute tolerance of the integrator. Defaults 1e-10, 1e-12.
    pub rtol: f64,
    pub atol: f64,
    /// Segments of the period, shot in parallel from the orbit's states at their starts
    /// ([`crate::integrate::shoot_periodic_segments`]). Default 2: the stability of a
    /// point runs beside the next point's corrector, and with two halves it can use the
    /// core the corrector leaves idle (NLvib's contact benchmark: 0.72 s → 0.64 s on two
    /// cores; three segments measured the same, four slower; docs/performance.md).
    pub segments: usize,
}

impl Default for Shooting {
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            atol: 1e-12,
            segments: 2,
        }
    }
}

impl StabilityMethod for Shooting {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        let omega = orbit.omega();
        let (n, m) = (system.n_mech(), system.n_therm());
        let segments = self.segments.max(1);
        let starts: Vec<Vec<f64>> = (0..segments)
            .map(|k| {
                let (mut x, mut v, mut temp) = (vec![0.0; n], vec![0.0; n], vec![0.0; m]);
                let t = orbit.period() * k as f64 / segments as f64;
                orbit.state_at(t, &mut x, &mut v, &mut temp);
                x.into_iter().chain(v).chain(temp).collect()
            })
            .collect();
        let opts = crate::integrate::ShootingOptions {
            integrator: Dopri5Options {
                rtol: self.rtol,
                atol: self.atol,
                ..Dopri5Options::default()
            },
            ..Default::default()
        };
        let flow = crate::integrate::shoot_periodic_segments(
            system,
            omega,
            &starts,
            orbit.period(),
            &opts,
        )
        .map_err(|e| StabilityError::Setup {
            omega,
            reason: format!("shooting from the given orbit: {e}"),
        })?;
        eigenvalues_checked(flow.phi.as_ref(), omega).map(FloquetResult::new)
    }
}
