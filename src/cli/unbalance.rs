//! `tmrotor unbalance`: the unbalance response of the linearised rotor (Bode and polar).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::linear;
use crate::model::Assembly;

/// Arguments of `tmrotor unbalance`.
#[derive(Debug, Args)]
pub struct UnbalanceArgs {
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
    /// Node ids to draw and print (comma-separated) [default: the nodes of the unbalanced
    /// disks]; the CSV holds every node.
    #[arg(long, value_delimiter = ',')]
    pub nodes: Vec<u32>,
    /// Write the response of every node as CSV to this file (speed_rad_s, rotor,
    /// frequency_rad_s, node, x and y amplitude and phase, semi-axes, whirl).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Draw Bode (semi-major axis, phase) and polar plots to FIGURE.png / FIGURE.svg.
    #[arg(long, value_name = "FIGURE")]
    pub figure: Option<PathBuf>,
    #[command(flatten)]
    pub figure_args: super::FigureArgs,
}

/// Runs `tmrotor unbalance`, writing the peaks of the drawn nodes to `out`.
pub fn run(args: &UnbalanceArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let speeds = super::campbell::parse_speeds(&args.speeds)?;
    let model = super::model::load_for_linear(args.model.as_ref(), &args.set)?;
    let asm = Assembly::new(&model)?;
    let resp = linear::unbalance_response(&asm, &speeds)
        .with_context(|| format!("unbalance response of {}", model.spec.name))?;
    let mut ids = args.nodes.clone();
    if ids.is_empty() {
        for u in &asm.unbalances {
            if !ids.contains(&u.node) {
                ids.push(u.node);
            }
        }
    }
    let mut nodes = Vec::new();
    for id in &ids {
        let i = model
            .node_index(*id)
            .with_context(|| format!("--nodes: node {id} is not a node of {}", model.spec.name))?;
        nodes.push((i, *id));
    }
    if let Some(path) = &args.csv {
        std::fs::write(
            path,
            super::linear_outputs::unbalance_csv(&resp, model.node_ids()),
        )
        .with_context(|| format!("writing {}", path.display()))?;
    }
    writeln!(
        out,
        "{}: unbalance response over {:.1}–{:.1} rad/s ({} speeds), linearised bearings",
        model.spec.name,
        speeds[0],
        speeds[speeds.len() - 1],
        speeds.len()
    )?;
    writeln!(
        out,
        "{:>10}  {:>6}  {:>12}  {:>14}  {:>8}",
        "unbalance", "node", "peak ω", "major axis", "whirl"
    )?;
    let mut rotors: Vec<&str> = Vec::new();
    for r in &resp {
        if !rotors.contains(&r.rotor_id.as_str()) {
            rotors.push(&r.rotor_id);
        }
    }
    for rotor in rotors {
        for &(i, id) in &nodes {
            let peak = resp
                .iter()
                .filter(|r| r.rotor_id == rotor)
                .max_by(|a, b| a.node(i).major_axis().total_cmp(&b.node(i).major_axis()));
            if let Some(p) = peak {
                let o = p.node(i);
                writeln!(
                    out,
                    "{:>10}  {:>6}  {:>12.2}  {:>11.4} µm  {:>8}",
                    rotor,
                    id,
                    p.speed_rad_s,
                    o.major_axis() * 1e6,
                    if o.forward() { "forward" } else { "backward" }
                )?;
            }
        }
    }
    if let Some(stem) = &args.figure {
        let fig = crate::figure::linear::unbalance_figure(
            &resp,
            &nodes,
            &format!("Unbalance response of {}", model.spec.name),
        );
        for f in super::linear_outputs::draw(stem, &fig, &args.figure_args)? {
            writeln!(out, "wrote {}", f.display())?;
        }
    }
    Ok(())
}
