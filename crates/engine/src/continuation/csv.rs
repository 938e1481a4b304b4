//! The branch as CSV text, as the examples print it.
//!
//! One header row, no comment lines (the convention of every table: docs/user-guide.md,
//! "CSV outputs"). Columns:
//! `omega,amplitude,stable,bifurcation,rms_amplitude,arc_length,newton_iterations,residual_mech,residual_therm`.
//! `amplitude` is `max_t |x_dof(t)|` over one period of the chosen mechanical DoF
//! ([`HbSolution::max_abs`](crate::hb::HbSolution::max_abs)); `rms_amplitude` is paper
//! Eq. 35 for the same DoF; `stable` is `true`/`false`, empty when no stability method ran
//! (or it failed at that point); `bifurcation` is the type of a located bifurcation
//! ([`BifurcationKind::key`](crate::stability::BifurcationKind::key)), empty
//! otherwise. Rows are ordered by arclength; located bifurcations are rows of their own.

use std::fmt::Write;

/// What the columns of [`branch_csv`] mean, for a program to print beside the CSV (on
/// stderr, so the CSV itself stays a plain table).
pub const COLUMNS_NOTE: &str = "columns: amplitude = max |x(t)| over one period of the chosen DoF; \
rms_amplitude = paper Eq. 35 of that DoF; stable empty = not computed; bifurcation = the type \
of a located bifurcation row";

use super::{Branch, BranchPoint, ContinuationError};

/// CSV of `branch` with amplitudes of mechanical DoF `dof` (0-based). Errors when `dof`
/// is not a mechanical DoF.
pub fn branch_csv(branch: &Branch, dof: usize) -> Result<String, ContinuationError> {
    branch_csv_with_parameter(branch, dof, "omega")
}

/// As [`branch_csv`], with the first column (the continuation parameter) named
/// `parameter` instead of `omega`, for systems whose continuation parameter is not a
/// speed (e.g. a forcing amplitude written as the base frequency of a rescaled time, see
/// `systems::period_doubling::GammaParametrized`).
pub fn branch_csv_with_parameter(
    branch: &Branch,
    dof: usize,
    parameter: &str,
) -> Result<String, ContinuationError> {
    if let Some(p) = branch.points.first()
        && dof >= p.solution.n_mech()
    {
        return Err(ContinuationError::Setting {
            field: "amplitude DoF",
            value: dof as f64,
            reason: "not a mechanical DoF of the system",
        });
    }
    let mut rows: Vec<&BranchPoint> = branch.points.iter().chain(&branch.bifurcations).collect();
    rows.sort_by(|a, b| a.arclength.total_cmp(&b.arclength));
    let mut s = String::new();
    s.push_str(parameter);
    s.push_str(",amplitude,stable,bifurcation,rms_amplitude,arc_length,newton_iterations,residual_mech,residual_therm\n");
    for p in rows {
        let stable = match p.stable() {
            Some(true) => "true",
            Some(false) => "false",
            None => "",
        };
        let label = p.bifurcation.map_or("", |k| k.key());
        let sol = &p.solution;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{:e},{:e}",
            sol.omega,
            sol.max_abs(dof),
            stable,
            label,
            sol.rms_amplitude(dof, None),
            p.arclength,
            sol.iterations,
            sol.residual.mech,
            sol.residual.therm
        );
    }
    Ok(s)
}
