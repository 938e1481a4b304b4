//! Harmonic balance (paper Section 4.1): multi-frequency basis, AFT, residual and exact
//! Jacobian, linear solves with condensation of the linear DoFs, Newton (modified IHB) and
//! the solution type.
//!
//! | item | what |
//! |---|---|
//! | [`Basis`] | constant + rational multiples of ω (Eq. 34) |
//! | [`Aft`] | coefficients ↔ time samples by FFT (Eq. 28) |
//! | [`EventNodes`] | exact coefficients of piecewise-smooth terms: quadrature between located switching instants |
//! | [`HarmonicBalance`] | residual `R(A, ω)` (Eq. 25–27), exact `∂R/∂A`, `∂R/∂ω` |
//! | [`LinearSolver`] | Newton systems with the linear DoFs condensed per harmonic |
//! | [`newton`] | damped Newton with separate mechanical / thermal tests (Eq. 29) |
//! | [`HbSolution`] | a converged periodic solution; amplitude helpers (Eq. 35) |
//! | [`time_residual`] | residual of the governing equations on a fine time grid (Eq. 36) |
pub mod aft;
pub mod basis;
pub mod condense;
pub mod events;
pub mod newton;
pub mod residual;
pub mod solution;
pub mod time_residual;

pub use aft::{Aft, AftError, Signal};
pub use basis::{Basis, BasisError, Ratio};
pub use condense::{Border, Factorization, LinearSolver, SolveError};
pub use events::{EventNodes, PanelRule};
pub use newton::{NewtonError, NewtonOptions, NewtonStats};
pub use residual::{HarmonicBalance, HbError, JacobianParts, ResidualNorms, SparseLinear};
pub use solution::HbSolution;
pub use time_residual::{ResidualStats, TimeResidual, time_domain_residual};
