//! Linear solves of the Newton systems, with the linear DoFs condensed away ("speed by
//! structure").
//!
//! The Jacobian is `J = Z(ω) + J_nl` where the linear dynamic stiffness `Z` is block
//! diagonal in the harmonics (one `n × n` block for the constant term and one `2n × 2n`
//! block `[[K − w²M, wC], [−wC, K − w²M]]` per harmonic, separately for the mechanical and
//! the thermal field, which the linear part does not couple) and `J_nl` is dense but lives
//! only on the nonlinear DoFs `N`. Splitting each block into linear DoFs `L` and `N`,
//!
//! ```text
//!   x_L = Z_LL⁻¹ (b_L − Z_LN x_N − c_L μ)                              (per field and harmonic)
//!   (Z_NN − Z_NL Z_LL⁻¹ Z_LN + J_nl) x_N + (c_N − Z_NL Z_LL⁻¹ c_L) μ = b_N − Z_NL Z_LL⁻¹ b_L
//! ```
//!
//! so each solve factors small per-harmonic blocks `Z_LL` (cost linear in the number of
//! harmonics) and one dense system of size `|N|·(1+2H)` (+1 with a border), instead of one
//! of size `n·(1+2H)`. The optional border (an extra column `c`, row `r` and corner `d`)
//! is the pseudo-arclength equation: `[[J, c], [rᵀ, d]] [x; μ] = [b; e]`; it is condensed in
//! the same way, so the bordered matrix stays regular at folds.
//!
//! Thermal DoFs not in the nonlinear set are condensed like mechanical ones (first order:
//! `M = 0`). [`LinearSolver::condense`] `= false` assembles and factors the full matrix
//! instead (reference and benchmark).

use faer::Mat;
use faer::linalg::solvers::Solve;
use rayon::prelude::*;
use thiserror::Error;

use super::residual::{HarmonicBalance, JacobianParts, fields};
use crate::system::DenseMatrix;

/// Errors of the linear solves.
#[derive(Debug, Error, PartialEq)]
pub enum SolveError {
    #[error("singular {what} ({size}×{size}) at ω = {omega} rad/s: the solution is not finite")]
    Singular {
        what: &'static str,
        size: usize,
        omega: f64,
    },
}

/// Extra column, row and corner of a bordered system (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Border<'b> {
    pub column: &'b [f64],
    pub row: &'b [f64],
    pub corner: f64,
}

/// Solves `[[J, c], [rᵀ, d]] [x; μ] = [b; e]` (or `J x = b` without border).
#[derive(Clone, Copy, Debug)]
pub struct LinearSolver {
    /// Condense the linear DoFs per harmonic (default `true`).
    pub condense: bool,
}

impl Default for LinearSolver {
    fn default() -> Self {
        Self { condense: true }
    }
}

/// A matrix entry of the harmonic block of one field: `(cos|sin) × (cos|sin)` parts.
#[inline]
#[allow(clippy::too_many_arguments)]
fn z_entry(
    k: &DenseMatrix,
    c: &DenseMatrix,
    m: Option<&DenseMatrix>,
    w: f64,
    i: usize,
    j: usize,
    part_row: usize,
    part_col: usize,
) -> f64 {
    match (part_row, part_col) {
        (0, 0) | (1, 1) => k.get(i, j) - w * w * m.map_or(0.0, |m| m.get(i, j)),
        (0, 1) => w * c.get(i, j),
        _ => -w * c.get(i, j),
    }
}

fn solve_dense(
    a: &Mat<f64>,
    b: &Mat<f64>,
    what: &'static str,
    omega: f64,
) -> Result<Mat<f64>, SolveError> {
    let x = a.partial_piv_lu().solve(b);
    for j in 0..x.ncols() {
        for i in 0..x.nrows() {
            if !x[(i, j)].is_finite() {
                return Err(SolveError::Singular {
                    what,
                    size: a.nrows(),
                    omega,
                });
            }
        }
    }
    Ok(x)
}

impl LinearSolver {
    /// Solves the (bordered) Newton system at the Jacobian `parts` for right-hand side
    /// `b` (and `e` for the border row). Returns `(x, μ)` (`μ = 0` without border).
    pub fn solve(
        &self,
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
        b: &[f64],
        e: f64,
    ) -> Result<(Vec<f64>, f64), SolveError> {
        if self.condense {
            self.solve_condensed(hb, parts, border, b, e)
        } else {
            self.solve_full(hb, parts, border, b, e)
        }
    }

