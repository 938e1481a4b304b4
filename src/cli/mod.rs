//! The `tmrotor` command line: one file per subcommand, each with `run(args)`.
//! `src/main.rs` only parses and maps errors to exit codes.

use clap::{Parser, Subcommand};

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
    Sweep,
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None | Some(Command::Sweep) => anyhow::bail!("sweep: not available yet"),
    }
}
