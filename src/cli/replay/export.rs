//! `replay export FILE --out DIR`: every table of [`crate::derive::table::tables`] as
//! `DIR/<name>.csv`, plus the embedded model (`model.toml`) and settings (`settings.toml`).

use std::io::Write;
use std::path::Path;

use anyhow::Context;

use crate::derive::table;
use crate::record::output::write_atomic;
use crate::record::reader::Recording;

/// Writes the tables and the embedded texts into `dir` (created if missing) and lists what
/// it wrote on `out`. Each file is written under a temporary name and renamed into place,
/// so a file that is there is complete.
pub fn run(rec: &Recording, dir: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
    crate::input::ensure_dir(dir)
        .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
    for t in table::tables(rec) {
        let mut bytes = Vec::new();
        t.write_csv(&mut bytes)?;
        let path = dir.join(format!("{}.csv", t.name));
        write_file(&path, &bytes)?;
        writeln!(
            out,
            "{}: {} rows, {} columns",
            path.display(),
            t.rows.len(),
            t.header.len()
        )?;
    }
    for (name, text) in [
        ("model.toml", &rec.run.model_text),
        ("settings.toml", &rec.run.settings_toml),
    ] {
        if !text.is_empty() {
            let path = dir.join(name);
            write_file(&path, text.as_bytes())?;
            writeln!(out, "{}", path.display())?;
        }
    }
    Ok(())
}

fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    write_atomic(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

/// `replay export` of an operating map: its three CSVs (as `tmrotor campaign map` writes
/// them) into `dir`, created if missing.
pub fn map(
    map: &crate::campaign::map::OperatingMap,
    dir: &Path,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    crate::input::ensure_dir(dir)
        .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
    for path in crate::campaign::map::write_map_csvs(map, dir)? {
        writeln!(out, "{}", path.display())?;
    }
    Ok(())
}
