//! Recording of continuation runs as MCAP files, and reading them back (paper-independent
//! output layer; SPEC §4).
//!
//! | type / module | role |
//! |---|---|
//! | [`types`] | domain types: [`RunInfo`], [`PointRecord`], [`BifurcationRecord`], [`RunStatus`] |
//! | [`Sink`], [`MemorySink`], [`record_run`] | where the continuation writes; always finished |
//! | [`McapSink`] | protobuf messages in zstd-chunked, indexed MCAP files (clock, layout, crash safety in [`mcap_sink`]) |
//! | [`schema`] | topics, message types and their embedded descriptor sets |
//! | [`convert`] | the only domain ↔ protobuf conversion |
//! | [`reader`] | [`read_recording`]: back to domain types, tolerant of files cut short |
//! | [`synthetic`] | a closed-form 2-DoF run for tests and examples |
//!
//! Only this module uses `mcap` and `prost`.
//!
//! ```
//! use tmrotor_rotor::record::synthetic::{self, SyntheticOptions};
//! use tmrotor_rotor::record::{McapOptions, McapSink, RunStatus, Sink, read_recording};
//!
//! let data = synthetic::generate(&SyntheticOptions::default());
//! let dir = tempfile::tempdir()?;
//! let path = dir.path().join("sweep.mcap");
//! let mut sink = McapSink::create(&path, McapOptions::default())?;
//! sink.begin_run(&data.run)?;
//! for point in &data.points {
//!     sink.write_point(point)?; // durable when this returns
//! }
//! sink.finish(RunStatus::Completed)?;
//!
//! let rec = read_recording(&path)?;
//! assert!(rec.complete);
//! assert_eq!(rec.points, data.points);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod convert;
pub mod map;
pub mod mcap_sink;
pub mod output;
pub mod pb;
pub mod reader;
pub mod scan;
pub mod schema;
pub mod sink;
pub mod synthetic;
pub mod transient;
pub mod types;

use std::path::PathBuf;

use thiserror::Error;

pub use mcap_sink::{McapOptions, McapSink};
pub use reader::{ReadError, ReadOptions, Recording, read_recording, read_recording_with};
pub use sink::{MemorySink, Sink, record_run};
pub use transient::{MemoryTransient, TransientSink};
pub use types::{
    BifurcationRecord, BranchRecord, PointRecord, RunInfo, RunStatus, TruncationCheck,
    TruncationOutcome, TruncationVerdict,
};

/// Errors writing a recording.
#[derive(Debug, Error)]
pub enum RecordError {
    #[error("cannot create recording {path}: {source}")]
    Create {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("writing recording {path}: {source}")]
    Mcap {
        path: PathBuf,
        source: mcap::McapError,
    },
    #[error("invalid run description: {0}")]
    InvalidRun(String),
    #[error("point {index} (ω = {omega_rad_s} rad/s) does not match the run: {reason}")]
    InvalidPoint {
        index: u64,
        omega_rad_s: f64,
        reason: String,
    },
    #[error("bifurcation {number} does not match the run: {reason}")]
    InvalidBifurcation { number: u32, reason: String },
    #[error("point index {index} after {previous}: indices must increase strictly")]
    NonIncreasingIndex { index: u64, previous: u64 },
    /// The output path cannot be written without destroying something the tool did not
    /// write.
    #[error("output {path}: {reason}; nothing was written")]
    Target { path: PathBuf, reason: String },
    #[error("{0} called before begin_run")]
    NotStarted(&'static str),
    #[error("begin_run called twice")]
    AlreadyStarted,
    #[error("the recording is already finished")]
    Finished,
    /// Another process writes the same output.
    #[error(
        "{what} is being written by {holder}: its lock {lock} is held; wait for it to end, or \
         write elsewhere"
    )]
    Locked {
        what: String,
        lock: PathBuf,
        holder: String,
    },
}
