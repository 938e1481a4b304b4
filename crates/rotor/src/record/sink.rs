//! The [`Sink`] trait the continuation writes to, an in-memory sink for tests, the
//! checks every sink applies, and the helper that makes sure a run is always finished
//! (on errors too). A run is stopped cleanly through the flag its driver polls; the
//! applications set that flag from their Ctrl-C handler.

use super::RecordError;
use super::convert::{validate_point, validate_run};
use super::types::{
    BifurcationRecord, BranchRecord, PointRecord, RunInfo, RunStatus, TruncationCheck,
};

/// Where the points of a continuation run go.
///
/// Call order: [`Sink::begin_run`] once, then any number of [`Sink::write_point`] (point
/// indices strictly increasing) and [`Sink::write_bifurcation`], then [`Sink::finish`]
/// exactly once, also when the run failed or was interrupted ([`record_run`] does this).
pub trait Sink {
    /// Starts the run: stores its description.
    fn begin_run(&mut self, run: &RunInfo) -> Result<(), RecordError>;
    /// Writes one converged point; durable on return for sinks backed by a file.
    fn write_point(&mut self, point: &PointRecord) -> Result<(), RecordError>;
    /// Writes one located bifurcation.
    fn write_bifurcation(&mut self, bifurcation: &BifurcationRecord) -> Result<(), RecordError>;
    /// Describes branch `k > 0` before its first point (branches numbered 1, 2, … in
    /// order; points of branch 0 are the run's).
    fn write_branch(&mut self, branch: &BranchRecord) -> Result<(), RecordError>;
    /// Ends the run with its status. Further writes fail with [`RecordError::Finished`].
    fn finish(&mut self, status: RunStatus) -> Result<(), RecordError>;
    /// Writes a warning about the branch between point `after_point` and the next (a
    /// change of stability that could not be located, a fold the multipliers do not
    /// confirm). Default: dropped.
    fn write_note(&mut self, after_point: u64, text: &str) -> Result<(), RecordError> {
        let _ = (after_point, text);
        Ok(())
    }
    /// Writes the check of one event of the run's branch at higher truncation orders
    /// (after the branch, before [`Sink::finish`]). Default: dropped.
    fn write_truncation_check(&mut self, check: &TruncationCheck) -> Result<(), RecordError> {
        let _ = check;
        Ok(())
    }
}

macro_rules! forward_sink {
    ($($t:ty),*) => {$(
        impl<S: Sink + ?Sized> Sink for $t {
            fn begin_run(&mut self, run: &RunInfo) -> Result<(), RecordError> {
                (**self).begin_run(run)
            }
            fn write_point(&mut self, point: &PointRecord) -> Result<(), RecordError> {
                (**self).write_point(point)
            }
            fn write_bifurcation(&mut self, b: &BifurcationRecord) -> Result<(), RecordError> {
                (**self).write_bifurcation(b)
            }
            fn write_branch(&mut self, b: &BranchRecord) -> Result<(), RecordError> {
                (**self).write_branch(b)
            }
            fn finish(&mut self, status: RunStatus) -> Result<(), RecordError> {
                (**self).finish(status)
            }
            fn write_note(&mut self, after_point: u64, text: &str) -> Result<(), RecordError> {
                (**self).write_note(after_point, text)
            }
            fn write_truncation_check(&mut self, c: &TruncationCheck) -> Result<(), RecordError> {
                (**self).write_truncation_check(c)
            }
        }
    )*};
}

forward_sink!(&mut S, Box<S>);

/// The call-order and size checks shared by all sinks.
#[derive(Clone, Debug, Default)]
pub struct SinkChecks {
    run: Option<RunInfo>,
    /// The run as the points of branch `k` see it, at `k − 1`.
    branches: Vec<RunInfo>,
    last_index: Option<u64>,
    finished: bool,
}

impl SinkChecks {
    /// Checks a `begin_run` call.
    pub fn begin(&mut self, run: &RunInfo) -> Result<(), RecordError> {
        if self.finished {
            return Err(RecordError::Finished);
        }
        if self.run.is_some() {
            return Err(RecordError::AlreadyStarted);
        }
        validate_run(run).map_err(RecordError::InvalidRun)?;
        self.run = Some(run.clone());
        Ok(())
    }

    /// Checks a `write_branch` call: branches come numbered 1, 2, … and leave from a
    /// branch already there; its basis must be one.
    pub fn branch(&mut self, b: &BranchRecord) -> Result<(), RecordError> {
        if self.finished {
            return Err(RecordError::Finished);
        }
        let run = self
            .run
            .as_ref()
            .ok_or(RecordError::NotStarted("write_branch"))?;
        let want = self.branches.len() as u32 + 1;
        let reason = if b.branch != want {
            Some(format!(
                "branch {} given where branch {want} comes next",
                b.branch
            ))
        } else if b.parent >= b.branch {
            Some(format!("its parent {} is not an earlier branch", b.parent))
        } else {
            None
        };
        let branch_run = b.run_of(run);
        let reason = reason.or_else(|| validate_run(&branch_run).err());
        if let Some(reason) = reason {
            return Err(RecordError::InvalidRun(format!(
                "branch {}: {reason}",
                b.branch
            )));
        }
        self.branches.push(branch_run);
        Ok(())
    }

