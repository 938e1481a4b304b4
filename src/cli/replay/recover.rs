//! `replay recover IN OUT`: a clean recording of every point that survives in a damaged or
//! cut file.

use std::io::Write;
use std::path::Path;

use anyhow::bail;

use crate::record::reader::{Recording, index_ranges};
use crate::record::{McapOptions, McapSink, RunStatus, Sink};

/// Writes the run description, every intact point and bifurcation of `rec` into a new
/// recording at `target` (refused when it exists), with the original warnings and a note
/// of what was lost, and the original status (`interrupted` when the file had none).
pub fn run(rec: &Recording, target: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
    if target.exists() {
        bail!(
            "{} exists: recover writes a new file (choose another name)",
            target.display()
        );
    }
    if rec.points.is_empty() {
        bail!(
            "{}: no intact point to recover ({})",
            rec.file.display(),
            rec.notes.join("; ")
        );
    }
    // Points read from a lean recording have no orbits; keep that form.
    let options = if rec.points.iter().any(|p| p.orbits.is_empty()) {
        McapOptions::lean()
    } else {
        McapOptions::default()
    };
    let mut sink = McapSink::create(target, options)?;
    sink.begin_run(&rec.run)?;
    let mut bifs = rec.bifurcations.iter().peekable();
    let mut branches = rec.branches.iter().peekable();
    for p in &rec.points {
        while let Some(b) = bifs.next_if(|b| b.after_point < p.index) {
            sink.write_bifurcation(b)?;
        }
        // a branch is described before its first point
        while let Some(b) = branches.next_if(|b| b.branch <= p.branch) {
            sink.write_branch(b)?;
        }
        sink.write_point(p)?;
    }
    let last = rec.points.last().map_or(0, |p| p.index);
    for b in bifs {
        if b.after_point <= last {
            sink.write_bifurcation(b)?;
        }
    }
    for w in &rec.warnings {
        sink.write_note(last, w)?;
    }
    let lost = if rec.missing.is_empty() {
        String::new()
    } else {
        format!("; points lost: {}", index_ranges(&rec.missing))
    };
    let note = format!(
        "recovered by replay recover from {}: {} points{lost}",
        rec.file.display(),
        rec.points.len()
    );
    sink.write_note(last, &note)?;
    sink.finish(rec.status.clone().unwrap_or(RunStatus::Interrupted))?;
    writeln!(
        out,
        "wrote {} ({} points{lost}; from {}: {})",
        target.display(),
        rec.points.len(),
        rec.file.display(),
        if rec.complete {
            "complete".to_string()
        } else {
            rec.notes.join("; ")
        }
    )?;
    Ok(())
}
