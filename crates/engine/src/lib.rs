//! # tmrotor-engine
//!
//! Harmonic balance, pseudo-arclength continuation and Floquet stability for any system of
//! second-order ODEs with periodic forcing, independent of rotors: the numerical engine of
//! tmrotor, with no application dependencies (no command line, no recording, no figures).
//!
//! ```text
//! your system: implements System (linear matrices + nonlinear terms with derivatives)  [system]
//!        ▼
//! harmonic balance: Fourier basis, AFT, Newton with condensation                      [hb]
//!        ▼
//! continuation in the forcing frequency (pseudo-arclength, fold location, switching)  [continuation]
//!        ▼
//! Floquet stability of each orbit, bifurcation detection, location and type           [stability]
//! ```
//!
//! [`integrate`] holds the time integrators (Dormand–Prince with dense output, the
//! variational equations) used as independent references and for transients;
//! [`systems`] holds reference problems with known answers (Duffing, the tuned absorber,
//! the Jeffcott rotor, a contact oscillator, Hill's equation, a chain of oscillators).
//!
//! `examples/own_system.rs` in the repository applies the engine to a user's own ODE
//! system from scratch.

pub mod continuation;
pub mod hb;
pub mod integrate;
pub mod stability;
pub mod system;
pub mod systems;
