//! `replay branch FILE [--csv]`: the branch table of [`crate::derive::table::branch`].

use std::io::Write;

use crate::derive::table;
use crate::record::reader::Recording;

/// Writes one row per point (columns: [`table::branch`]), as CSV or aligned text.
pub fn run(rec: &Recording, csv: bool, out: &mut dyn Write) -> anyhow::Result<()> {
    let t = table::branch(rec);
    if csv {
        t.write_csv(out)?;
    } else {
        t.write_aligned(out)?;
    }
    Ok(())
}
