//! `replay branch FILE [--csv]`.

use std::io::Write;

use crate::hb::Ratio;
use crate::record::reader::Recording;

/// Column name of a node's amplitude: `amp_<id>_m`.
pub fn amplitude_column(id: u32) -> String {
    format!("amp_{id}_m")
}

/// Share of the half-order harmonics (`ω/2`, `3ω/2`, …: odd multiples of `ω/2`) in a
/// point's mechanical response: the largest half-order amplitude `√(a² + b²)` over the
/// DoFs divided by the largest amplitude of any harmonic (the constant term left out).
/// `None` when the basis has no half-order harmonic.
///
/// On the dual rotor's basis (Eq. 34) the half-order harmonic is `ω/2`; `λω/2 = 3ω/5` is
/// not one. A response without it repeats every five shaft revolutions; where the share
/// is large the branch runs through the period-doubled (`ω/2`) response, which the
/// continuation follows where it joins the primary one (see the README).
pub fn half_order_share(harmonics: &[Ratio], n_mech: usize, coeffs_mech: &[f64]) -> Option<f64> {
    let n_h = harmonics.len();
    let half: Vec<bool> = harmonics
        .iter()
        // ν = num/den is an odd multiple of 1/2 when 2ν is an odd integer
        .map(|r| r.den > 0 && (2 * r.num) % r.den == 0 && (2 * r.num / r.den) % 2 == 1)
        .collect();
    if !half.iter().any(|&h| h) {
        return None;
    }
    let per_dof = 1 + 2 * n_h;
    let (mut largest, mut largest_half) = (0.0f64, 0.0f64);
    for c in coeffs_mech.chunks_exact(per_dof).take(n_mech) {
        for (h, &is_half) in half.iter().enumerate() {
            let amp = c[1 + h].hypot(c[1 + n_h + h]);
            largest = largest.max(amp);
            if is_half {
                largest_half = largest_half.max(amp);
            }
        }
    }
    Some(if largest > 0.0 {
        largest_half / largest
    } else {
        0.0
    })
}

/// Writes one row per point: index, ω, arc length, RMS amplitude per node (Eq. 35),
/// stable (`1`, `0`, empty when not assessed), bifurcation label, residuals, iterations,
/// and the [`half_order_share`] (empty when the basis has no half-order harmonic).
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
        row.push(
            half_order_share(&rec.run.harmonics, rec.run.n_mech, &p.coeffs_mech)
                .map_or(String::new(), |v| format!("{v:.4e}")),
        );
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

#[cfg(test)]
mod tests {
    use super::*;

    fn ratio(num: u32, den: u32) -> Ratio {
        Ratio::new(num, den).expect("ratio")
    }

    #[test]
    fn half_order_share_takes_odd_multiples_of_half_omega_only() {
        // the dual rotor's basis at order 1: ω/2, 3ω/5 (λω/2), ω, 6ω/5
        let basis = [ratio(1, 2), ratio(3, 5), ratio(1, 1), ratio(6, 5)];
        // two DoFs of [a0, a1..a4, b1..b4]
        let coeffs = [
            // DoF 0: ω/2 amplitude 5 (3, 4), 3ω/5 amplitude 20, ω amplitude 10
            1e3, 3.0, 20.0, 10.0, 0.0, 4.0, 0.0, 0.0, 0.0, //
            // DoF 1: 6ω/5 amplitude 40 (largest), ω/2 amplitude 2
            0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 40.0,
        ];
        let share = half_order_share(&basis, 2, &coeffs).expect("has ω/2");
        assert!((share - 5.0 / 40.0).abs() < 1e-15, "{share}");
        // 3ω/2 counts; ω/4, ω/6, 3ω/5 and ω do not
        let none = [ratio(1, 4), ratio(1, 6), ratio(3, 5), ratio(1, 1)];
        assert!(half_order_share(&none, 1, &[0.0; 9]).is_none());
        assert_eq!(
            half_order_share(&[ratio(3, 2), ratio(1, 1)], 1, &[0.0, 1.0, 2.0, 0.0, 0.0]),
            Some(0.5)
        );
        // a response at rest has no share
        assert_eq!(half_order_share(&basis, 2, &[0.0; 18]), Some(0.0));
    }
}
