//! Nonlinear rolling-element bearings with thermal clearance (paper section 2.1, Eqs. 1–5).
//!
//! * [`hertz`]: the Hertzian restoring force of a rolling-element bearing summed over its
//!   elements (Eqs. 3–5), with the number of loaded elements and the exact partial
//!   derivatives with respect to the relative ring displacement and the clearance variation;
//! * [`expansion`]: the radial thermal expansions of rolling elements, inner ring and outer
//!   ring (Eqs. 1–2) and the resulting clearance variation `δv = −(u_b + (u_i − u_o)/2)`
//!   with its derivatives with respect to the temperatures involved;
//! * [`linear`]: the cage-averaged law linearised at a radial load, for modal analysis.
//!
//! [`ContactLaw`] is the one definition of a bearing's kind.
//!
//! Everything here is pointwise (one instant, one bearing) and allocation-free, so that the
//! coupled model can call it inside the harmonic-balance AFT loop and chain the derivatives.
//! SI units throughout (m, N, rad/s, K or °C where only differences matter).

pub mod expansion;
pub mod hertz;
pub mod linear;

pub use expansion::{ClearanceVariation, ExpansionGeometry, OuterSeat};
pub use hertz::{BearingForce, ContactLaw, HertzBearing, cage_speed_rad_s};
pub use linear::HertzLaw;

/// Errors raised when bearing data are inconsistent.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BearingError {
    /// A parameter that must be strictly positive is not.
    #[error("bearing parameter `{field}` must be > 0, got {value}")]
    NotPositive { field: &'static str, value: f64 },
    /// The number of rolling elements must be at least one.
    #[error("bearing needs at least one rolling element, got {0}")]
    NoElements(usize),
}

pub(crate) fn check_positive(field: &'static str, value: f64) -> Result<(), BearingError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(BearingError::NotPositive { field, value })
    }
}
