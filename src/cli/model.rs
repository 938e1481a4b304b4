//! `tmrotor model check FILE`, `tmrotor model show` and `tmrotor model reference`.

use std::io::Write;
use std::path::PathBuf;

use clap::Subcommand;

use crate::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use crate::model::{BUILTIN_TOML, Model};
use crate::thermal::ThermalSpec;

/// Model-file commands.
#[derive(Debug, Subcommand)]
pub enum ModelCommand {
    /// Validate a model file (and assemble it); report the first problem with its field
    /// path, or a summary.
    Check {
        /// The model file (TOML).
        file: PathBuf,
        /// Set a value by its path before checking, as `sweep --set` does (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE", value_parser = crate::model::set::parse_assignment)]
        set: Vec<(String, toml::Value)>,
    },
    /// Print the built-in dual-rotor model file (a documented starting point to copy; every
    /// key is described in docs/model-reference.md, or `tmrotor model reference`).
    Show,
    /// Print the model-file reference (markdown): every key with unit, default, whether it
    /// is required, the range checked and its meaning.
    Reference,
}

/// Loads the model named by an optional `--model` flag (built-in when absent).
pub fn load(file: Option<&PathBuf>) -> anyhow::Result<Model> {
    Ok(match file {
        Some(f) => Model::from_file(f)?,
        None => Model::builtin()?,
    })
}

/// Runs a model command, writing to `out`.
pub fn run(cmd: &ModelCommand, out: &mut dyn Write) -> anyhow::Result<()> {
    match cmd {
        ModelCommand::Show => out.write_all(BUILTIN_TOML.as_bytes())?,
        ModelCommand::Reference => out.write_all(crate::model::reference::markdown().as_bytes())?,
        ModelCommand::Check { file, set } => {
            let set: crate::model::ModelSet = set.iter().cloned().collect();
            let model = Model::load(Some(file), &set)?;
            // what a sweep builds, so every check a sweep makes: the assembly, the
            // `[thermal]` table's fields and ranges, its network, and the checks between
            // the mechanical and thermal tables (one validation path)
            let coupled = CoupledRotor::new(
                &model,
                &StudyOverrides::default(),
                CouplingOptions::default(),
            )?;
            let asm = coupled.assembly();
            // the table's study values for the summary (already validated above)
            let thermal = match model.thermal() {
                Some(table) => Some(ThermalSpec::from_table(table, &model.source)?),
                None => None,
            };
            let spec = &model.spec;
            let rotors: Vec<String> = spec
                .rotors
                .iter()
                .enumerate()
                .map(|(r, rot)| {
                    format!(
                        "{} ({}, {} nodes)",
                        rot.id,
                        model.speed_ratio(r),
                        rot.nodes.len()
                    )
                })
                .collect();
            writeln!(out, "{}: ok", model.source)?;
            writeln!(out, "  name:     {}", spec.name)?;
            writeln!(out, "  rotors:   {}", rotors.join(", "))?;
            writeln!(
                out,
                "  nodes:    {} ({} DoF); shafts {}, disks {}, supports {}, bearings {}",
                model.n_nodes(),
                model.n_dof(),
                spec.shafts.len(),
                spec.disks.len(),
                spec.supports.len(),
                spec.bearings.len()
            )?;
            if !spec.nonlinear.is_empty() {
                let list: Vec<String> = spec
                    .nonlinear
                    .iter()
                    .map(|e| format!("{} ({}, node {})", e.id, e.kind.label(), e.node))
                    .collect();
                writeln!(out, "  nonlinear: {}", list.join(", "))?;
            }
            let (a0, a1) = model.rayleigh();
            writeln!(out, "  damping:  a0 = {a0:.4} 1/s, a1 = {a1:.4e} s")?;
            writeln!(
                out,
                "  gravity:  {}",
                if spec.gravity.enabled { "on" } else { "off" }
            )?;
            for b in &asm.bearings {
                writeln!(
                    out,
                    "  bearing {}: load {:.1} N, linearised kxx = {:.4e} N/m, kyy = {:.4e} N/m",
                    b.id,
                    b.load_n[0].hypot(b.load_n[1]),
                    b.stiffness_n_m[0][0],
                    b.stiffness_n_m[1][1]
                )?;
            }
            if let Some(t) = thermal {
                writeln!(
                    out,
                    "  thermal:  {} nodes, {} bearings; flow {} L/min, cooling {} °C, ambient {} °C",
                    t.n_nodes,
                    t.bearings.len(),
                    t.flow_l_min,
                    t.cooling_temp_c,
                    t.ambient_temp_c
                )?;
            }
        }
    }
    Ok(())
}
