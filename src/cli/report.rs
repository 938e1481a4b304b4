//! `tmrotor report DIR`: the reproduction report (markdown) of a campaign directory.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::report::{campaign_findings, markdown, sensitivity_markdown};

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
    let text = markdown(
        &runs,
        &args.dir.display().to_string(),
        truncation.as_deref(),
    );
    emit(args, &text, out)
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
