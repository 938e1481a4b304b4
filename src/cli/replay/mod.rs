//! The `replay` command line: works from a recording alone.
//!
//! One file per subcommand, each with `run(args, out)` writing to any `io::Write`, so
//! tests call them in-process; `src/bin/replay.rs` only parses and maps errors to exit
//! codes ([`main`]).
//!
//! | subcommand | output |
//! |---|---|
//! | `info FILE` | runs, topics, counts, ω range, bifurcations, settings, completeness |
//! | `branch FILE --csv` | one row per point: ω, stability, bifurcation, residuals, amplitude per node |
//! | `export FILE --out DIR` | every per-point quantity as CSV tables, the model and the settings |
//! | `orbit FILE --point N [--node K] [--samples S]` | time histories re-derived from the coefficients |
//! | `stability FILE [--sip-intervals N]` | Floquet multipliers recomputed (optionally with a finer product) and compared with the stored ones |
//! | `recover IN OUT` | a clean recording of every intact point of a damaged or cut file |
//! | `plot FILE [--out DIR] [--format png,svg] [--title] [--node ID] [--thermal-node ID] [--point N]` | figures as PNG and SVG: amplitude–frequency curves, RC variations, temperatures, multipliers, orbits, bearing loads |
//!
//! Model-dependent re-derivations go through [`crate::derive::rederivers_for`]; where it
//! has nothing for the recording's model, replay says so instead of guessing.

pub mod branch;
pub mod export;
pub mod info;
pub mod orbit;
pub mod recover;
pub mod stability;
pub mod verify;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub use super::NotAvailable;
use crate::record::reader::{ReadOptions, Recording, read_recording_with};

/// Inspect, export and re-derive tmrotor recordings (MCAP) without rerunning anything.
#[derive(Debug, Parser)]
#[command(name = "replay", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Runs, topics, message counts, ω range, bifurcations and settings of a recording.
    Info { file: PathBuf },
    /// The branch as a table: one row per point.
    Branch {
        file: PathBuf,
        /// Comma-separated values with a header row (default: aligned text).
        #[arg(long)]
        csv: bool,
    },
    /// Every per-point quantity as CSV files (branch, temperatures, clearances, bearing
    /// loads, thermal forces, multipliers, slow exponents, bifurcations, nodes), with the
    /// embedded model and settings.
    Export {
        file: PathBuf,
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
    },
    /// Time histories of one point re-derived from its harmonic coefficients, as CSV.
    Orbit {
        file: PathBuf,
        /// Point index (as in `replay branch`).
        #[arg(long)]
        point: u64,
        /// Dynamic node id (default: all nodes).
        #[arg(long)]
        node: Option<u32>,
        /// Samples per period.
        #[arg(long, default_value_t = 256)]
        samples: usize,
    },
    /// Recompute the Floquet multipliers and compare them with the stored ones.
    Stability {
        file: PathBuf,
        /// SIP intervals per period for the recomputation instead of the recorded ones
        /// (exp-sip: even; from 4096 on the product is not refined further): audits the
        /// stored stability with a finer product. Costs about 1.3 s per point at 8192.
        #[arg(long, value_name = "N")]
        sip_intervals: Option<usize>,
    },
    /// Re-solve the run's located bifurcations at higher truncation orders (a window around
    /// each group, from the recorded point before it) and say whether each one converged
    /// (its ω and kind held), moved or vanished.
    Verify {
        file: PathBuf,
        /// Truncation orders (comma-separated; default: the recorded order + 1 and + 2).
        #[arg(long, value_delimiter = ',', value_name = "K")]
        orders: Vec<u32>,
        /// Half-width of the ω window around each group of bifurcations, rad/s.
        #[arg(
            long,
            default_value_t = 1.0,
            value_name = "RAD_S",
            allow_negative_numbers = true
        )]
        window: f64,
        /// A bifurcation that moved by at most this is converged, rad/s.
        #[arg(
            long,
            default_value_t = 0.05,
            value_name = "RAD_S",
            allow_negative_numbers = true
        )]
        tolerance: f64,
    },
    /// Figures (PNG and SVG): amplitude–frequency curves, RC variations, temperatures
    /// grouped by bearing, one thermal node with stability, Floquet multipliers against the
    /// unit circle, orbits at the resonant peaks, bearing loads.
    Plot {
        file: PathBuf,
        /// Output directory (created if missing).
        #[arg(long, default_value = ".")]
        out: PathBuf,
        #[command(flatten)]
        figures: super::FigureArgs,
        /// Dynamic node whose resonant peaks give the orbits and whose highest point is the
        /// default `--point` (default: node 8 when recorded, else the first).
        #[arg(long, value_name = "ID")]
        node: Option<u32>,
        /// Thermal node of `temperature_node<ID>` (default: 58 for the built-in dual rotor,
        /// the paper's Fig. 15; else the hottest node at the last point).
        #[arg(long, value_name = "ID")]
        thermal_node: Option<u32>,
        /// Point (index as in `replay branch`) of the multiplier and bearing-load figures
        /// (default: the highest amplitude of `--node`).
        #[arg(long, value_name = "N")]
        point: Option<u64>,
    },
    /// Transient runs (`tmrotor transient`) over a sweep's branch: a figure of one node's
    /// RMS amplitude against ω (the branch stable and unstable, each run on top), the speed
    /// where each run changes fastest (its jump), and the runs as CSV.
    Transient {
        /// Transient recordings.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// A sweep recording whose branch is drawn beneath.
        #[arg(long, value_name = "SWEEP")]
        branch: Option<PathBuf>,
        /// Dynamic node (default: node 8 when recorded, else the first).
        #[arg(long, value_name = "ID")]
        node: Option<u32>,
        /// Output directory (created if missing).
        #[arg(long, default_value = ".")]
        out: PathBuf,
        #[command(flatten)]
        figures: super::FigureArgs,
    },
    /// Write a clean recording of every intact point of a damaged or cut one (OUT must not
    /// exist); what was lost is logged in it and printed.
    Recover { file: PathBuf, out: PathBuf },
    /// Write a synthetic recording (closed-form 2-DoF rotor) for trying the tools.
    #[command(hide = true)]
    Synthetic {
        file: PathBuf,
        /// Without thermal node and bearing.
        #[arg(long)]
        mechanical: bool,
        /// Points on each side of the resonance.
        #[arg(long, default_value_t = 20)]
        points: usize,
        /// Stop without finishing the file, as a killed process would.
        #[arg(long)]
        unfinished: bool,
    },
}

