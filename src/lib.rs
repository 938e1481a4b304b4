//! # tmrotor
//!
//! Nonlinear, thermo-mechanically coupled vibration of rotor–bearing systems, solved by
//! harmonic balance with continuation in rotor speed and Floquet stability, recorded as
//! protobuf messages in MCAP files.
//!
//! ## The pipeline
//!
//! ```text
//! model file (TOML) ─► model: FE rotor + bearings + thermal network      [model], [bearing], [thermal], [coupled]
//!                        │ implements System (residual terms + exact derivatives)   [system]
//!                        ▼
//!                  harmonic balance: basis, AFT, Newton (modified IHB)              [hb]
//!                        ▼
//!                  continuation in ω (pseudo-arclength)                             [continuation]
//!                        ▼
//!                  Floquet stability, bifurcation detection / location / type       [stability]
//!                        ▼
//!                  sink ─► MCAP file (protobuf messages on topics)                  [record]
//! ```
//!
//! The driver that runs one sweep from study settings into a sink is [`sweep`]; several
//! sweeps in parallel with a manifest are a [`campaign`], whose runs
//! [`campaign::figures`] overlays in PNG figures drawn with the helpers of [`figure`]
//! (shared with `replay plot`); the comparison of truncation orders with the residual of
//! the governing equations (Eq. 36) is [`truncation`], and the paper's findings against a
//! campaign are the [`report`]. The binaries (`tmrotor`, see [`cli`], and `replay`) are
//! thin layers over these.
//!
//! Linear analyses of the assembled rotor (modes, Campbell diagram) live in [`linear`];
//! reference problems with known answers (Duffing, absorber, Jeffcott) in [`systems`];
//! the time integrator used as an independent reference in [`integrate`].

pub mod bearing;
pub mod campaign;
pub mod cli;
pub mod continuation;
pub mod coupled;
pub mod figure;
pub mod hb;
pub mod integrate;
pub mod linear;
pub mod model;
pub mod record;
pub mod report;
pub mod stability;
pub mod sweep;
pub mod system;
pub mod systems;
pub mod thermal;
pub mod truncation;