    /// Checks a `write_point` call; returns the run as the point's branch sees it.
    pub fn point(&mut self, p: &PointRecord) -> Result<&RunInfo, RecordError> {
        if self.finished {
            return Err(RecordError::Finished);
        }
        let run = self
            .run
            .as_ref()
            .ok_or(RecordError::NotStarted("write_point"))?;
        let run = match p.branch {
            0 => run,
            k => self
                .branches
                .get(k as usize - 1)
                .ok_or_else(|| RecordError::InvalidPoint {
                    index: p.index,
                    omega_rad_s: p.omega_rad_s,
                    reason: format!("branch {k} was not described with write_branch"),
                })?,
        };
        if let Some(previous) = self.last_index
            && p.index <= previous
        {
            return Err(RecordError::NonIncreasingIndex {
                index: p.index,
                previous,
            });
        }
        validate_point(run, p).map_err(|reason| RecordError::InvalidPoint {
            index: p.index,
            omega_rad_s: p.omega_rad_s,
            reason,
        })?;
        self.last_index = Some(p.index);
        Ok(run)
    }

    /// Checks a `write_bifurcation` call; returns the run.
    pub fn bifurcation(&mut self, b: &BifurcationRecord) -> Result<&RunInfo, RecordError> {
        if self.finished {
            return Err(RecordError::Finished);
        }
        let run = self
            .run
            .as_ref()
            .ok_or(RecordError::NotStarted("write_bifurcation"))?;
        if b.amplitude_rms_m.len() != run.nodes.len() {
            return Err(RecordError::InvalidBifurcation {
                number: b.number,
                reason: format!(
                    "amplitude_rms_m: {} values, expected {}",
                    b.amplitude_rms_m.len(),
                    run.nodes.len()
                ),
            });
        }
        Ok(run)
    }

    /// Checks a `finish` call.
    pub fn finish(&mut self) -> Result<(), RecordError> {
        if self.finished {
            return Err(RecordError::Finished);
        }
        self.finished = true;
        Ok(())
    }

    /// Checks a truncation check's place in the call order: after `begin`, before
    /// `finish`.
    pub fn truncation_check(&self) -> Result<(), RecordError> {
        if self.finished {
            return Err(RecordError::Finished);
        }
        self.run
            .as_ref()
            .map(|_| ())
            .ok_or(RecordError::NotStarted("write_truncation_check"))
    }

    /// Whether `finish` was called.
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Index of the last point written.
    pub fn last_index(&self) -> Option<u64> {
        self.last_index
    }

    /// The run, once begun.
    pub fn run(&self) -> Option<&RunInfo> {
        self.run.as_ref()
    }
}

/// Keeps everything in memory; used by tests and as a reference for the file sinks.
#[derive(Clone, Debug, Default)]
pub struct MemorySink {
    checks: SinkChecks,
    pub run: Option<RunInfo>,
    pub points: Vec<PointRecord>,
    pub bifurcations: Vec<BifurcationRecord>,
    pub branches: Vec<BranchRecord>,
    pub status: Option<RunStatus>,
    /// Warnings written with [`Sink::write_note`]: (after point, text).
    pub notes: Vec<(u64, String)>,
    /// Checks written with [`Sink::write_truncation_check`].
    pub truncation: Vec<TruncationCheck>,
}

impl MemorySink {
    pub fn new() -> Self {
        Self::default()
    }
}

impl Sink for MemorySink {
    fn begin_run(&mut self, run: &RunInfo) -> Result<(), RecordError> {
        self.checks.begin(run)?;
        self.run = Some(run.clone());
        Ok(())
    }

    fn write_point(&mut self, point: &PointRecord) -> Result<(), RecordError> {
        self.checks.point(point)?;
        self.points.push(point.clone());
        Ok(())
    }

    fn write_bifurcation(&mut self, bifurcation: &BifurcationRecord) -> Result<(), RecordError> {
        self.checks.bifurcation(bifurcation)?;
        self.bifurcations.push(bifurcation.clone());
        Ok(())
    }

    fn write_branch(&mut self, branch: &BranchRecord) -> Result<(), RecordError> {
        self.checks.branch(branch)?;
        self.branches.push(branch.clone());
        Ok(())
    }

    fn finish(&mut self, status: RunStatus) -> Result<(), RecordError> {
        self.checks.finish()?;
        self.status = Some(status);
        Ok(())
    }

    fn write_note(&mut self, after_point: u64, text: &str) -> Result<(), RecordError> {
        self.notes.push((after_point, text.to_string()));
        Ok(())
    }

    fn write_truncation_check(&mut self, check: &TruncationCheck) -> Result<(), RecordError> {
        self.checks.truncation_check()?;
        self.truncation.push(check.clone());
        Ok(())
    }
}

/// Begins the run on `sink`, runs `body`, and finishes the sink in every case: with the
/// status `body` returns, or with [`RunStatus::Failed`] carrying the error text when it
/// fails (the error is then returned unchanged, after the recording was closed).
pub fn record_run<S, T, E, F>(sink: &mut S, run: &RunInfo, body: F) -> Result<T, E>
where
    S: Sink + ?Sized,
    E: std::fmt::Display + From<RecordError>,
    F: FnOnce(&mut S) -> Result<(T, RunStatus), E>,
{
    sink.begin_run(run)?;
    match body(sink) {
        Ok((value, status)) => {
            sink.finish(status)?;
            Ok(value)
        }
        Err(err) => {
            // The body's error is the one to report; a failure to close is secondary.
            let _ = sink.finish(RunStatus::Failed(err.to_string()));
            Err(err)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_labels_round_trip() {
        for s in [
            RunStatus::Completed,
            RunStatus::Interrupted,
            RunStatus::Failed("Newton: 30 iterations".into()),
        ] {
            assert_eq!(RunStatus::from_label(&s.label()), s);
        }
    }
}
