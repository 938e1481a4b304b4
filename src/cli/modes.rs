//! `tmrotor modes`: damped natural frequencies of the linearised rotor at one speed.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::linear;
use crate::model::Assembly;

/// Arguments of `tmrotor modes`.
#[derive(Debug, Args)]
pub struct ModesArgs {
    /// Model file (default: the built-in dual rotor).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Set a value of the model file by its path before it is checked (repeatable; as
    /// `tmrotor sweep --set`, docs/model-reference.md "Setting values by path").
    #[arg(long = "set", value_name = "PATH=VALUE", value_parser = crate::model::set::parse_assignment)]
    pub set: Vec<(String, toml::Value)>,
    /// Reference (LP) speed ω in rad/s; each rotor spins at its speed ratio times ω.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub speed: f64,
    /// Number of modes (lowest first).
    #[arg(long, default_value_t = 10, value_parser = super::positive_count, allow_negative_numbers = true)]
    pub count: usize,
    /// Write CSV (mode, frequency_rad_s, frequency_hz, damping_ratio, whirl,
    /// undamped_rad_s, log_decrement, forward_share) instead of a table.
    #[arg(long)]
    pub csv: bool,
    /// Write the mode shapes as CSV to this file (per mode and node: complex x, y, θx, θy,
    /// the orbit's semi-axes and whirl).
    #[arg(long, value_name = "FILE")]
    pub shapes: Option<PathBuf>,
    /// Draw the mode shapes along the shaft to FIGURE.png / FIGURE.svg.
    #[arg(long, value_name = "FIGURE")]
    pub figure: Option<PathBuf>,
    #[command(flatten)]
    pub figure_args: super::FigureArgs,
}

/// Runs `tmrotor modes`, writing to `out`.
pub fn run(args: &ModesArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if !args.speed.is_finite() || args.speed < 0.0 {
        anyhow::bail!(
            "--speed must be a non-negative number of rad/s, got {}",
            args.speed
        );
    }
    let model = super::model::load_for_linear(args.model.as_ref(), &args.set)?;
    let asm = Assembly::new(&model)?;
    let modes = linear::modes(&asm, args.speed, args.count)?;
    if args.csv {
        writeln!(
            out,
            "mode,frequency_rad_s,frequency_hz,damping_ratio,whirl,undamped_rad_s,log_decrement,forward_share"
        )?;
        for (i, m) in modes.iter().enumerate() {
            writeln!(
                out,
                "{},{},{},{},{},{},{},{}",
                i + 1,
                m.frequency_rad_s,
                m.frequency_hz(),
                m.damping_ratio,
                m.whirl,
                m.undamped_rad_s,
                m.log_decrement(),
                linear::forward_share(&m.shape)
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
            "{:>4}  {:>14}  {:>12}  {:>9}  {:>9}  {:>8}",
            "mode", "freq (rad/s)", "freq (Hz)", "ζ", "log dec", "whirl"
        )?;
        for (i, m) in modes.iter().enumerate() {
            writeln!(
                out,
                "{:>4}  {:>14.3}  {:>12.4}  {:>9.5}  {:>9.5}  {:>8}",
                i + 1,
                m.frequency_rad_s,
                m.frequency_hz(),
                m.damping_ratio,
                m.log_decrement(),
                m.whirl
            )?;
        }
    }
    let axial = model.axial_positions();
    if let Some(path) = &args.shapes {
        std::fs::write(
            path,
            super::linear_outputs::shapes_csv(&modes, model.node_ids(), &axial),
        )
        .with_context(|| format!("writing {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(stem) = &args.figure {
        let rotors: Vec<(String, Vec<usize>)> = model
            .spec
            .rotors
            .iter()
            .map(|r| {
                let idx = r
                    .nodes
                    .iter()
                    .filter_map(|&n| model.node_index(n))
                    .collect();
                (r.id.clone(), idx)
            })
            .collect();
        let fig = crate::figure::linear::shapes_figure(
            &modes,
            &axial,
            &rotors,
            &format!(
                "Mode shapes of {} at ω = {} rad/s",
                model.spec.name, args.speed
            ),
        );
        for f in super::linear_outputs::draw(stem, &fig, &args.figure_args)? {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
