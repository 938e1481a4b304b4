//! `tmrotor campbell`: natural frequencies versus speed and critical speeds.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::linear;
use crate::model::Assembly;

/// Arguments of `tmrotor campbell`.
#[derive(Debug, Args)]
pub struct CampbellArgs {
    /// Model file (default: the built-in dual rotor).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Set a value of the model file by its path before it is checked (repeatable; as
    /// `tmrotor sweep --set`, docs/model-reference.md "Setting values by path").
    #[arg(long = "set", value_name = "PATH=VALUE", value_parser = crate::model::set::parse_assignment)]
    pub set: Vec<(String, toml::Value)>,
    /// Reference-speed grid START:END:COUNT in rad/s (COUNT points, ends included).
    #[arg(long, allow_hyphen_values = true)]
    pub speeds: String,
    /// Number of modes followed (lowest first).
    #[arg(long, default_value_t = 10, value_parser = super::positive_count, allow_negative_numbers = true)]
    pub count: usize,
    /// Write the diagram as CSV to this file (speed_rad_s, mode, frequency_rad_s,
    /// frequency_hz, damping_ratio, log_decrement, whirl, forward_share, mac), one row per
    /// speed and followed mode.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Draw the diagram to FIGURE.png / FIGURE.svg (modes in their whirl's colour, 1×
    /// lines, critical speeds circled).
    #[arg(long, value_name = "FIGURE")]
    pub figure: Option<PathBuf>,
    #[command(flatten)]
    pub figure_args: super::FigureArgs,
}

/// The most speeds of a grid: 100 000 (a Campbell diagram at 0.01 rad/s over 1 000 rad/s;
/// minutes of eigenproblems).
pub const MAX_SPEEDS: usize = 100_000;

/// Parses `START:END:COUNT`.
pub fn parse_speeds(s: &str) -> anyhow::Result<Vec<f64>> {
    let parts: Vec<&str> = s.split(':').collect();
    if parts.len() != 3 {
        anyhow::bail!("--speeds must be START:END:COUNT, got {s:?}");
    }
    let start: f64 = parts[0]
        .trim()
        .parse()
        .with_context(|| format!("--speeds start {:?}", parts[0]))?;
    let end: f64 = parts[1]
        .trim()
        .parse()
        .with_context(|| format!("--speeds end {:?}", parts[1]))?;
    let count: usize = parts[2]
        .trim()
        .parse()
        .with_context(|| format!("--speeds count {:?}", parts[2]))?;
    if count > MAX_SPEEDS {
        anyhow::bail!(
            "--speeds count {count}: at most {MAX_SPEEDS} speeds (each is an eigenproblem of the whole rotor)"
        );
    }
    linear::speed_grid(start, end, count).map_err(|e| anyhow::anyhow!("--speeds: {e}"))
}

/// Runs `tmrotor campbell`, writing the critical speeds to `out`.
pub fn run(args: &CampbellArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let speeds = parse_speeds(&args.speeds)?;
    let model = super::model::load_for_linear(args.model.as_ref(), &args.set)?;
    let asm = Assembly::new(&model)?;
    let diagram = linear::campbell(&asm, &speeds, args.count)?;
    if let Some(path) = &args.csv {
        std::fs::write(path, super::linear_outputs::campbell_csv(&diagram))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(stem) = &args.figure {
        let fig = crate::figure::linear::campbell_figure(
            &diagram,
            &format!("Campbell diagram of {}", model.spec.name),
        );
        for f in super::linear_outputs::draw(stem, &fig, &args.figure_args)? {
            writeln!(out, "wrote {}", f.display())?;
        }
    }
    writeln!(
        out,
        "{}: critical speeds in {:.1}–{:.1} rad/s ({} modes, {} speeds)",
        model.spec.name,
        speeds[0],
        speeds[speeds.len() - 1],
        args.count,
        speeds.len()
    )?;
    writeln!(
        out,
        "{:>8}  {:>6}  {:>4}  {:>8}  {:>7}  {:>9}  {:>12}  {:>10}  {:>12}",
        "line",
        "ratio",
        "mode",
        "whirl",
        "fwd",
        "unbalance",
        "ω (rad/s)",
        "ω (rpm)",
        "freq (rad/s)"
    )?;
    for c in &diagram.critical_speeds {
        writeln!(
            out,
            "{:>8}  {:>6.3}  {:>4}  {:>8}  {:>7.3}  {:>9}  {:>12.2}  {:>10.1}  {:>12.2}",
            format!("1×{}", c.rotor_id),
            c.speed_ratio,
            c.mode,
            c.whirl,
            c.forward_share,
            if c.excited_by_unbalance() {
                "excites"
            } else {
                "–"
            },
            c.speed_rad_s,
            c.speed_rad_s * 30.0 / std::f64::consts::PI,
            c.frequency_rad_s
        )?;
    }
    if diagram.critical_speeds.is_empty() {
        writeln!(out, "  (none in this range)")?;
    } else {
        let excited = diagram
            .critical_speeds
            .iter()
            .filter(|c| c.excited_by_unbalance())
            .count();
        writeln!(
            out,
            "{excited} of {} excited by unbalance (a rotating unbalance drives only the part \
             of a mode that whirls with it: forward share ≥ 0.5, ≤ 0.5 for a counter-rotating \
             rotor; modes are followed by shape, numbered in order of frequency at the first \
             speed)",
            diagram.critical_speeds.len()
        )?;
    }
    Ok(())
}
