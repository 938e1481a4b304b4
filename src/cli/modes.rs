//! `tmrotor modes`: damped natural frequencies of the linearised rotor at one speed.

use std::io::Write;
use std::path::PathBuf;

use clap::Args;

use crate::linear;
use crate::model::Assembly;

/// Arguments of `tmrotor modes`.
#[derive(Debug, Args)]
pub struct ModesArgs {
    /// Model file (default: the built-in dual rotor).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Reference (LP) speed ω in rad/s; each rotor spins at its speed ratio times ω.
    #[arg(long, default_value_t = 0.0)]
    pub speed: f64,
    /// Number of modes (lowest first).
    #[arg(long, default_value_t = 10)]
    pub count: usize,
    /// Write CSV (mode,frequency_rad_s,frequency_hz,damping_ratio,whirl,undamped_rad_s)
    /// instead of a table.
    #[arg(long)]
    pub csv: bool,
}

/// Runs `tmrotor modes`, writing to `out`.
pub fn run(args: &ModesArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if !args.speed.is_finite() || args.speed < 0.0 {
        anyhow::bail!(
            "--speed must be a non-negative number of rad/s, got {}",
            args.speed
        );
    }
    let model = super::model::load(args.model.as_ref())?;
    let asm = Assembly::new(&model)?;
    let modes = linear::modes(&asm, args.speed, args.count)?;
    if args.csv {
        writeln!(
            out,
            "mode,frequency_rad_s,frequency_hz,damping_ratio,whirl,undamped_rad_s"
        )?;
        for (i, m) in modes.iter().enumerate() {
            writeln!(
                out,
                "{},{:.6},{:.6},{:.6},{},{:.6}",
                i + 1,
                m.frequency_rad_s,
                m.frequency_hz(),
                m.damping_ratio,
                m.whirl,
                m.undamped_rad_s
            )?;
        }
    } else {
        writeln!(
            out,
            "{} at ω = {} rad/s ({} DoF)",
            model.spec.name, args.speed, asm.n_dof
        )?;
        writeln!(
            out,
            "{:>4}  {:>14}  {:>12}  {:>9}  {:>8}",
            "mode", "freq (rad/s)", "freq (Hz)", "ζ", "whirl"
        )?;
        for (i, m) in modes.iter().enumerate() {
            writeln!(
                out,
                "{:>4}  {:>14.3}  {:>12.4}  {:>9.5}  {:>8}",
                i + 1,
                m.frequency_rad_s,
                m.frequency_hz(),
                m.damping_ratio,
                m.whirl
            )?;
        }
    }
    Ok(())
}
