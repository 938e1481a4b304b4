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
    /// The table of the bifurcations at higher truncation orders comes from the checks the
    /// sweeps recorded; with this, recordings without them (earlier versions, `verify =
    /// false`) are re-solved now at the order plus one and plus two (`replay verify`; about
    /// 10 s a run with bifurcations on the dual rotor).
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
    // the command line that regenerates the report, for its header
    let source = match &args.truncation {
        Some(p) => format!("{} --truncation {}", args.dir.display(), p.display()),
        None => args.dir.display().to_string(),
    };
    let mut text = markdown(&runs, &source, truncation.as_deref());
    text.push_str(&verdicts(&args.dir, args.verify)?);
    emit(args, &text, out)
}

/// The campaign's bifurcations at higher truncation orders, as a markdown section (one
/// row per located bifurcation or unlocated change of stability of a run's own branch):
/// the checks each sweep recorded (`/truncation`), or, with `resolve`, re-solved now for
/// the recordings that have none (`replay verify`). Empty when there is nothing to show.
fn verdicts(dir: &std::path::Path, resolve: bool) -> anyhow::Result<String> {
    use crate::truncation::verify::{VerifyOptions, verify_bifurcations};
    let mut rows = Vec::new();
    let mut orders_seen: Vec<u32> = Vec::new();
    for (name, path) in campaign_runs(dir)? {
        let rec = crate::record::read_recording(&path)
            .with_context(|| format!("{}: cannot read the recording", path.display()))?;
        let checks = if !rec.truncation.is_empty() {
            rec.truncation.clone()
        } else if resolve && rec.bifurcations.iter().any(|b| b.branch == 0) {
            let order = crate::sweep::StudySettings::from_run(&rec.run)?
                .harmonic
                .order;
            verify_bifurcations(&rec, &VerifyOptions::for_order(order), |_| {})?
        } else {
            continue;
        };
        for c in &checks {
            for (k, _) in &c.orders {
                if !orders_seen.contains(k) {
                    orders_seen.push(*k);
                }
            }
        }
        for c in checks {
            rows.push((name.clone(), c));
        }
    }
    if rows.is_empty() {
        return Ok(if resolve {
            "\n## The bifurcations at higher truncation orders\n\nNo run has a located bifurcation.\n"
                .to_string()
        } else {
            String::new()
        });
    }
    orders_seen.sort_unstable();
    let mut s = String::from("\n## The bifurcations at higher truncation orders\n\n");
    s.push_str(
        "Each located bifurcation of a run's own branch, and each change of stability it \
         could not locate, re-solved on the basis of a higher order over a window of \
         ±1 rad/s from the recorded point before it (by the sweep after its branch, or \
         `replay verify`): converged when the same kind lies within 0.05 rad/s, moved when \
         farther in the window, vanished when none is there. A bifurcation that vanished at \
         every higher order is not a result: the statements above leave it out.\n\n",
    );
    let heads: Vec<String> = orders_seen.iter().map(|k| format!("order {k}")).collect();
    s.push_str(&format!(
        "| run | kind | ω (rad/s) | {} | verdict |\n",
        heads.join(" | ")
    ));
    s.push_str(&format!(
        "|---|---|---|{}---|\n",
        "---|".repeat(heads.len())
    ));
    for (name, c) in rows {
        let cells: Vec<String> = orders_seen
            .iter()
            .map(|k| {
                c.orders
                    .iter()
                    .find(|(o, _)| o == k)
                    .map_or("".to_string(), |(_, o)| o.describe(4).replace('|', "/"))
            })
            .collect();
        s.push_str(&format!(
            "| {name} | {} | {:.4} | {} | {} |\n",
            c.kind.map_or("change", |k| k.abbreviation()),
            c.omega_rad_s,
            cells.join(" | "),
            c.verdict().label()
        ));
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
