//! The `tmrotor` command line: one file per subcommand, each with `run(args)`.
//! `src/main.rs` only parses and maps errors to exit codes.

pub mod campaign;
pub mod campbell;
pub mod model;
pub mod modes;
pub mod report;
pub mod sweep;
pub mod truncation;

use clap::{Parser, Subcommand};

/// How often a long command whose progress goes to a file (not a terminal) writes a
/// progress line: often enough to follow a cluster job's log, rarely enough to keep it
/// short (a default sweep writes one line, a paper campaign about seven).
pub const LOG_EVERY: std::time::Duration = std::time::Duration::from_secs(15);

/// Nonlinear thermo-mechanical rotor dynamics: harmonic balance, continuation, Floquet
/// stability, MCAP recordings.
#[derive(Debug, Parser)]
#[command(name = "tmrotor", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run one continuation sweep (default: the built-in dual rotor, q_l = 2 L/min, 25 °C,
    /// ω ∈ [300, 700] rad/s, order 3) and write an MCAP recording.
    Sweep(sweep::SweepArgs),
    /// Run a campaign of sweeps (TOML file) in parallel, one recording per run plus a
    /// manifest; resumable, shardable (`--shard I/N`, then `campaign merge DIR`).
    Campaign(campaign::CampaignArgs),
    /// Check a model file, or print the built-in one.
    #[command(subcommand)]
    Model(model::ModelCommand),
    /// Damped natural frequencies, damping ratios and whirl directions at one speed.
    Modes(modes::ModesArgs),
    /// Campbell diagram and critical speeds (1× LP, 1× HP) over a speed range.
    Campbell(campbell::CampbellArgs),
    /// The reproduction report (markdown) of a campaign directory: the paper's findings
    /// against the recordings.
    Report(report::ReportArgs),
    /// Truncation study (paper Section 5.1): per order, amplitudes, temperatures and the
    /// residual of the governing equations (Eq. 36) at points A–D.
    Truncation(truncation::TruncationArgs),
}

/// A sweep or campaign stopped by Ctrl-C or a termination signal (SIGTERM, SIGHUP: a
/// cluster job at its time limit) after writing what it had computed: the process exits
/// with status 130, not 0, so that scripts and schedulers see the work is not complete.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

/// Exit status of an [`Interrupted`] run (128 + SIGINT, the shell's convention).
pub const INTERRUPTED_EXIT: u8 = 130;

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None => {
            let args = Cli::parse_from(["tmrotor", "sweep"]);
            match args.command {
                Some(Command::Sweep(a)) => sweep::run(&a, &mut std::io::stdout().lock()),
                _ => anyhow::bail!("internal: default sweep arguments did not parse"),
            }
        }
        Some(Command::Sweep(args)) => sweep::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Campaign(args)) => campaign::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Model(cmd)) => model::run(&cmd, &mut std::io::stdout().lock()),
        Some(Command::Modes(args)) => modes::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Campbell(args)) => campbell::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Report(args)) => report::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Truncation(args)) => truncation::run(&args, &mut std::io::stdout().lock()),
    }
}
