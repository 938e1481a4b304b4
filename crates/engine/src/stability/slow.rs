//! Slow (thermal) Floquet exponents from the quasi-static reduction of the harmonic-balance
//! Jacobian onto the thermal mean values.
//!
//! No longer part of the verdict: [`super::assess`] takes the coupled exponents nearest zero
//! from Hill's eigenproblem ([`super::hill_near_zero`]), exact where this reduction has a
//! pole (at the folds of the frozen-temperature problem). Kept as a second method for the
//! thermal exponents away from those points (`tests/stability_split.rs`,
//! `examples/stability_split.rs`).
//!
//! ## Why
//! A coupled thermo-mechanical orbit has two time scales: the vibration period `P`
//! (milliseconds to a tenth of a second) and thermal time constants of seconds to hours.
//! Its thermal multipliers `exp(P·λ)` sit within about `P·|λ| ≈ 1e-6` of +1, which no
//! product of interval exponentials resolves (its error is of order 1e-4 near the circle).
//! A fold of the coupled branch driven by the thermal feedback would pass one of these
//! slow multipliers through +1, unseen by the product. Measured on the dual rotor they do
//! not (the slowest stays at −3.40e-5 1/s across every fold of the paper runs; the folds
//! the product misses there belong to the truncated balance, see `docs/stability.md`),
//! but the exponents are recorded so that a user can see it, and the product no longer
//! carries 66 unresolvable multipliers.
//!
//! ## What
//! With the vibration fast and the temperatures slow, the slow motion follows the
//! averaged heat balance with the vibration in its periodic state for the current mean
//! temperatures (Tikhonov's quasi-static reduction). Linearised, its matrix is the Schur
//! complement of the harmonic-balance Jacobian `J = ∂R/∂A` onto the thermal mean
//! coefficients `m`, all other coefficients `r` (mechanical harmonics, thermal harmonics)
//! eliminated:
//!
//! ```text
//!   S = J_mm − J_mr J_rr⁻¹ J_rm,      C_T δṪ = −S δT,      λ = eig(−C_T⁻¹ S)
//! ```
//!
//! `det J = det J_rr · det S`, so `S` is singular exactly where the coupled branch folds
//! (with `J_rr` regular): a slow exponent passes through 0 there, and the count of
//! exponents with positive real part changes by one. The fast multipliers come from the
//! frozen-temperature product ([`super::frozen`]).
//!
//! ## How
//! The mechanical field reaches the thermal means only through the nonlinear thermal
//! DoFs `q` (contact heat, cooling, expansion), so `S = J_mm + E_q Δ E_qᵀ` with `J_mm` the
//! means' own block of `J` and `Δ` a `|q| × |q|` matrix. One factorization of `J` and `|q|`
//! solves give `W = (J⁻¹)_{m q} = S⁻¹ E_q`, and with `G = E_qᵀ J_mm⁻¹ E_q` Woodbury's
//! identity `E_qᵀ S⁻¹ E_q = (G⁻¹ + Δ)⁻¹` yields `Δ = W_qq⁻¹ − G⁻¹`.
//!
//! ## Limits
//! The reduction neglects `λ` against the fast exponents: its relative error is of order
//! `|λ|/γ` with `γ = min |ln μ_fast| / P` the fast exponent nearest zero
//! ([`fast_gap`], [`ratio_to_gap`]). It is exact in the limit at a coupled fold (`λ → 0`) and fails near a
//! fold of the frozen-temperature problem (`γ → 0`, `J_rr` singular, one `λ` through
//! infinity), where a fast and a slow multiplier interact; the sweep reports such points.

use faer::Mat;
use faer::linalg::solvers::Solve;
use num_complex::Complex64;

use super::{StabilityError, eigenvalues_checked};
use crate::hb::{HarmonicBalance, HbSolution, JacobianParts, LinearSolver};
use crate::system::DenseMatrix;

/// Slow exponents `λ` (1/s) of `solution`, a converged point of `hb`: the eigenvalues of
/// `−C_T⁻¹ S` (see the module docs). Empty for a system without thermal DoFs.
pub fn slow_exponents(
    hb: &HarmonicBalance<'_>,
    solution: &HbSolution,
) -> Result<Vec<Complex64>, StabilityError> {
    slow_exponents_with(hb, solution, None)
}

/// [`slow_exponents`] with the Jacobian at the point when the caller has it (the
/// continuation's corrector computes it with its last residual); `None` or parts of
/// another ω: evaluated here.
pub fn slow_exponents_with(
    hb: &HarmonicBalance<'_>,
    solution: &HbSolution,
    parts: Option<&JacobianParts>,
) -> Result<Vec<Complex64>, StabilityError> {
    let n_t = hb.n_therm();
    if n_t == 0 {
        return Ok(Vec::new());
    }
    let omega = solution.omega;
    let s = thermal_schur_with(hb, solution, parts)?;
    let lin = hb.system().linear(omega);
    let cap = &lin.thermal_capacity;
    let setup = |reason: String| StabilityError::Setup { omega, reason };
    let c = to_mat(cap);
    let lu = c.partial_piv_lu();
    let a = lu.solve(&s);
    if !super::all_finite(a.as_ref()) {
        return Err(setup(
            "the thermal capacity matrix is singular (a thermal node without heat capacity)".into(),
        ));
    }
    let minus_a = Mat::from_fn(n_t, n_t, |i, j| -a[(i, j)]);
    eigenvalues_checked(minus_a.as_ref(), omega)
}

