//! # tmrotor-rotor
//!
//! The rotor library of tmrotor: thermo-mechanically coupled rotor–bearing models, their
//! linear analyses, the sweep that follows them in speed with the engine
//! (`tmrotor-engine`, re-exported here as [`hb`], [`continuation`], [`stability`], …),
//! the time-domain transient, and the MCAP recordings every run writes and every reader
//! reads. It has no command line, no terminal output of its own and never exits the
//! process: a run is stopped through the flag its driver polls.
//!
//! ```text
//! model file (TOML) ─► FE rotor + bearings + thermal network        [model], [bearing], [thermal], [coupled]
//!                        │ implements the engine's System
//!                        ▼
//!                  study settings ─► sweep (HB + continuation + Floquet)   [study], [sweep]
//!                        ▼
//!                  sink ─► MCAP file (protobuf messages on topics)         [record]
//!                        ▼
//!                  quantities re-derived from stored coefficients          [derive]
//! ```
//!
//! Linear analyses of the assembled rotor (modes, Campbell diagram, unbalance response)
//! live in [`linear`]; time integration of the coupled model in [`transient`]; bounded
//! reading of user files in [`input`].

pub use tmrotor_engine::{continuation, hb, integrate, stability, system, systems};

pub mod bearing;
pub mod coupled;
pub mod derive;
pub mod input;
pub mod linear;
pub mod model;
pub mod record;
pub mod study;
pub mod sweep;
pub mod thermal;
pub mod transient;
