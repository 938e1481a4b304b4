//! `tmrotor campaign`: several sweeps from one file, in parallel, with a manifest.

use std::path::PathBuf;
use std::sync::Mutex;

use clap::{Args, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use crate::campaign;
use crate::record::install_interrupt_flag;

#[derive(Debug, Clone, Args)]
pub struct CampaignArgs {
    #[command(subcommand)]
    pub merge: Option<CampaignCommand>,
    /// Campaign file (TOML; see `examples/paper_campaign.toml`).
    pub file: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run only shard I of N (runs whose position p has p mod N = I), e.g. `--shard 0/4`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Debug, Clone, Subcommand)]
pub enum CampaignCommand {
    /// Join the shard manifests of an output directory into manifest.toml.
    Merge {
        /// The campaign's output directory.
        dir: PathBuf,
    },
}

fn parse_shard(s: &str) -> anyhow::Result<(usize, usize)> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| anyhow::anyhow!("--shard {s:?}: expected I/N"))?;
    let (i, n): (usize, usize) = (
        i.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--shard {s:?}: I is not a number"))?,
        n.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--shard {s:?}: N is not a number"))?,
    );
    if n == 0 || i >= n {
        anyhow::bail!("--shard {s:?}: need 0 ≤ I < N");
    }
    Ok((i, n))
}

pub fn run(args: &CampaignArgs, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    if let Some(CampaignCommand::Merge { dir }) = &args.merge {
        let m = campaign::merge_manifests(dir)?;
        writeln!(
            out,
            "merged {} runs into {}",
            m.runs.len(),
            dir.join("manifest.toml").display()
        )?;
        return Ok(());
    }
    let file = args
        .file
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("campaign: give a campaign file (or `merge DIR`)"))?;
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let multi = MultiProgress::new();
    if args.quiet {
        multi.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let style = ProgressStyle::with_template("{prefix:>10} {elapsed_precise} [{bar:25}] {msg}")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    let bars: Mutex<Vec<(String, ProgressBar)>> = Mutex::new(Vec::new());
    let progress = |name: &str, p: &crate::sweep::Progress| {
        if let Ok(mut b) = bars.lock() {
            let bar = match b.iter().find(|(n, _)| n == name) {
                Some((_, bar)) => bar.clone(),
                None => {
                    let bar = multi.add(ProgressBar::new(1000));
                    bar.set_style(style.clone());
                    bar.set_prefix(name.to_string());
                    b.push((name.to_string(), bar.clone()));
                    bar
                }
            };
            bar.set_position((p.fraction * 1000.0) as u64);
            bar.set_message(format!(
                "ω {:.1} rad/s, {} points, {} bifurcations",
                p.omega_rad_s, p.points, p.bifurcations
            ));
        }
    };
    let interrupt = install_interrupt_flag().ok();
    let manifest = campaign::run(file, args.threads, shard, interrupt, &progress)?;
    if let Ok(b) = bars.lock() {
        for (_, bar) in b.iter() {
            bar.finish_and_clear();
        }
    }
    for r in &manifest.runs {
        writeln!(
            out,
            "{:>12}  {:<12} {:>5} points {:>7.1} s  {}",
            r.name, r.status, r.points, r.seconds, r.recording
        )?;
    }
    Ok(())
}
