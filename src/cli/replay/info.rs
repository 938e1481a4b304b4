//! `replay info FILE`.

use std::io::Write;

use crate::derive::{PERIOD_DOUBLED_SHARE, period_doubled_stretches, point_half_order_share};
use crate::record::reader::Recording;

fn stable_label(s: Option<bool>) -> &'static str {
    match s {
        Some(true) => "stable",
        Some(false) => "unstable",
        None => "unknown",
    }
}

/// Prints a summary of the recording.
pub fn run(rec: &Recording, out: &mut dyn Write) -> anyhow::Result<()> {
    header(rec, out)?;
    if let Some(t) = &rec.transient {
        transient_info(t, out)?;
    }
    writeln!(out, "points:      {}", rec.points.len())?;
    if let Some((lo, hi)) = rec.omega_range() {
        writeln!(out, "ω range:     {lo:.4} … {hi:.4} rad/s")?;
    }
    branches(rec, out)?;
    stability_and_bifurcations(rec, out)?;
    warnings_and_contents(rec, out)
}

/// The file, its state, the run's model, basis and sizes, and the viewer indices.
fn header(rec: &Recording, out: &mut dyn Write) -> anyhow::Result<()> {
    let r = &rec.run;
    writeln!(out, "file:        {}", rec.file.display())?;
    writeln!(
        out,
        "state:       {}",
        if rec.complete {
            "complete".to_string()
        } else {
            format!("INCOMPLETE ({})", rec.notes.join("; "))
        }
    )?;
    writeln!(
        out,
        "status:      {}",
        rec.status
            .as_ref()
            .map_or("none (the run did not finish writing)".into(), |s| s
                .label())
    )?;
    writeln!(out, "written by:  {} {}", r.tool_name, r.tool_version)?;
    writeln!(
        out,
        "model:       {} ({} bytes embedded)",
        r.model_name,
        r.model_text.len()
    )?;
    let harmonics: Vec<String> = r
        .harmonics
        .iter()
        .map(|h| {
            if h.den == 1 {
                format!("{}ω", h.num)
            } else {
                format!("{}/{}ω", h.num, h.den)
            }
        })
        .collect();
    writeln!(out, "runs:        1")?;
    if !rec.points.is_empty() && !rec.topics.iter().any(|t| t.topic == "/orbits") {
        writeln!(
            out,
            "form:        lean (no /orbits or /scene; replay re-derives orbits from /harmonics)"
        )?;
    }
    writeln!(
        out,
        "basis:       {} harmonics: {}; λ = {}/{}",
        r.harmonics.len(),
        harmonics.join(", "),
        r.lambda.num,
        r.lambda.den
    )?;
    writeln!(
        out,
        "DoFs:        {} mechanical, {} thermal; {} dynamic nodes, {} thermal nodes, {} bearings",
        r.n_mech,
        r.n_therm,
        r.nodes.len(),
        r.thermal_nodes.len(),
        r.bearings.len()
    )?;
    // The index a viewer's message path uses (`/summary.amplitude_rms_m[7]`).
    let indexed = |names: Vec<&str>| -> String {
        let items: Vec<String> = names
            .iter()
            .enumerate()
            .map(|(i, n)| format!("[{i}] {n}"))
            .collect();
        items.join(", ")
    };
    writeln!(
        out,
        "node index:  {}",
        indexed(r.nodes.iter().map(|n| n.name.as_str()).collect())
    )?;
    if !r.bearings.is_empty() {
        writeln!(
            out,
            "bearing index: {}",
            indexed(r.bearings.iter().map(|b| b.name.as_str()).collect())
        )?;
    }
    Ok(())
}

