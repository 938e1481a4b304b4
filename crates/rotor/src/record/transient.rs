//! Transient runs in a recording: the messages of `/transient/info`,
//! `/transient/revolution` and `/transient/samples` (`proto/tmrotor/v1/transient.proto`),
//! the [`TransientSink`] seam the transient driver writes to, and an in-memory sink.
//!
//! The records are the protobuf messages themselves: each is a flat list of numbers per
//! node, thermal node or bearing in the order of the run's [`RunInfo`], with nothing to
//! convert. Log times are simulated time ([`time_ns`]).

use super::RecordError;
use super::types::{RunInfo, RunStatus};

pub use super::pb::tmrotor::v1::{Revolution, Samples, TransientInfo};

/// Log time of simulated time `t` (s), in nanoseconds.
pub fn time_ns(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        (t * 1e9).round().min(u64::MAX as f64) as u64
    } else {
        0
    }
}

/// The dynamic node with the largest RMS amplitude at `revolution`: its index (in
/// `RunInfo.nodes` order) and the amplitude (m); `(0, 0.0)` without nodes.
pub fn largest_amplitude(revolution: &Revolution) -> (usize, f64) {
    revolution
        .amplitude_rms_m
        .iter()
        .enumerate()
        .fold(
            (0, 0.0),
            |(bk, ba), (k, &a)| if a > ba { (k, a) } else { (bk, ba) },
        )
}

/// Where a transient run goes. Call order: [`TransientSink::begin_transient`] once, then
/// samples and revolutions in time order, then [`TransientSink::finish_transient`] exactly
/// once (also when the run failed or was interrupted).
pub trait TransientSink {
    /// Stores the run description and the transient's settings.
    fn begin_transient(&mut self, run: &RunInfo, info: &TransientInfo) -> Result<(), RecordError>;
    /// Writes one decimated sample of the displacements.
    fn write_samples(&mut self, samples: &Samples) -> Result<(), RecordError>;
    /// Writes one revolution's record; durable on return for sinks backed by a file.
    fn write_revolution(&mut self, revolution: &Revolution) -> Result<(), RecordError>;
    /// Ends the run with its status.
    fn finish_transient(&mut self, status: RunStatus) -> Result<(), RecordError>;
}

/// A transient run kept in memory (tests, and callers that post-process at once).
#[derive(Clone, Debug, Default)]
pub struct MemoryTransient {
    pub run: Option<RunInfo>,
    pub info: Option<TransientInfo>,
    pub samples: Vec<Samples>,
    pub revolutions: Vec<Revolution>,
    pub status: Option<RunStatus>,
}

impl TransientSink for MemoryTransient {
    fn begin_transient(&mut self, run: &RunInfo, info: &TransientInfo) -> Result<(), RecordError> {
        if self.run.is_some() {
            return Err(RecordError::NotStarted("begin_transient called twice"));
        }
        self.run = Some(run.clone());
        self.info = Some(info.clone());
        Ok(())
    }
    fn write_samples(&mut self, samples: &Samples) -> Result<(), RecordError> {
        self.samples.push(samples.clone());
        Ok(())
    }
    fn write_revolution(&mut self, revolution: &Revolution) -> Result<(), RecordError> {
        if self.run.is_none() {
            return Err(RecordError::NotStarted("write_revolution"));
        }
        self.revolutions.push(revolution.clone());
        Ok(())
    }
    fn finish_transient(&mut self, status: RunStatus) -> Result<(), RecordError> {
        if self.status.is_some() {
            return Err(RecordError::Finished);
        }
        self.status = Some(status);
        Ok(())
    }
}

impl<S: TransientSink + ?Sized> TransientSink for &mut S {
    fn begin_transient(&mut self, run: &RunInfo, info: &TransientInfo) -> Result<(), RecordError> {
        (**self).begin_transient(run, info)
    }
    fn write_samples(&mut self, samples: &Samples) -> Result<(), RecordError> {
        (**self).write_samples(samples)
    }
    fn write_revolution(&mut self, revolution: &Revolution) -> Result<(), RecordError> {
        (**self).write_revolution(revolution)
    }
    fn finish_transient(&mut self, status: RunStatus) -> Result<(), RecordError> {
        (**self).finish_transient(status)
    }
}