/// The Schur complement `S` of the harmonic-balance Jacobian at `solution` onto the
/// thermal mean coefficients (`n_therm × n_therm`, W/K for a heat balance in W).
pub fn thermal_schur(
    hb: &HarmonicBalance<'_>,
    solution: &HbSolution,
) -> Result<Mat<f64>, StabilityError> {
    thermal_schur_with(hb, solution, None)
}

/// [`thermal_schur`] with the Jacobian at the point given (see [`slow_exponents_with`]).
pub fn thermal_schur_with(
    hb: &HarmonicBalance<'_>,
    solution: &HbSolution,
    given: Option<&JacobianParts>,
) -> Result<Mat<f64>, StabilityError> {
    let omega = solution.omega;
    let setup = |reason: String| StabilityError::Setup { omega, reason };
    let (n_m, n_t, nc) = (hb.n_mech(), hb.n_therm(), hb.n_coeffs());
    let coeffs = solution.unknowns();
    let evaluated;
    let parts = match given.filter(|p| p.omega == omega) {
        Some(p) => p,
        None => {
            let mut r = vec![0.0; coeffs.len()];
            evaluated = hb
                .residual_jacobian(&coeffs, omega, &mut r)
                .map_err(|e| setup(e.to_string()))?;
            &evaluated
        }
    };
    let k_t = to_mat(&parts.linear.thermal_conductance);
    let q_dofs = &hb.nonlinear_dofs().therm;
    if q_dofs.is_empty() {
        // no coupling: the thermal means see their conductance alone
        return Ok(k_t);
    }
    let fact = LinearSolver::default()
        .factor(hb, parts, None)
        .map_err(|e| setup(format!("harmonic-balance Jacobian: {e}")))?;

    let nq = q_dofs.len();
    // W_qq = E_qᵀ (J⁻¹)_{m q}: the nonlinear thermal DoFs' mean coefficients of J⁻¹ e_q
    let mut w_qq = Mat::<f64>::zeros(nq, nq);
    let mut rhs = vec![0.0; coeffs.len()];
    for (k, &dq) in q_dofs.iter().enumerate() {
        rhs.iter_mut().for_each(|v| *v = 0.0);
        rhs[(n_m + dq) * nc] = 1.0;
        let (x, _) = fact
            .solve(&rhs, 0.0)
            .map_err(|e| setup(format!("harmonic-balance Jacobian: {e}")))?;
        for (i, &di) in q_dofs.iter().enumerate() {
            w_qq[(i, k)] = x[(n_m + di) * nc];
        }
    }
    // J_mm: the thermal means' own block (conductance and the nonlinear heat terms'
    // dependence on the mean temperatures, the vibration held)
    let p = hb.nonlinear_dofs().mech.len();
    let ld = (p + nq) * nc;
    let mut j_mm = k_t;
    for (i, &di) in q_dofs.iter().enumerate() {
        for (j, &dj) in q_dofs.iter().enumerate() {
            j_mm[(di, dj)] += parts.nonlinear[((p + i) * nc) * ld + (p + j) * nc];
        }
    }
    // G = E_qᵀ J_mm⁻¹ E_q
    let e_q = Mat::from_fn(n_t, nq, |i, j| if q_dofs[j] == i { 1.0 } else { 0.0 });
    let j_inv_e = j_mm.partial_piv_lu().solve(&e_q);
    let g = Mat::from_fn(nq, nq, |i, j| j_inv_e[(q_dofs[i], j)]);
    let eye = Mat::<f64>::identity(nq, nq);
    let w_inv = w_qq.partial_piv_lu().solve(&eye);
    let g_inv = g.partial_piv_lu().solve(&eye);
    if !super::all_finite(w_inv.as_ref()) || !super::all_finite(g_inv.as_ref()) {
        return Err(setup(
            "the reduction onto the thermal means is singular (a fold of the \
             frozen-temperature problem at this point)"
                .into(),
        ));
    }
    let mut s = j_mm;
    for (i, &di) in q_dofs.iter().enumerate() {
        for (j, &dj) in q_dofs.iter().enumerate() {
            s[(di, dj)] += w_inv[(i, j)] - g_inv[(i, j)];
        }
    }
    Ok(s)
}

/// The fast exponent nearest zero, `γ = min |ln μ| / P` (1/s), over the fast multipliers
/// `fast` of an orbit of period `period` (s): 0 when one of them is +1, infinite without
/// fast multipliers.
pub fn fast_gap(fast: &[Complex64], period: f64) -> f64 {
    fast.iter()
        .filter(|m| m.norm() > 0.0)
        .map(|m| m.ln().norm() / period)
        .fold(f64::INFINITY, f64::min)
}

/// `|λ| / γ`: the estimated relative error of the quasi-static reduction for the slow
/// exponent `lambda` when the fast exponent nearest zero is `gap` ([`fast_gap`]); 0 for an
/// infinite gap.
pub fn ratio_to_gap(lambda: Complex64, gap: f64) -> f64 {
    if gap.is_infinite() {
        0.0
    } else {
        lambda.norm() / gap
    }
}

fn to_mat(d: &DenseMatrix) -> Mat<f64> {
    Mat::from_fn(d.n, d.n, |i, j| d.get(i, j))
}