/// The branches of a recording with switched branches, each with its origin and points.
fn branches(rec: &Recording, out: &mut dyn Write) -> anyhow::Result<()> {
    if !rec.branches.is_empty() {
        writeln!(out, "branches:    {}", rec.branches.len() + 1)?;
        for k in rec.branch_numbers() {
            let on: Vec<&crate::record::PointRecord> =
                rec.points.iter().filter(|p| p.branch == k).collect();
            let range = match (on.first(), on.last()) {
                (Some(a), Some(b)) => format!(
                    "points {}–{}, ω {:.4} → {:.4} rad/s",
                    a.index, b.index, a.omega_rad_s, b.omega_rad_s
                ),
                _ => "no points".to_string(),
            };
            let what = match rec.branches.iter().find(|b| b.branch == k) {
                None => "the run's".to_string(),
                Some(b) => format!(
                    "{} from bifurcation #{} of branch {} at ω = {:.4} rad/s, {} harmonics",
                    b.kind,
                    u64::from(b.origin_bifurcation) + 1,
                    b.parent,
                    b.origin_omega_rad_s,
                    b.harmonics.len()
                ),
            };
            writeln!(out, "  branch {k}: {what}; {} {range}", on.len())?;
        }
    }
    Ok(())
}

/// The stability counts, the located bifurcations (with their modulation and truncation
/// checks) and the unlocated changes of stability.
fn stability_and_bifurcations(rec: &Recording, out: &mut dyn Write) -> anyhow::Result<()> {
    let unstable = rec
        .points
        .iter()
        .filter(|p| p.stable == Some(false))
        .count();
    let unknown = rec.points.iter().filter(|p| p.stable.is_none()).count();
    writeln!(
        out,
        "stability:   {} stable, {unstable} unstable, {unknown} not assessed",
        rec.points.len() - unstable - unknown
    )?;
    writeln!(out, "bifurcations: {}", rec.bifurcations.len())?;
    for b in &rec.bifurcations {
        writeln!(
            out,
            "  #{} {} at ω = {:.4} rad/s (after point {}){}",
            u64::from(b.number) + 1,
            b.kind.label(),
            b.omega_rad_s,
            b.after_point,
            if b.confirmed {
                ""
            } else {
                ", not confirmed by the multipliers"
            }
        )?;
        if let Some(m) = b.modulation {
            writeln!(
                out,
                "     {}angle {:.3e} rad: a modulation of {:.4} s ({:.0} revolutions){}",
                if m.thermo_mechanical() {
                    "thermo-mechanical, "
                } else {
                    ""
                },
                m.angle_rad,
                m.period_s,
                m.period_s * b.omega_rad_s / std::f64::consts::TAU,
                m.thermal_share
                    .map(|s| format!(", thermal share {s:.2}"))
                    .unwrap_or_default()
            )?;
        }
        if let Some(c) = rec.truncation_of(b) {
            writeln!(out, "     at higher truncation orders: {}", order_cells(c))?;
        }
    }
    let unlocated: Vec<_> = rec.truncation.iter().filter(|c| c.kind.is_none()).collect();
    if !unlocated.is_empty() {
        writeln!(out, "unlocated changes of stability: {}", unlocated.len())?;
        for c in unlocated {
            writeln!(
                out,
                "  between points {} and {} (ω ≈ {:.4} rad/s), at higher truncation orders: {}",
                c.after_point,
                c.after_point + 1,
                c.omega_rad_s,
                order_cells(c)
            )?;
        }
    }
    Ok(())
}