    fn solve_full(
        &self,
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
        b: &[f64],
        e: f64,
    ) -> Result<(Vec<f64>, f64), SolveError> {
        let nu = hb.n_unknowns();
        let m = nu + usize::from(border.is_some());
        let jac = hb.dense_jacobian(parts);
        let mut a = Mat::<f64>::zeros(m, m);
        for i in 0..nu {
            for j in 0..nu {
                a[(i, j)] = jac[i * nu + j];
            }
        }
        let mut rhs = Mat::<f64>::zeros(m, 1);
        for i in 0..nu {
            rhs[(i, 0)] = b[i];
        }
        if let Some(bd) = border {
            for i in 0..nu {
                a[(i, nu)] = bd.column[i];
                a[(nu, i)] = bd.row[i];
            }
            a[(nu, nu)] = bd.corner;
            rhs[(nu, 0)] = e;
        }
        let x = solve_dense(&a, &rhs, "Jacobian", parts.omega)?;
        let sol = (0..nu).map(|i| x[(i, 0)]).collect();
        let mu = if border.is_some() { x[(nu, 0)] } else { 0.0 };
        Ok((sol, mu))
    }

    fn solve_condensed(
        &self,
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
        b: &[f64],
        e: f64,
    ) -> Result<(Vec<f64>, f64), SolveError> {
        let omega = parts.omega;
        let nc = hb.n_coeffs();
        let basis = hb.basis();
        let nh = basis.n_harmonics();
        let globals = hb.nonlinear_global();
        let pn = globals.len() * nc;
        let has_border = border.is_some();
        let m = pn + usize::from(has_border);
        let n_total = hb.n_mech() + hb.n_therm();
        let mut pos = vec![usize::MAX; n_total];
        for (k, &g) in globals.iter().enumerate() {
            pos[g] = k;
        }
        // condensed matrix, starts as J_nl (+ border)
        let mut a = Mat::<f64>::zeros(m, m);
        for i in 0..pn {
            for j in 0..pn {
                a[(i, j)] = parts.nonlinear[i * pn + j];
            }
        }
        let mut s = Mat::<f64>::zeros(m, 1);
        for (k, &g) in globals.iter().enumerate() {
            for c in 0..nc {
                s[(k * nc + c, 0)] = b[g * nc + c];
                if let Some(bd) = border {
                    a[(k * nc + c, pn)] = bd.column[g * nc + c];
                    a[(pn, k * nc + c)] = bd.row[g * nc + c];
                }
            }
        }
        if let Some(bd) = border {
            a[(pn, pn)] = bd.corner;
            s[(pn, 0)] = e;
        }
        // coefficient index of (harmonic slot hs, part): hs = 0 constant, hs ≥ 1 harmonic hs-1
        let coeff = |hs: usize, part: usize| -> usize {
            if hs == 0 {
                0
            } else if part == 0 {
                hs
            } else {
                nh + hs
            }
        };
        // one block per (field, harmonic slot): the linear-DoF solves are independent and
        // run in parallel; their contributions are added to the condensed system in order.
        struct Block {
            lin: Vec<usize>,
            nl: Vec<usize>,
            hs: usize,
            parts: usize,
            /// `Z_NN − Z_NL W` (sn × sn), row/col local (part·|N| + t)
            schur: Mat<f64>,
            /// `Z_NL [y_b, y_c]` (sn × 1 or 2)
            rhs_corr: Mat<f64>,
            /// `[W, y_b, y_c]` (sl × ncol)
            sol: Option<Mat<f64>>,
        }
        let flds = fields(&parts.linear, hb.n_mech(), hb.n_therm());
        let mut jobs = Vec::new();
        for (fi, fld) in flds.iter().enumerate() {
            if fld.n > 0 {
                jobs.extend((0..=nh).map(|hs| (fi, hs)));
            }
        }
        let build = |&(fi, hs): &(usize, usize)| -> Result<Block, SolveError> {
            let fld = &flds[fi];
            let nl: Vec<usize> = (0..fld.n)
                .filter(|&i| pos[fld.offset + i] != usize::MAX)
                .collect();
            let lin: Vec<usize> = (0..fld.n)
                .filter(|&i| pos[fld.offset + i] == usize::MAX)
                .collect();
            let w = if hs == 0 {
                0.0
            } else {
                basis.harmonics()[hs - 1].value() * omega
            };
            let np = if hs == 0 { 1 } else { 2 };
            let z = |i: usize, j: usize, pr: usize, pc: usize| {
                z_entry(fld.stiffness, fld.damping, fld.mass, w, i, j, pr, pc)
            };
            let (nn, nl_len) = (lin.len(), nl.len());
            let (sl, sn) = (np * nn, np * nl_len);
            let mut schur = Mat::<f64>::zeros(sn, sn);
            for pr in 0..np {
                for (ti, &i) in nl.iter().enumerate() {
                    for pc in 0..np {
                        for (tj, &j) in nl.iter().enumerate() {
                            schur[(pr * nl_len + ti, pc * nl_len + tj)] = z(i, j, pr, pc);
                        }
                    }
                }
            }
            let ncol = sn + 1 + usize::from(has_border);
            let mut rhs_corr = Mat::<f64>::zeros(sn, ncol - sn);
            let mut sol = None;
            if nn > 0 {
                let mut zll = Mat::<f64>::zeros(sl, sl);
                let mut rhs = Mat::<f64>::zeros(sl, ncol);
                let mut znl = Mat::<f64>::zeros(sn, sl);
                for pr in 0..np {
                    for (ti, &i) in lin.iter().enumerate() {
                        let gi = (fld.offset + i) * nc + coeff(hs, pr);
                        for pc in 0..np {
                            for (tj, &j) in lin.iter().enumerate() {
                                zll[(pr * nn + ti, pc * nn + tj)] = z(i, j, pr, pc);
                            }
                            for (tj, &j) in nl.iter().enumerate() {
                                rhs[(pr * nn + ti, pc * nl_len + tj)] = z(i, j, pr, pc);
                                znl[(pc * nl_len + tj, pr * nn + ti)] = z(j, i, pc, pr);
                            }
                        }
                        rhs[(pr * nn + ti, sn)] = b[gi];
                        if let Some(bd) = border {
                            rhs[(pr * nn + ti, sn + 1)] = bd.column[gi];
                        }
                    }
                }
                let x = solve_dense(&zll, &rhs, "linear-DoF block", omega)?;
                let prod = &znl * &x; // sn × ncol
                for r in 0..sn {
                    for c in 0..sn {
                        schur[(r, c)] -= prod[(r, c)];
                    }
                    for c in sn..ncol {
                        rhs_corr[(r, c - sn)] = prod[(r, c)];
                    }
                }
                sol = Some(x);
            }
            Ok(Block {
                lin: lin.iter().map(|&i| fld.offset + i).collect(),
                nl: nl.iter().map(|&i| fld.offset + i).collect(),
                hs,
                parts: np,
                schur,
                rhs_corr,
                sol,
            })
        };
        let blocks: Vec<Block> = if hb.n_unknowns() >= 256 {
            jobs.par_iter().map(build).collect::<Result<_, _>>()?
        } else {
            jobs.iter().map(build).collect::<Result<_, _>>()?
        };
        for bl in &blocks {
            let (nl_len, np, hs) = (bl.nl.len(), bl.parts, bl.hs);
            let sn = np * nl_len;
            let crow = |t: usize, part: usize| pos[bl.nl[t]] * nc + coeff(hs, part);
            for pr in 0..np {
                for ti in 0..nl_len {
                    let (r, ar) = (pr * nl_len + ti, crow(ti, pr));
                    for pc in 0..np {
                        for tj in 0..nl_len {
                            a[(ar, crow(tj, pc))] += bl.schur[(r, pc * nl_len + tj)];
                        }
                    }
                    s[(ar, 0)] -= bl.rhs_corr[(r, 0)];
                    if has_border {
                        a[(ar, pn)] -= bl.rhs_corr[(r, 1)];
                    }
                }
            }
            if let (Some(bd), Some(sol)) = (border, &bl.sol) {
                let nn = bl.lin.len();
                for pr in 0..np {
                    for (ti, &gi) in bl.lin.iter().enumerate() {
                        let rl = bd.row[gi * nc + coeff(hs, pr)];
                        if rl == 0.0 {
                            continue;
                        }
                        let li = pr * nn + ti;
                        for pc in 0..np {
                            for tj in 0..nl_len {
                                a[(pn, crow(tj, pc))] -= rl * sol[(li, pc * nl_len + tj)];
                            }
                        }
                        s[(pn, 0)] -= rl * sol[(li, sn)];
                        a[(pn, pn)] -= rl * sol[(li, sn + 1)];
                    }
                }
            }
        }
        let xs = if m > 0 {
            solve_dense(&a, &s, "condensed Jacobian", omega)?
        } else {
            Mat::<f64>::zeros(0, 1)
        };
        let mu = if has_border { xs[(pn, 0)] } else { 0.0 };
        let mut x = vec![0.0; hb.n_unknowns()];
        for (k, &g) in globals.iter().enumerate() {
            for c in 0..nc {
                x[g * nc + c] = xs[(k * nc + c, 0)];
            }
        }
        for bl in &blocks {
            let Some(sol) = &bl.sol else { continue };
            let (nn, nl_len) = (bl.lin.len(), bl.nl.len());
            let sn = bl.parts * nl_len;
            for pr in 0..bl.parts {
                for (ti, &gi) in bl.lin.iter().enumerate() {
                    let li = pr * nn + ti;
                    let mut v = sol[(li, sn)];
                    if has_border {
                        v -= sol[(li, sn + 1)] * mu;
                    }
                    for pc in 0..bl.parts {
                        for (tj, &gj) in bl.nl.iter().enumerate() {
                            v -= sol[(li, pc * nl_len + tj)] * x[gj * nc + coeff(bl.hs, pc)];
                        }
                    }
                    x[gi * nc + coeff(bl.hs, pr)] = v;
                }
            }
        }
        Ok((x, mu))
    }
}
