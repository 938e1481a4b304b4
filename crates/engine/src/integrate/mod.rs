//! Direct time integration of a [`System`](crate::system::System): the independent
//! reference the harmonic-balance and Floquet results are checked against.
//!
//! * [`StateSpace`]: the first-order form `ẏ = φ(t, y)`, `y = [x, ẋ, T]`, with `M` and `C_T`
//!   factored once, and its linearisation `B(t)` (paper Eq. 30) applied in factored form;
//! * [`Dopri5`]: adaptive Dormand–Prince 5(4) with exact stops at requested instants and a
//!   Hermite interpolant per step; [`rk4`]: classical fixed-step Runge–Kutta 4;
//! * [`steady_state`]: runs to steady state and samples one period ([`SteadyState`]);
//!   [`poincare_samples`]: stroboscopic samples `y(kP)` (period doubling, quasi-periodicity);
//! * [`SampledOrbit`]: a [`PeriodicOrbit`](crate::system::PeriodicOrbit) from uniformly
//!   sampled data by trigonometric interpolation (spectrally accurate for smooth orbits);
//! * [`monodromy_along_orbit`]: the monodromy matrix by integrating the variational
//!   equations `Φ̇ = B(t) Φ`, `Φ(0) = I`, over one period along a given orbit (matrix ODE);
//!   [`flow_with_sensitivity`]: state and `∂y(t)/∂y(0)` together; [`shoot_periodic`]:
//!   periodic orbits (stable or not) by Newton shooting on `y(P) − y(0)`.
//!
//! Defaults: `rtol = 1e-10`, `atol = 1e-12` ([`Dopri5Options`]); 256 samples per period
//! ([`SteadyStateOptions`]). Reasons are given on each field.

// Numerical kernels index several equally long buffers in one loop; iterator chains
// would obscure the formulas.
#![allow(clippy::needless_range_loop)]

mod dopri;
mod orbit;
mod state_space;
mod steady;
mod transient;
mod variational;

pub use dopri::{Dopri5, Dopri5Options, Dopri5Stats, HermiteStep, rk4};
pub use orbit::SampledOrbit;
pub use state_space::{StateSpace, Workspace};
pub use steady::{
    SteadyState, SteadyStateOptions, poincare_samples, steady_state, steady_state_with,
};
pub use transient::{
    SpeedProfile, StepView, ThermalStepping, Transient, TransientOptions, TransientStats,
};
pub use variational::{
    FlowSensitivity, ShootingOptions, flow_with_sensitivity, monodromy_along_orbit, shoot_periodic,
    shoot_periodic_segments,
};

use thiserror::Error;

/// Errors of the time-integration layer.
#[derive(Debug, Error)]
pub enum IntegrateError {
    #[error("{matrix} matrix is singular (its LU solve produced non-finite values)")]
    Singular { matrix: &'static str },
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    Dimension {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    #[error("invalid integration interval [{t0}, {t1}] (need finite t0 < t1)")]
    Interval { t0: f64, t1: f64 },
    #[error("step budget of {steps} steps exhausted at t = {t} (end {t_end})")]
    StepBudget { steps: usize, t: f64, t_end: f64 },
    #[error("step size underflow (h = {h}) at t = {t}")]
    StepUnderflow { t: f64, h: f64 },
    #[error("non-finite state at t = {t}")]
    NonFinite { t: f64 },
    #[error("invalid setting {field} = {value}: {reason}")]
    Setting {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error("shooting did not converge in {iterations} iterations (‖y(P) − y(0)‖ = {residual:e})")]
    Shooting { iterations: usize, residual: f64 },
}
