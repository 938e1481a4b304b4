//! `replay branch FILE [--csv]`.

use std::io::Write;

use crate::derive::point_half_order_share;
use crate::record::reader::Recording;

/// Column name of a node's amplitude: `amp_<id>_m`.
pub fn amplitude_column(id: u32) -> String {
    format!("amp_{id}_m")
}

/// Writes one row per point: index, ω, arc length, RMS amplitude per node (Eq. 35),
/// stable (`1`, `0`, empty when not assessed), bifurcation label, residuals, iterations,
/// and the [`crate::derive::half_order_share`] (empty when the basis has no
/// half-order harmonic).
pub fn run(rec: &Recording, csv: bool, out: &mut dyn Write) -> anyhow::Result<()> {
    let mut header = vec!["index".to_string(), "omega".into(), "arc_length".into()];
    header.extend(rec.run.nodes.iter().map(|n| amplitude_column(n.id)));
    header.extend(
        [
            "stable",
            "bifurcation",
            "residual_mech",
            "residual_therm",
            "newton_iterations",
            "half_order_share",
        ]
        .map(String::from),
    );
    let mut rows = Vec::with_capacity(rec.points.len());
    for p in &rec.points {
        let mut row = vec![
            p.index.to_string(),
            format!("{}", p.omega_rad_s),
            format!("{}", p.arc_length),
        ];
        row.extend(p.amplitude_rms_m.iter().map(|a| format!("{a:e}")));
        row.push(match p.stable {
            Some(true) => "1".into(),
            Some(false) => "0".into(),
            None => String::new(),
        });
        row.push(
            p.bifurcation
                .map_or(String::new(), |b| b.label().to_string()),
        );
        row.push(format!("{:e}", p.residual_mech));
        row.push(format!("{:e}", p.residual_therm));
        row.push(p.newton_iterations.to_string());
        row.push(point_half_order_share(&rec.run, p).map_or(String::new(), |v| format!("{v:.4e}")));
        rows.push(row);
    }
    if csv {
        writeln!(out, "{}", header.join(","))?;
        for row in rows {
            writeln!(out, "{}", row.join(","))?;
        }
        return Ok(());
    }
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for row in &rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let line = |cells: &[String]| -> String {
        cells
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:>w$}"))
            .collect::<Vec<_>>()
            .join("  ")
    };
    writeln!(out, "{}", line(&header))?;
    for row in &rows {
        writeln!(out, "{}", line(row))?;
    }
    Ok(())
}
