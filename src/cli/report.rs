//! `tmrotor report DIR`: the reproduction report (markdown) of a campaign directory.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::report::{campaign_findings, campaign_runs, markdown, sensitivity_markdown};

/// Arguments of `tmrotor report`.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Campaign output directory (with manifest.toml), e.g. examples/paper_campaign-out.
    pub dir: PathBuf,
    /// Output file; default: stdout.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// CSV of the truncation study (`tmrotor truncation --csv FILE`, e.g.
    /// examples/truncation_q2.csv) to tabulate and judge.
    #[arg(long)]
    pub truncation: Option<PathBuf>,
    /// Score every model variant of the campaign (its runs grouped by the values they
    /// set) on the statements instead: the sensitivity table.
    #[arg(long)]
    pub sensitivity: bool,
    /// Re-solve every run's located bifurcations at the recorded truncation order plus
    /// one and plus two (`replay verify`) and add their verdicts as a table (about 10 s a
    /// run with bifurcations on the dual rotor).
    #[arg(long)]
    pub verify: bool,
}

/// Writes the report.
pub fn run(args: &ReportArgs, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    let runs = campaign_findings(&args.dir)?;
    if args.sensitivity {
        let text = sensitivity_markdown(&runs, &args.dir.display().to_string());
        return emit(args, &text, out);
    }
    let truncation = match &args.truncation {
        Some(p) => Some(
            std::fs::read_to_string(p)
                .with_context(|| format!("{}: cannot read the truncation study", p.display()))?,
        ),
        None => None,
    };
    let mut text = markdown(
        &runs,
        &args.dir.display().to_string(),
        truncation.as_deref(),
    );
    if args.verify {
        text.push_str(&verdicts(&args.dir)?);
    }
    emit(args, &text, out)
}

/// The campaign's bifurcations re-solved at higher truncation orders, as a markdown
/// section (one row per bifurcation of a run's own branch).
fn verdicts(dir: &std::path::Path) -> anyhow::Result<String> {
    use crate::truncation::verify::{VerifyOptions, verify_bifurcations};
    let mut rows = Vec::new();
    let mut orders_seen = Vec::new();
    for (name, path) in campaign_runs(dir)? {
        let rec = crate::record::read_recording(&path)
            .with_context(|| format!("{}: cannot read the recording", path.display()))?;
        if rec.bifurcations.iter().all(|b| b.branch != 0) {
            continue;
        }
        let order = crate::sweep::StudySettings::from_run(&rec.run)?
            .harmonic
            .order;
        let options = VerifyOptions::for_order(order);
        orders_seen.clone_from(&options.orders);
        for v in verify_bifurcations(&rec, &options, |_| {})? {
            let cells: Vec<String> = v
                .orders
                .iter()
                .map(|(_, o)| o.describe(4).replace('|', "/"))
                .collect();
            rows.push(format!(
                "| {name} | {} | {:.4} | {} |",
                v.kind.abbreviation(),
                v.omega_rad_s,
                cells.join(" | ")
            ));
        }
    }
    let mut s = String::from("\n## The bifurcations at higher truncation orders\n\n");
    if rows.is_empty() {
        s.push_str("No run has a located bifurcation.\n");
        return Ok(s);
    }
    s.push_str(
        "Each located bifurcation of a run's own branch re-solved on the basis of a higher \
         order over a window of ±1 rad/s from the recorded point before it (`replay verify`): \
         converged when the same kind lies within 0.05 rad/s, moved when farther in the \
         window, vanished when none is there.\n\n",
    );
    let heads: Vec<String> = orders_seen.iter().map(|k| format!("order {k}")).collect();
    s.push_str(&format!(
        "| run | kind | ω (rad/s) | {} |\n",
        heads.join(" | ")
    ));
    s.push_str(&format!("|---|---|---|{}\n", "---|".repeat(heads.len())));
    for r in rows {
        s.push_str(&r);
        s.push('\n');
    }
    Ok(s)
}

fn emit(args: &ReportArgs, text: &str, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    match &args.output {
        Some(p) => {
            std::fs::write(p, text).with_context(|| format!("{}: cannot write", p.display()))?;
            writeln!(out, "wrote {}", p.display())?;
        }
        None => write!(out, "{text}")?,
    }
    Ok(())
}
