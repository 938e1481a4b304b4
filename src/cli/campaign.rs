//! `tmrotor campaign`: several sweeps from one file, in parallel, with a manifest; and
//! `campaign plot DIR`: the runs overlaid in PNG figures ([`campaign::figures`]).

use std::path::PathBuf;
use std::sync::Mutex;

use clap::{Args, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use crate::campaign;
use crate::campaign::figures::{CampaignFigures, FigureOptions, plot_campaign};
use crate::cli::sweep::progress_message;
use crate::record::install_interrupt_flag;

#[derive(Debug, Clone, Args)]
pub struct CampaignArgs {
    #[command(subcommand)]
    pub command: Option<CampaignCommand>,
    /// Campaign file (TOML; see `examples/paper_campaign.toml`).
    pub file: Option<PathBuf>,
    /// Runs computed at the same time (default: one per core). Each run's parallel parts
    /// get `threads / runs at a time` threads of their own (at least one); with one run
    /// at a time, it uses every core, and so does the last run still going once all
    /// have started.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run only shard I of N (runs whose position p has p mod N = I), e.g. `--shard 0/4`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
    /// Do not write the figures (`figures/` in the output directory) when every run has
    /// completed.
    #[arg(long)]
    pub no_figures: bool,
}

#[derive(Debug, Clone, Subcommand)]
pub enum CampaignCommand {
    /// Join the shard manifests of an output directory into manifest.toml.
    Merge {
        /// The campaign's output directory.
        dir: PathBuf,
    },
    /// PNG figures of all runs overlaid: amplitude of node 8, clearance variations,
    /// temperatures (reads manifest.toml and the recordings of DIR).
    Plot {
        /// The campaign's output directory (holds manifest.toml).
        dir: PathBuf,
        /// Where the figures go (default: DIR/figures).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Dynamic node of the amplitude–frequency figure; repeat for several
        /// (default: 8, the paper's Fig. 8a).
        #[arg(long = "node", value_name = "ID")]
        nodes: Vec<u32>,
        /// ω of the bearing-position temperature chart, rad/s (nearest recorded point).
        #[arg(long, default_value_t = 620.0)]
        omega: f64,
    },
}

fn report(figures: &CampaignFigures, out: &mut impl std::io::Write) -> std::io::Result<()> {
    for note in &figures.notes {
        writeln!(out, "note: {note}")?;
    }
    for path in &figures.written {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
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
    if let Some(CampaignCommand::Merge { dir }) = &args.command {
        let m = campaign::merge_manifests(dir)?;
        writeln!(
            out,
            "merged {} runs into {}",
            m.runs.len(),
            dir.join("manifest.toml").display()
        )?;
        return Ok(());
    }
    if let Some(CampaignCommand::Plot {
        dir,
        out: fig_dir,
        nodes,
        omega,
    }) = &args.command
    {
        let options = FigureOptions {
            nodes: nodes.clone(),
            omega_rad_s: *omega,
            ..FigureOptions::default()
        };
        let fig_dir = fig_dir.clone().unwrap_or_else(|| dir.join("figures"));
        let figures = plot_campaign(dir, &fig_dir, &options)?;
        report(&figures, out)?;
        return Ok(());
    }
    let file = args.file.as_ref().ok_or_else(|| {
        anyhow::anyhow!("campaign: give a campaign file (or `merge DIR`, `plot DIR`)")
    })?;
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
            bar.set_message(progress_message(p, "ω "));
        }
    };
    let interrupt = install_interrupt_flag().ok();
    let manifest = campaign::run(file, args.threads, shard, interrupt.clone(), &progress)?;
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
    if !args.no_figures {
        figures(&manifest, file, shard.is_some(), out)?;
    }
    let stopped = interrupt.is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed));
    let unfinished: Vec<&str> = manifest
        .runs
        .iter()
        .filter(|r| r.status != "completed")
        .map(|r| r.name.as_str())
        .collect();
    if unfinished.is_empty() {
        return Ok(());
    }
    let which = unfinished.join(", ");
    if stopped {
        return Err(super::Interrupted(format!(
            "{} of {} runs not completed ({which}); the same command resumes them",
            unfinished.len(),
            manifest.runs.len()
        ))
        .into());
    }
    anyhow::bail!(
        "{} of {} runs did not complete ({which}); their status and how they ended are in \
         the manifest",
        unfinished.len(),
        manifest.runs.len()
    )
}

/// The campaign's figures once every run is complete (or why they are not drawn).
fn figures(
    manifest: &campaign::Manifest,
    file: &std::path::Path,
    sharded: bool,
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    let pending = manifest
        .runs
        .iter()
        .filter(|r| r.status != "completed")
        .count();
    let (_, _, dir) = campaign::load(file)?;
    if sharded {
        writeln!(
            out,
            "figures: not written for a shard; after `tmrotor campaign merge {0}`, run \
             `tmrotor campaign plot {0}`",
            dir.display()
        )?;
    } else if pending > 0 {
        writeln!(
            out,
            "figures: not written, {pending} run(s) not completed; `tmrotor campaign plot {}` \
             draws what there is",
            dir.display()
        )?;
    } else {
        let figures = plot_campaign(&dir, &dir.join("figures"), &FigureOptions::default())
            .map_err(|e| anyhow::anyhow!("the runs are recorded, but the figures failed: {e}"))?;
        report(&figures, out)?;
    }
    Ok(())
}
