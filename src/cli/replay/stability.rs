//! `replay stability FILE`.

use std::io::Write;

use crate::derive::{StabilityRederive, multiplier_deviation, rederivers_with_intervals};
use crate::record::reader::Recording;

use super::NotAvailable;

/// Result of comparing recomputed and stored multipliers.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityComparison {
    /// Points compared.
    pub compared: usize,
    /// Largest multiplier deviation over all points, and at which point index.
    pub max_deviation: Option<(f64, u64)>,
    /// Points whose stable flag would change.
    pub flag_changes: Vec<u64>,
}

/// Recomputes the multipliers of every point that has stored ones with `method` and
/// compares them.
pub fn compare(
    rec: &Recording,
    method: &dyn StabilityRederive,
) -> anyhow::Result<StabilityComparison> {
    compare_with(rec, method, |_, _| {})
}

/// [`compare`], telling `progress(done, total)` after each point.
pub fn compare_with(
    rec: &Recording,
    method: &dyn StabilityRederive,
    mut progress: impl FnMut(usize, usize),
) -> anyhow::Result<StabilityComparison> {
    let total = rec
        .points
        .iter()
        .filter(|p| !p.multipliers.is_empty())
        .count();
    let mut result = StabilityComparison {
        compared: 0,
        max_deviation: None,
        flag_changes: Vec::new(),
    };
    for p in rec.points.iter().filter(|p| !p.multipliers.is_empty()) {
        let floquet = method.floquet(p)?;
        let fresh = &floquet.multipliers;
        let dev = multiplier_deviation(&p.multipliers, fresh).ok_or_else(|| {
            anyhow::anyhow!(
                "point {}: {} multipliers recomputed, {} stored{}",
                p.index,
                fresh.len(),
                p.multipliers.len(),
                if p.multipliers.len() > fresh.len() && p.slow_exponents.is_empty() {
                    " (the recording was written before the stability was split into fast \
                     multipliers and slow thermal exponents, with the thermal multipliers \
                     among its own: recompute it with the version that wrote it)"
                } else {
                    ""
                }
            )
        })?;
        result.compared += 1;
        progress(result.compared, total);
        if result.max_deviation.is_none_or(|(d, _)| dev > d) {
            result.max_deviation = Some((dev, p.index));
        }
        if p.stable.is_some_and(|s| s != floquet.stable) {
            result.flag_changes.push(p.index);
        }
    }
    Ok(result)
}

/// Runs the comparison with `method`, or with the method rebuilt from the recording's
/// model (with `sip_intervals` replacing the recorded intervals when given, to audit the
/// stored stability with a finer product); fails with [`NotAvailable`] when there is
/// none.
pub fn run(
    rec: &Recording,
    method: Option<&dyn StabilityRederive>,
    sip_intervals: Option<usize>,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if let Some(n) = sip_intervals.filter(|&n| n < 8 || n % 2 != 0) {
        anyhow::bail!(
            "--sip-intervals {n}: must be an even number of at least 8 (the exp-sip product \
             is extrapolated from N and N/2 intervals)"
        );
    }
    if let Some(n) = sip_intervals.filter(|&n| n > crate::study::MAX_SIP_INTERVALS) {
        anyhow::bail!(
            "--sip-intervals {n}: must be at most {} (the product keeps a state per interval)",
            crate::study::MAX_SIP_INTERVALS
        );
    }
    // a recording with several branches: each on its own basis, compared in turn
    if method.is_none() && !rec.branches.is_empty() {
        let mut total = StabilityComparison {
            compared: 0,
            max_deviation: None,
            flag_changes: Vec::new(),
        };
        for k in rec.branch_numbers() {
            let Some(run) = rec.run_of(k) else { continue };
            let hooks = rederivers_with_intervals(&run, sip_intervals);
            let Some(m) = &hooks.stability else {
                return Err(NotAvailable(format!(
                    "Floquet multipliers cannot be recomputed for {} (branch {k}): {}",
                    rec.file.display(),
                    hooks.unavailable_reason
                ))
                .into());
            };
            let sub = Recording {
                run: run.into_owned(),
                points: rec
                    .points
                    .iter()
                    .filter(|p| p.branch == k)
                    .cloned()
                    .collect(),
                ..rec.clone()
            };
            let c = with_progress(|progress| compare_with(&sub, m.as_ref(), progress))?;
            total.compared += c.compared;
            if let Some((d, i)) = c.max_deviation
                && total.max_deviation.is_none_or(|(t, _)| d > t)
            {
                total.max_deviation = Some((d, i));
            }
            total.flag_changes.extend(c.flag_changes);
        }
        return report(total, sip_intervals, out);
    }
    let hooks;
    let method = match method {
        Some(m) => m,
        None => {
            hooks = rederivers_with_intervals(&rec.run, sip_intervals);
            match &hooks.stability {
                Some(m) => m.as_ref(),
                None => {
                    let stored = rec
                        .points
                        .iter()
                        .filter(|p| !p.multipliers.is_empty())
                        .count();
                    return Err(NotAvailable(format!(
                        "Floquet multipliers cannot be recomputed for {}: {} ({stored} of {} \
                         points have stored multipliers; `replay branch` lists their stability)",
                        rec.file.display(),
                        hooks.unavailable_reason,
                        rec.points.len()
                    ))
                    .into());
                }
            }
        }
    };
    let c = with_progress(|progress| compare_with(rec, method, progress))?;
    report(c, sip_intervals, out)
}

/// Prints a comparison.
fn report(
    c: StabilityComparison,
    sip_intervals: Option<usize>,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if let Some(n) = sip_intervals {
        writeln!(out, "recomputed with sip_intervals = {n}")?;
    }
    writeln!(out, "points compared: {}", c.compared)?;
    match c.max_deviation {
        Some((d, i)) => writeln!(
            out,
            "largest deviation |μ_recomputed − μ_stored|: {d:e} (point {i})"
        )?,
        None => writeln!(out, "no point has stored multipliers")?,
    }
    if c.flag_changes.is_empty() {
        writeln!(out, "stable flags: all agree")?;
    } else {
        writeln!(out, "stable flag differs at points: {:?}", c.flag_changes)?;
    }
    Ok(())
}

/// Runs `work` with a progress report of its points: a bar on a terminal, else (a log
/// file) a line every [`crate::cli::LOG_EVERY`]; an audit on a finer product takes about
/// a second a point.
fn with_progress<T>(work: impl FnOnce(&mut dyn FnMut(usize, usize)) -> T) -> T {
    use std::io::IsTerminal;
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(crate::cli::bar_style(
        "{elapsed_precise} [{bar:30}] {pos}/{len} points recomputed",
    ));
    let log = !std::io::stderr().is_terminal();
    let start = std::time::Instant::now();
    let mut last = start;
    let out = work(&mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        if log && last.elapsed() >= crate::cli::LOG_EVERY {
            last = std::time::Instant::now();
            eprintln!(
                "replay stability: {done}/{total} points recomputed after {:.0} s",
                start.elapsed().as_secs_f64()
            );
        }
    });
    bar.finish_and_clear();
    out
}
