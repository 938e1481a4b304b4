//! `replay verify FILE`: the located bifurcations re-solved at higher truncation orders.

use std::io::Write;

use crate::record::reader::Recording;
use crate::truncation::verify::{VerifyOptions, verify_bifurcations};

/// Runs the check and prints one line per bifurcation and order.
pub fn run(
    rec: &Recording,
    orders: &[u32],
    window: f64,
    tolerance: f64,
    out: &mut dyn Write,
    err: &mut (dyn Write + Send),
) -> anyhow::Result<()> {
    let settings = crate::sweep::StudySettings::from_run(&rec.run)?;
    let recorded = settings.harmonic.order;
    let mut options = VerifyOptions::for_order(recorded);
    if !orders.is_empty() {
        options.orders = orders.to_vec();
    }
    for (name, v) in [("--window", window), ("--tolerance", tolerance)] {
        if !(v.is_finite() && v > 0.0) {
            anyhow::bail!("{name} {v}: must be a positive number of rad/s");
        }
    }
    if let Some(bad) = options.orders.iter().find(|&&k| k == 0 || k > 12) {
        anyhow::bail!("--orders: {bad} is not a truncation order from 1 to 12");
    }
    options.window_rad_s = window;
    options.tolerance_rad_s = tolerance;
    if rec.bifurcations.iter().all(|b| b.branch != 0) {
        writeln!(
            out,
            "no located bifurcation on the run's branch: nothing to verify"
        )?;
        return Ok(());
    }
    let verdicts = verify_bifurcations(rec, &options, |msg| {
        let _ = writeln!(err, "verify: {msg}");
    })?;
    writeln!(
        out,
        "recorded at order {recorded}; re-solved at {} (window ±{window} rad/s, converged within {tolerance} rad/s)",
        options
            .orders
            .iter()
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    )?;
    for v in &verdicts {
        let cells: Vec<String> = v
            .orders
            .iter()
            .map(|(k, o)| format!("order {k} {}", o.describe(4)))
            .collect();
        writeln!(
            out,
            "  #{} {} at ω = {:.4} rad/s: {}",
            u64::from(v.number) + 1,
            v.what(),
            v.omega_rad_s,
            cells.join("; ")
        )?;
    }
    Ok(())
}
