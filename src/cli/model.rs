//! `tmrotor model check FILE`, `tmrotor model show` and `tmrotor model reference`.

use std::io::Write;
use std::path::PathBuf;

use clap::Subcommand;

use crate::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use crate::model::{BUILTIN_TOML, Model};
use crate::thermal::{ThermalNetwork, ThermalSpec};

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
    /// Print the thermal network of a model file (built-in when absent) as a `[thermal]`
    /// table written node by node, with a table of its nodes: a generated network
    /// (`generate = true`) spelled out, a starting point for editing it by hand.
    Thermal {
        /// The model file (TOML); the built-in dual rotor when absent.
        file: Option<PathBuf>,
        /// Set a value by its path first, as `sweep --set` does (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE", value_parser = crate::model::set::parse_assignment)]
        set: Vec<(String, toml::Value)>,
    },
}

/// The `[thermal]` table of `spec` as TOML, preceded by a comment listing every node.
fn thermal_table(model: &Model, spec: &ThermalSpec) -> anyhow::Result<String> {
    #[derive(serde::Serialize)]
    struct Doc<'a> {
        thermal: &'a ThermalSpec,
    }
    let names = ThermalNetwork::new(spec)?.names().to_vec();
    let mut out = format!(
        "# The thermal network of {} ({} nodes), written node by node\n\
         # (`tmrotor model thermal`). Nodes:\n",
        model.source, spec.n_nodes
    );
    for (k, name) in names.iter().enumerate() {
        out.push_str(&format!("# {:>4}  {name}\n", k + 1));
    }
    out.push('\n');
    out.push_str(&toml::to_string(&Doc { thermal: spec })?);
    Ok(out)
}

/// Loads the model named by an optional `--model` flag (built-in when absent).
pub fn load(file: Option<&PathBuf>) -> anyhow::Result<Model> {
    load_with(file, &[])
}

/// [`load`] with `--set` values applied (the built-in model when `file` is `None`).
pub fn load_with(file: Option<&PathBuf>, set: &[(String, toml::Value)]) -> anyhow::Result<Model> {
    let set: crate::model::ModelSet = set.iter().cloned().collect();
    Ok(Model::load(file.map(|f| f.as_path()), &set)?)
}

/// [`load_with`] for the linear analyses (`modes`, `campbell`, `unbalance`), which say on
/// stderr how the model's `[[nonlinear]]` elements enter them (their tangent at the
/// undeflected position, `Assembly`'s `element_springs`).
pub fn load_for_linear(
    file: Option<&PathBuf>,
    set: &[(String, toml::Value)],
) -> anyhow::Result<Model> {
    let model = load_with(file, set)?;
    let n = model.spec.nonlinear.len();
    if n > 0 {
        eprintln!(
            "note: {}: {n} [[nonlinear]] element{} linearised about the undeflected position \
             (a polynomial support's linear term; a rub or a stop only where in contact there); \
             their nonlinear terms are the sweep's.",
            model.source,
            if n == 1 { "" } else { "s" },
        );
    }
    Ok(model)
}

/// Runs a model command, writing to `out`.
pub fn run(cmd: &ModelCommand, out: &mut dyn Write) -> anyhow::Result<()> {
    match cmd {
        ModelCommand::Show => out.write_all(BUILTIN_TOML.as_bytes())?,
        ModelCommand::Reference => out.write_all(crate::model::reference::markdown().as_bytes())?,
        ModelCommand::Thermal { file, set } => {
            let set: crate::model::ModelSet = set.iter().cloned().collect();
            let model = Model::load(file.as_deref(), &set)?;
            let spec = ThermalSpec::of_model(&model)?.ok_or_else(|| {
                anyhow::anyhow!("{}: the model has no [thermal] table", model.source)
            })?;
            out.write_all(thermal_table(&model, &spec)?.as_bytes())?;
        }
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
            let thermal = ThermalSpec::of_model(&model)?;
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
                let generated = model
                    .thermal()
                    .is_some_and(|t| t.contains_key(crate::thermal::generate::GENERATE_KEY));
                writeln!(
                    out,
                    "  thermal:  {} nodes{}, {} bearings; flow {} L/min, cooling {} °C, ambient {} °C",
                    t.n_nodes,
                    if generated {
                        " (generated from the geometry; `tmrotor model thermal` lists them)"
                    } else {
                        ""
                    },
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