/// Reads a recording (without the stored orbits, which every subcommand re-derives from
/// the coefficients: memory stays well below the file's size) and reports on stderr when
/// it is incomplete.
pub fn open(file: &PathBuf, err: &mut dyn Write) -> anyhow::Result<Recording> {
    open_with(file, ReadOptions { orbits: false }, err)
}

/// As [`open`], keeping what `options` says.
pub fn open_with(
    file: &PathBuf,
    options: ReadOptions,
    err: &mut dyn Write,
) -> anyhow::Result<Recording> {
    let rec = read_recording_with(file, options)?;
    if !rec.complete {
        writeln!(
            err,
            "note: {} is incomplete ({} points readable): {}",
            file.display(),
            rec.points.len(),
            rec.notes.join("; ")
        )?;
    }
    Ok(rec)
}

/// The operating map in `file` (`tmrotor campaign map` writes them), when reading it as a
/// recording failed with `error` because it has the map's topics instead of a run;
/// otherwise `error` itself.
fn operating_map(
    file: &Path,
    error: anyhow::Error,
) -> anyhow::Result<crate::campaign::map::OperatingMap> {
    let is_map = matches!(
        error.downcast_ref::<crate::record::ReadError>(),
        Some(crate::record::ReadError::Foreign { reason, .. }) if reason.contains("/map/info")
    );
    if !is_map {
        return Err(error);
    }
    Ok(crate::campaign::map::read_map_mcap(file)?)
}

/// Runs a parsed command line, writing results to `out` and notes to `err`.
pub fn run(cli: Cli, out: &mut dyn Write, err: &mut (dyn Write + Send)) -> anyhow::Result<()> {
    match cli.command {
        Command::Info { file } => match open(&file, err) {
            Ok(rec) => info::run(&rec, out),
            Err(e) => info::map(&file, &operating_map(&file, e)?, out),
        },
        Command::Branch { file, csv } => branch::run(&open(&file, err)?, csv, out),
        Command::Export { file, out: dir } => match open(&file, err) {
            Ok(rec) => export::run(&rec, &dir, out),
            Err(e) => export::map(&operating_map(&file, e)?, &dir, out),
        },
        Command::Orbit {
            file,
            point,
            node,
            samples,
        } => orbit::run(&open(&file, err)?, point, node, samples, out, err),
        Command::Stability {
            file,
            sip_intervals,
        } => stability::run(&open(&file, err)?, None, sip_intervals, out),
        Command::Verify {
            file,
            orders,
            window,
            tolerance,
        } => verify::run(&open(&file, err)?, &orders, window, tolerance, out, err),
        Command::Transient {
            files,
            branch,
            node,
            out: dir,
            figures,
        } => {
            let runs = files
                .iter()
                .map(|f| Ok((f.clone(), open(f, err)?)))
                .collect::<anyhow::Result<Vec<_>>>()?;
            let branch = branch.as_ref().map(|b| open(b, err)).transpose()?;
            crate::figure::transient::run(
                &runs,
                branch.as_ref(),
                node,
                &dir,
                &figures.output()?,
                out,
            )
        }
        Command::Recover { file, out: target } => {
            // Everything, stored orbits included: the recovered file keeps the original form.
            let rec = open_with(&file, ReadOptions::default(), err)?;
            recover::run(&rec, &target, out)
        }
        Command::Plot {
            file,
            out: dir,
            figures,
            node,
            thermal_node,
            point,
        } => {
            let options = crate::figure::recording::PlotOptions {
                output: figures.output()?,
                node,
                thermal_node,
                point,
            };
            crate::figure::recording::run(&open(&file, err)?, &dir, &options, out, err)
        }
        Command::Synthetic {
            file,
            mechanical,
            points,
            unfinished,
        } => {
            let options = crate::record::synthetic::SyntheticOptions {
                points_per_side: points,
                thermal: !mechanical,
                ..Default::default()
            };
            let n = crate::record::synthetic::write_mcap(&file, &options, !unfinished)?;
            writeln!(out, "wrote {} ({n} points)", file.display())?;
            Ok(())
        }
    }
}

/// Entry point of the binary: parse, run, and exit with the status [`super::exit_code`]
/// maps the outcome to (the same mapping as `tmrotor`'s).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let (mut out, mut err) = (std::io::stdout().lock(), std::io::stderr());
    super::exit_code("replay", run(cli, &mut out, &mut err))
}