/// The warnings, the period-doubled stretches, the topics and attachments, the settings
/// and the last point.
fn warnings_and_contents(rec: &Recording, out: &mut dyn Write) -> anyhow::Result<()> {
    if !rec.warnings.is_empty() {
        writeln!(out, "warnings:    {}", rec.warnings.len())?;
        for w in &rec.warnings {
            writeln!(out, "  {w}")?;
        }
    }
    let stretches = period_doubled_stretches(
        rec.points
            .iter()
            .map(|p| (p.index, p.omega_rad_s, point_half_order_share(&rec.run, p))),
    );
    if !stretches.is_empty() {
        writeln!(
            out,
            "period-doubled response (ω/2 share ≥ {:.0} %):",
            100.0 * PERIOD_DOUBLED_SHARE
        )?;
        for st in &stretches {
            writeln!(out, "  {st}")?;
        }
    }
    writeln!(out, "topics:")?;
    for t in &rec.topics {
        writeln!(
            out,
            "  {:<16} {:<26} {:>6} messages",
            t.topic, t.schema, t.messages
        )?;
    }
    writeln!(out, "attachments: {}", rec.attachments.join(", "))?;
    writeln!(out, "settings:")?;
    for (k, v) in &rec.run.settings {
        writeln!(out, "  {k} = {v}")?;
    }
    if let Some(p) = rec.points.last() {
        writeln!(
            out,
            "last point:  {} at ω = {:.4} rad/s, {}",
            p.index,
            p.omega_rad_s,
            stable_label(p.stable)
        )?;
    }
    Ok(())
}

/// Prints a summary of an operating map (`tmrotor campaign map`).
pub fn map(
    file: &std::path::Path,
    map: &crate::campaign::map::OperatingMap,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    writeln!(out, "file:        {} (operating map)", file.display())?;
    writeln!(out, "parameter:   {}", map.param)?;
    let values: Vec<String> = map.slices.iter().map(|s| s.p.to_string()).collect();
    writeln!(
        out,
        "runs:        {} ({} = {})",
        map.slices.len(),
        map.param,
        values.join(", ")
    )?;
    writeln!(
        out,
        "tolerance:   {} rad/s between joined points",
        map.omega_tolerance
    )?;
    writeln!(out, "curves:      {}", map.curves.len())?;
    for c in &map.curves {
        let (Some(first), Some(last)) = (c.points.first(), c.points.last()) else {
            continue;
        };
        writeln!(
            out,
            "  {:>2} {:<15} {} … {}, ω = {:.2} … {:.2} rad/s",
            c.id,
            c.kind.label(),
            first.0,
            last.0,
            first.1,
            last.1
        )?;
    }
    writeln!(out, "fold-pair ends: {}", map.pair_ends.len())?;
    for e in &map.pair_ends {
        writeln!(
            out,
            "  near ω = {:.2} rad/s: present at {}, gone at {} ({} bisections)",
            e.omega, e.p_with, e.p_without, e.refined
        )?;
    }
    writeln!(out, "regions:     {}", map.regions.len())?;
    Ok(())
}

/// The transient run of a recording (`tmrotor transient`): its profile, start, extent and
/// the last revolution.
fn transient_info(
    t: &crate::record::reader::TransientRecords,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if let Some(i) = &t.info {
        writeln!(out, "transient:   {}; {} s asked", i.profile, i.duration_s)?;
        writeln!(out, "start:       {}", i.start)?;
        writeln!(out, "thermal:     {}", i.thermal_stepping)?;
    }
    writeln!(
        out,
        "revolutions: {}{}; {} displacement samples",
        t.revolutions.len(),
        if t.missing.is_empty() {
            String::new()
        } else {
            format!(" ({} lost)", t.missing.len())
        },
        t.samples.len()
    )?;
    if let Some(last) = t.revolutions.last() {
        let (k, a) = crate::record::transient::largest_amplitude(last);
        writeln!(
            out,
            "last:        t {:.4} s, ω {:.3} rad/s, largest RMS amplitude {:.4} µm at node index {k}",
            last.time_s,
            last.omega_rad_s,
            a * 1e6
        )?;
    }
    Ok(())
}

/// `holds at orders 4, 5 (order 4 converged (521.7483), order 5 …)`.
fn order_cells(c: &crate::record::TruncationCheck) -> String {
    let cells: Vec<String> = c
        .orders
        .iter()
        .map(|(k, o)| format!("order {k} {}", o.describe(4)))
        .collect();
    format!("{} ({})", c.verdict_text(), cells.join(", "))
}
