//! `replay orbit FILE --point N [--node K] [--samples S]`.

use std::io::Write;

use anyhow::{Context, bail};

use crate::derive::{self, rederivers_for, table};
use crate::record::reader::Recording;

/// Memory `replay orbit` may use for its time histories: 2 GB.
const MAX_ORBIT_BYTES: u128 = 2_000_000_000;

/// Writes CSV time histories of one point at `samples` points per period, re-derived
/// from the stored coefficients: `t_s`, `x_<id>_m`, `y_<id>_m` per dynamic node (or only
/// node `node`), `T_<id>_c` per thermal node; bearing loads, clearances and thermal forces
/// through the embedded model when replay can rebuild it (otherwise a note on `err`).
pub fn run(
    rec: &Recording,
    point: u64,
    node: Option<u32>,
    samples: usize,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    let p = rec.point(point).with_context(|| {
        let last = rec
            .points
            .last()
            .map_or("none".into(), |p| p.index.to_string());
        format!(
            "{} has no point {point} ({} points readable, last index {last})",
            rec.file.display(),
            rec.points.len()
        )
    })?;
    let run = &*rec
        .run_of(p.branch)
        .with_context(|| format!("point {point}: its branch {} is not described", p.branch))?;
    if samples == 0 {
        bail!("--samples must be at least 1");
    }
    // Every series is held in memory at `samples` values (8 bytes each) before it is
    // written: refuse what would not fit comfortably, before allocating.
    let series = 2 * run.nodes.len() + run.thermal_nodes.len() + run.bearings.len() + 1;
    let bytes = (samples as u128) * (series as u128) * 8;
    if bytes > MAX_ORBIT_BYTES {
        bail!(
            "--samples {samples}: {series} series of {samples} samples would need about {} MB \
             (at most {} MB); a period is resolved by a few hundred samples",
            bytes / 1_000_000,
            MAX_ORBIT_BYTES / 1_000_000
        );
    }
    let selected: Vec<usize> = match node {
        None => (0..run.nodes.len()).collect(),
        Some(id) => match run.nodes.iter().position(|n| n.id == id) {
            Some(i) => vec![i],
            None => {
                let ids: Vec<String> = run.nodes.iter().map(|n| n.id.to_string()).collect();
                bail!(
                    "no dynamic node {id} in the recording (nodes: {})",
                    ids.join(", ")
                )
            }
        },
    };
    let orbits = derive::orbits(run, &p.coeffs_mech, p.omega_rad_s, samples)?;
    let temps = derive::temperature_histories(run, &p.coeffs_therm, p.omega_rad_s, samples)?;
    let basis = run.basis()?;
    let times = derive::sample_times(basis.period(p.omega_rad_s), samples);

    let hooks = rederivers_for(run);
    let bearings = match (&hooks.model, run.bearings.is_empty()) {
        (_, true) => None,
        (Some(model), false) => Some(model.bearings(p, samples)?),
        (None, false) => {
            writeln!(
                err,
                "note: bearing loads, clearances and thermal forces cannot be re-derived: {}",
                hooks.unavailable_reason
            )?;
            None
        }
    };

    let mut header = vec!["t_s".to_string()];
    for &i in &selected {
        let id = run.nodes[i].id;
        header.push(format!("{}_x_m", table::node_key(id)));
        header.push(format!("{}_y_m", table::node_key(id)));
    }
    header.extend(
        run.thermal_nodes
            .iter()
            .map(|n| format!("{}_c", table::thermal_node_key(n.id))),
    );
    if let Some(b) = &bearings {
        for (key, _) in table::bearing_keys(&run.bearings).iter().zip(&b.loads) {
            header.push(format!("{key}_load_n"));
        }
    }
    writeln!(out, "{}", header.join(","))?;
    for (k, t) in times.iter().enumerate() {
        let mut row = vec![format!("{t:e}")];
        for &i in &selected {
            row.push(format!("{:e}", orbits[i].x_m[k]));
            row.push(format!("{:e}", orbits[i].y_m[k]));
        }
        row.extend(temps.iter().map(|h| table::number(h[k])));
        if let Some(b) = &bearings {
            row.extend(b.loads.iter().map(|l| {
                l.radial_n
                    .get(k)
                    .map_or(String::new(), |v| format!("{v:e}"))
            }));
        }
        writeln!(out, "{}", row.join(","))?;
    }
    Ok(())
}
