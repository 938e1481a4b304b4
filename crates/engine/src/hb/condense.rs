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
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor as lu_factor, solve as lu_solve};
use faer::perm::PermRef;
use faer::{MatMut, Par, get_global_parallelism};
use rayon::prelude::*;
use std::sync::Arc;
use thiserror::Error;

use super::Basis;
use super::residual::{Field, HarmonicBalance, JacobianParts, fields};
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

/// `x` finite, or the singular-matrix error for `what` (`size` × `size`).
fn check_finite(
    x: &Mat<f64>,
    what: &'static str,
    size: usize,
    omega: f64,
) -> Result<(), SolveError> {
    let finite = (0..x.ncols()).all(|j| (0..x.nrows()).all(|i| x[(i, j)].is_finite()));
    if finite {
        Ok(())
    } else {
        Err(SolveError::Singular { what, size, omega })
    }
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
        self.factor(hb, parts, border)?.solve(b, e)
    }

    /// Factors the (bordered) Newton matrix at the Jacobian `parts`, for any number of
    /// right-hand sides ([`Factorization::solve`]; a solve after the factorization costs
    /// about 0.4 ms on the dual rotor against 11 ms for the factorization).
    pub fn factor(
        &self,
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
    ) -> Result<Factorization, SolveError> {
        self.factor_in(hb, parts, border, Layout::Single)
    }

    /// [`Self::factor`] for solves with blocks of right-hand sides
    /// ([`Factorization::solve_many`] with several columns, as Hill's block Arnoldi
    /// iteration does): the condensed matrix's factors are kept in the layout faer solves
    /// many columns fastest with, at the cost of one copy of the matrix.
    pub fn factor_for_blocks(
        &self,
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
    ) -> Result<Factorization, SolveError> {
        self.factor_in(hb, parts, border, Layout::Blocks)
    }

    fn factor_in(
        &self,
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
        layout: Layout,
    ) -> Result<Factorization, SolveError> {
        let inner = Arc::new(if self.condense {
            Factored::Condensed(Box::new(Condensed::new(hb, parts, border, layout)?))
        } else {
            Factored::Full(full_lu(hb, parts, border))
        });
        Ok(Factorization {
            inner,
            omega: parts.omega,
            n_unknowns: hb.n_unknowns(),
            border: border.map(|bd| (bd.row.to_vec(), bd.corner)),
            row_update: None,
        })
    }
}

/// How a condensed factorization keeps the condensed matrix's factors: for solves one
/// right-hand side at a time, or for blocks of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    /// The factors of the transposed matrix, as it is assembled: faer's transposed
    /// triangular solve is as fast as the direct one for one column.
    Single,
    /// The factors of the matrix itself (the assembled transpose copied over once): with
    /// four columns faer's direct triangular solve is about 2.5 times faster than its
    /// transposed one (on the dual rotor's 900 condensed unknowns 0.16 against 0.40 ms).
    Blocks,
}

/// A factored (bordered) Newton matrix (see [`LinearSolver::factor`]). Cloning shares
/// the factors (they are never changed after the factorization) and copies only the
/// border row and its replacement.
#[derive(Clone)]
pub struct Factorization {
    inner: Arc<Factored>,
    omega: f64,
    n_unknowns: usize,
    /// The border row and corner the matrix was factored with.
    border: Option<(Vec<f64>, f64)>,
    /// Set by [`Factorization::replace_border_row`].
    row_update: Option<RowUpdate>,
}

/// A replaced border row `(r', d')`, applied by Sherman–Morrison: the new matrix is
/// `A' = A + e vᵀ` with `e` the border's unit vector and `v = (r' − r, d' − d)`, so
/// `A'⁻¹ b = y − u (vᵀ y) / (1 + vᵀ u)` with `y = A⁻¹ b` and `u = A⁻¹ e`.
#[derive(Clone)]
struct RowUpdate {
    /// `u = A⁻¹ e`: unknowns, then the border component.
    u: Vec<f64>,
    u_mu: f64,
    /// `v = (r' − r, d' − d)`.
    v: Vec<f64>,
    v_corner: f64,
    /// `1 + vᵀ u`.
    denom: f64,
}

enum Factored {
    Full(Lu),
    Condensed(Box<Condensed>),
}

impl Factorization {
    /// Whether the matrix carries a border row and column.
    pub fn bordered(&self) -> bool {
        self.border.is_some()
    }

    /// Replaces the border row and corner by `row` and `corner` (the Jacobian and the
    /// border column stay), without a new factorization: later solves apply the change
    /// as a rank-one (Sherman–Morrison) correction, one extra solve now and a dot product
    /// per solve. This is how the continuation corrects with the matrix factored for its
    /// tangent: the tangent's matrix is bordered with the previous tangent, the
    /// corrector's with the new one. Fails without a border, on a length mismatch, or
    /// when the new matrix is singular (`1 + vᵀ u` vanishes). `u`, when given, is the
    /// solution `(x, μ)` for `b = 0, e = 1` with the current row (a tangent's own solve).
    pub fn replace_border_row(
        &mut self,
        row: &[f64],
        corner: f64,
        u: Option<(&[f64], f64)>,
    ) -> Result<(), SolveError> {
        let singular = SolveError::Singular {
            what: "bordered Jacobian with its border row replaced",
            size: self.n_unknowns + 1,
            omega: self.omega,
        };
        let Some((old_row, old_corner)) = &self.border else {
            return Err(singular);
        };
        if row.len() != old_row.len() {
            return Err(singular);
        }
        let v: Vec<f64> = row.iter().zip(old_row).map(|(n, o)| n - o).collect();
        let v_corner = corner - old_corner;
        let (u, u_mu) = match u {
            Some((x, mu)) if self.row_update.is_none() && x.len() == self.n_unknowns => {
                (x.to_vec(), mu)
            }
            _ => {
                self.row_update = None;
                self.solve(&vec![0.0; self.n_unknowns], 1.0)?
            }
        };
        let denom = 1.0 + dot(&v, &u) + v_corner * u_mu;
        // 1 + vᵀu = det(A') / det(A): relative to the sizes of its terms
        let size = 1.0 + dot(row, &u).abs() + (corner * u_mu).abs();
        if !denom.is_finite() || denom.abs() <= 1e-12 * size {
            return Err(singular);
        }
        self.row_update = Some(RowUpdate {
            u,
            u_mu,
            v,
            v_corner,
            denom,
        });
        Ok(())
    }

    /// Solves for right-hand side `b` (and `e` for the border row; ignored without
    /// border). Returns `(x, μ)` (`μ = 0` without border).
    pub fn solve(&self, b: &[f64], e: f64) -> Result<(Vec<f64>, f64), SolveError> {
        let (x, mu) =
            self.solve_many(faer::MatRef::from_column_major_slice(b, b.len(), 1), &[e])?;
        Ok(((0..x.nrows()).map(|i| x[(i, 0)]).collect(), mu[0]))
    }

    /// Solves for the columns of `b` at once (`n_unknowns × k`; `e[j]` the border
    /// row's entry of column `j`, ignored without border): the factors are read once for
    /// all of them, which is what makes a block of right-hand sides cheaper than `k`
    /// calls of [`Self::solve`]. Returns the solutions as columns and their `μ`.
    pub fn solve_many(
        &self,
        b: faer::MatRef<'_, f64>,
        e: &[f64],
    ) -> Result<(Mat<f64>, Vec<f64>), SolveError> {
        let (mut x, mut mu) = self.solve_factored(b, e)?;
        if let Some(ru) = &self.row_update {
            for (col, mu) in mu.iter_mut().enumerate() {
                let vx: f64 = (0..x.nrows()).map(|i| ru.v[i] * x[(i, col)]).sum();
                let f = (vx + ru.v_corner * *mu) / ru.denom;
                for (i, ui) in ru.u.iter().enumerate() {
                    x[(i, col)] -= f * ui;
                }
                *mu -= f * ru.u_mu;
            }
        }
        Ok((x, mu))
    }

    fn solve_factored(
        &self,
        b: faer::MatRef<'_, f64>,
        e: &[f64],
    ) -> Result<(Mat<f64>, Vec<f64>), SolveError> {
        let nu = self.n_unknowns;
        let k = b.ncols();
        let bordered = self.bordered();
        let e_of = |col: usize| e.get(col).copied().unwrap_or(0.0);
        match self.inner.as_ref() {
            Factored::Full(lu) => {
                let m = nu + usize::from(bordered);
                let mut rhs = Mat::<f64>::zeros(m, k);
                rhs.as_mut()
                    .submatrix_mut(0, 0, nu, k)
                    .copy_from(b.subrows(0, nu));
                if bordered {
                    for col in 0..k {
                        rhs[(nu, col)] = e_of(col);
                    }
                }
                let x = lu.solve(&rhs);
                check_finite(&x, "Jacobian", m, self.omega)?;
                let mu = (0..k)
                    .map(|col| if bordered { x[(nu, col)] } else { 0.0 })
                    .collect();
                Ok((x.as_ref().submatrix(0, 0, nu, k).to_owned(), mu))
            }
            Factored::Condensed(c) => {
                let e: Vec<f64> = (0..k).map(e_of).collect();
                c.solve_many(b, &e, self.omega)
            }
        }
    }
}

fn full_lu(hb: &HarmonicBalance<'_>, parts: &JacobianParts, border: Option<Border<'_>>) -> Lu {
    let nu = hb.n_unknowns();
    let m = nu + usize::from(border.is_some());
    let jac = hb.dense_jacobian(parts);
    let mut a = Mat::<f64>::zeros(m, m);
    a.as_mut()
        .submatrix_mut(0, 0, nu, nu)
        .copy_from(faer::MatRef::from_row_major_slice(&jac, nu, nu));
    if let Some(bd) = border {
        for i in 0..nu {
            a[(i, nu)] = bd.column[i];
            a[(nu, i)] = bd.row[i];
        }
        a[(nu, nu)] = bd.corner;
    }
    Lu::new(a)
}

/// One (field, harmonic slot) block of the linear dynamic stiffness, split into the
/// field's linear DoFs `L` and nonlinear DoFs `N`.
struct Block {
    /// Global DoFs of `L` and `N`.
    lin: Vec<usize>,
    nl: Vec<usize>,
    /// Harmonic slot (0 constant, `h ≥ 1` harmonic `h − 1`) and its parts (1 or 2).
    hs: usize,
    parts: usize,
    /// `Z_LL`, factored (`None` when the block has no linear DoFs).
    zll: Option<Lu>,
    /// `Z_NL` (`sn × sl`).
    znl: Mat<f64>,
    /// `W = Z_LL⁻¹ Z_LN` (`sl × sn`).
    w: Mat<f64>,
    /// `Z_LL⁻¹ c_L` for the border column `c` (`sl × 1`, empty without border).
    yc: Mat<f64>,
}

/// The condensed factorization (see the module docs).
struct Condensed {
    nc: usize,
    nh: usize,
    n_unknowns: usize,
    globals: Vec<usize>,
    /// Position of each global DoF among the nonlinear ones (`usize::MAX`: linear).
    pos: Vec<usize>,
    blocks: Vec<Block>,
    /// The border row (global unknowns), when bordered.
    border_row: Option<Vec<f64>>,
    /// LU of the condensed matrix (`None` when it is empty).
    lu: Option<Lu>,
}

impl Condensed {
    /// Coefficient index of (harmonic slot `hs`, part).
    fn coeff(&self, hs: usize, part: usize) -> usize {
        coeff_index(self.nh, hs, part)
    }

    fn pn(&self) -> usize {
        self.globals.len() * self.nc
    }

    fn new(
        hb: &HarmonicBalance<'_>,
        parts: &JacobianParts,
        border: Option<Border<'_>>,
        layout: Layout,
    ) -> Result<Self, SolveError> {
        let omega = parts.omega;
        let nc = hb.n_coeffs();
        let basis = hb.basis();
        let nh = basis.n_harmonics();
        let globals = hb.nonlinear_global().to_vec();
        let pn = globals.len() * nc;
        let has_border = border.is_some();
        let m = pn + usize::from(has_border);
        let n_total = hb.n_mech() + hb.n_therm();
        let mut pos = vec![usize::MAX; n_total];
        for (k, &g) in globals.iter().enumerate() {
            pos[g] = k;
        }
        // The condensed matrix is assembled transposed, `at = Aᵀ`: the row-major `J_nl` is
        // then a column-major copy (a transposing copy of 3 MB cost a millisecond), and the
        // Schur complements below are added down columns. `Lu` solves with `A`.
        // `at` starts as `J_nlᵀ` (+ border).
        let mut at = Mat::<f64>::zeros(m, m);
        at.as_mut()
            .submatrix_mut(0, 0, pn, pn)
            .copy_from(faer::MatRef::from_column_major_slice(
                &parts.nonlinear,
                pn,
                pn,
            ));
        if let Some(bd) = border {
            for (k, &g) in globals.iter().enumerate() {
                for c in 0..nc {
                    at[(pn, k * nc + c)] = bd.column[g * nc + c];
                    at[(k * nc + c, pn)] = bd.row[g * nc + c];
                }
            }
            at[(pn, pn)] = bd.corner;
        }
        let flds = fields(&parts.linear, hb.n_mech(), hb.n_therm());
        let mut jobs = Vec::new();
        for (fi, fld) in flds.iter().enumerate() {
            if fld.n > 0 {
                jobs.extend((0..=nh).map(|hs| (fi, hs)));
            }
        }
        // One block per (field, harmonic slot) ([`Condensing::block`]): the linear-DoF
        // solves are independent and run in parallel; their contributions are added to the
        // condensed matrix in order ([`Condensing::add`]).
        let condensing = Condensing {
            omega,
            nc,
            nh,
            basis,
            flds: &flds,
            pos: &pos,
            pn,
            border,
            has_border,
        };
        let built: Vec<(Block, Mat<f64>, Mat<f64>)> = if hb.n_unknowns() >= 256 {
            jobs.par_iter()
                .map(|job| condensing.block(job))
                .collect::<Result<_, _>>()?
        } else {
            jobs.iter()
                .map(|job| condensing.block(job))
                .collect::<Result<_, _>>()?
        };
        let mut blocks = Vec::with_capacity(built.len());
        for (bl, schur, corr_c) in built {
            condensing.add(&mut at, &bl, &schur, &corr_c);
            blocks.push(bl);
        }
        Ok(Self {
            nc,
            nh,
            n_unknowns: hb.n_unknowns(),
            globals,
            pos,
            blocks,
            border_row: border.map(|bd| bd.row.to_vec()),
            lu: (m > 0).then(|| match layout {
                Layout::Single => Lu::factor(at, true, get_global_parallelism()),
                Layout::Blocks => {
                    Lu::factor(at.transpose().to_owned(), false, get_global_parallelism())
                }
            }),
        })
    }

    /// Solves for the right-hand sides `b` (`n_unknowns × k`) and border entries `e` (one
    /// per column; ignored without border): the per-block solves, the condensed solve and
    /// the back-substitution each take all `k` columns at once, so the factors are read
    /// once for the block instead of once per column.
    fn solve_many(
        &self,
        b: faer::MatRef<'_, f64>,
        e: &[f64],
        omega: f64,
    ) -> Result<(Mat<f64>, Vec<f64>), SolveError> {
        let (nc, pn, k) = (self.nc, self.pn(), b.ncols());
        let has_border = self.border_row.is_some();
        let m = pn + usize::from(has_border);
        let mut s = Mat::<f64>::zeros(m, k);
        for col in 0..k {
            for (kk, &g) in self.globals.iter().enumerate() {
                for c in 0..nc {
                    s[(kk * nc + c, col)] = b[(g * nc + c, col)];
                }
            }
            if has_border {
                s[(pn, col)] = e[col];
            }
        }
        // y_b = Z_LL⁻¹ b_L per block, and its condensed contributions
        let mut ys = Vec::with_capacity(self.blocks.len());
        for bl in &self.blocks {
            let Some(zll) = &bl.zll else {
                ys.push(None);
                continue;
            };
            let (nn, nl_len, np, hs) = (bl.lin.len(), bl.nl.len(), bl.parts, bl.hs);
            let mut bl_rhs = Mat::<f64>::zeros(np * nn, k);
            for col in 0..k {
                for pr in 0..np {
                    for (ti, &gi) in bl.lin.iter().enumerate() {
                        bl_rhs[(pr * nn + ti, col)] = b[(gi * nc + self.coeff(hs, pr), col)];
                    }
                }
            }
            let y = zll.solve(&bl_rhs);
            check_finite(&y, "linear-DoF block", np * nn, omega)?;
            let corr = &bl.znl * &y;
            for col in 0..k {
                for pr in 0..np {
                    for ti in 0..nl_len {
                        let ar = self.pos[bl.nl[ti]] * nc + self.coeff(hs, pr);
                        s[(ar, col)] -= corr[(pr * nl_len + ti, col)];
                    }
                }
                if let Some(row) = &self.border_row {
                    for pr in 0..np {
                        for (ti, &gi) in bl.lin.iter().enumerate() {
                            s[(pn, col)] -=
                                row[gi * nc + self.coeff(hs, pr)] * y[(pr * nn + ti, col)];
                        }
                    }
                }
            }
            ys.push(Some(y));
        }
        let xs = match &self.lu {
            Some(lu) => {
                let xs = lu.solve(&s);
                check_finite(&xs, "condensed Jacobian", m, omega)?;
                xs
            }
            None => Mat::<f64>::zeros(0, k),
        };
        let mu: Vec<f64> = (0..k)
            .map(|col| if has_border { xs[(pn, col)] } else { 0.0 })
            .collect();
        let mut x = Mat::<f64>::zeros(self.n_unknowns, k);
        for col in 0..k {
            for (kk, &g) in self.globals.iter().enumerate() {
                for c in 0..nc {
                    x[(g * nc + c, col)] = xs[(kk * nc + c, col)];
                }
            }
        }
        // x_L = y_b − y_c μ − W x_N, per block for all columns: W x_N as one product
        for (bl, y) in self.blocks.iter().zip(&ys) {
            let Some(y) = y else { continue };
            let (nn, nl_len, np, hs) = (bl.lin.len(), bl.nl.len(), bl.parts, bl.hs);
            let mut xn = Mat::<f64>::zeros(np * nl_len, k);
            for col in 0..k {
                for pc in 0..np {
                    for (tj, &gj) in bl.nl.iter().enumerate() {
                        xn[(pc * nl_len + tj, col)] = x[(gj * nc + self.coeff(hs, pc), col)];
                    }
                }
            }
            let wx = &bl.w * &xn;
            for col in 0..k {
                for pr in 0..np {
                    for (ti, &gi) in bl.lin.iter().enumerate() {
                        let li = pr * nn + ti;
                        let mut v = y[(li, col)] - wx[(li, col)];
                        if has_border {
                            v -= bl.yc[(li, 0)] * mu[col];
                        }
                        x[(gi * nc + self.coeff(hs, pr), col)] = v;
                    }
                }
            }
        }
        Ok((x, mu))
    }
}

/// What the blocks of a condensed factorization are built from and added to its matrix
/// with (see [`Condensed::new`]): the speed, the coefficient layout, the fields, each
/// DoF's position among the nonlinear ones, the condensed size `pn` (the border's row and
/// column next) and the border.
struct Condensing<'a> {
    omega: f64,
    nc: usize,
    nh: usize,
    basis: &'a Basis,
    flds: &'a [Field<'a>; 2],
    pos: &'a [usize],
    pn: usize,
    border: Option<Border<'a>>,
    has_border: bool,
}

impl Condensing<'_> {
    /// One block of the linear dynamic stiffness, of field `fi` and harmonic slot `hs`:
    /// the block, with its linear-DoF part factored and solved against `[Z_LN, c_L]`, its
    /// Schur complement `Z_NN − Z_NL W` and `Z_NL Z_LL⁻¹ c_L` (one column with a border,
    /// none without).
    fn block(&self, &(fi, hs): &(usize, usize)) -> Result<(Block, Mat<f64>, Mat<f64>), SolveError> {
        let Self {
            omega,
            nc,
            nh,
            basis,
            flds,
            pos,
            border,
            has_border,
            ..
        } = *self;
        let coeff = |hs: usize, part: usize| coeff_index(nh, hs, part);
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
        let mut schur = z_block(&nl, &nl, np, z);
        let mut corr_c = Mat::<f64>::zeros(sn, usize::from(has_border));
        let mut block = Block {
            lin: lin.iter().map(|&i| fld.offset + i).collect(),
            nl: nl.iter().map(|&i| fld.offset + i).collect(),
            hs,
            parts: np,
            zll: None,
            znl: z_block(&nl, &lin, np, z),
            w: Mat::zeros(sl, sn),
            yc: Mat::zeros(sl, usize::from(has_border)),
        };
        if nn > 0 {
            // [Z_LN, c_L]
            let mut rhs = Mat::<f64>::zeros(sl, sn + usize::from(has_border));
            rhs.as_mut()
                .subcols_mut(0, sn)
                .copy_from(z_block(&lin, &nl, np, z));
            if let Some(bd) = border {
                for pr in 0..np {
                    for (ti, &i) in lin.iter().enumerate() {
                        let gi = (fld.offset + i) * nc + coeff(hs, pr);
                        rhs[(pr * nn + ti, sn)] = bd.column[gi];
                    }
                }
            }
            // small (≤ 2·72 rows) and already one of many parallel jobs
            let lu = Lu::factor(z_block(&lin, &lin, np, z), false, Par::Seq);
            let x = lu.solve(&rhs);
            check_finite(&x, "linear-DoF block", sl, omega)?;
            let prod = &block.znl * &x; // sn × ncol
            for r in 0..sn {
                for c in 0..sn {
                    schur[(r, c)] -= prod[(r, c)];
                }
                if has_border {
                    corr_c[(r, 0)] = prod[(r, sn)];
                }
            }
            block.w = x.subcols(0, sn).to_owned();
            if has_border {
                block.yc = x.subcols(sn, 1).to_owned();
            }
            block.zll = Some(lu);
        }
        Ok((block, schur, corr_c))
    }

    /// Adds a block's Schur complement `schur` and border terms (`corr_c`, and with a
    /// border the border row's linear part through `W` and `Z_LL⁻¹ c_L`) to the transposed
    /// condensed matrix `at`.
    fn add(&self, at: &mut Mat<f64>, bl: &Block, schur: &Mat<f64>, corr_c: &Mat<f64>) {
        let Self {
            nc,
            nh,
            pos,
            pn,
            border,
            has_border,
            ..
        } = *self;
        let coeff = |hs: usize, part: usize| coeff_index(nh, hs, part);
        let (nl_len, np, hs) = (bl.nl.len(), bl.parts, bl.hs);
        let crow = |t: usize, part: usize| pos[bl.nl[t]] * nc + coeff(hs, part);
        for pr in 0..np {
            for ti in 0..nl_len {
                let (r, ar) = (pr * nl_len + ti, crow(ti, pr));
                let mut col = at.col_mut(ar);
                for pc in 0..np {
                    for tj in 0..nl_len {
                        col[crow(tj, pc)] += schur[(r, pc * nl_len + tj)];
                    }
                }
                if has_border {
                    col[pn] -= corr_c[(r, 0)];
                }
            }
        }
        if let (Some(bd), true) = (border, bl.zll.is_some()) {
            let nn = bl.lin.len();
            for pr in 0..np {
                for (ti, &gi) in bl.lin.iter().enumerate() {
                    let rl = bd.row[gi * nc + coeff(hs, pr)];
                    if rl == 0.0 {
                        continue;
                    }
                    let li = pr * nn + ti;
                    let mut col = at.col_mut(pn);
                    for pc in 0..np {
                        for tj in 0..nl_len {
                            col[crow(tj, pc)] -= rl * bl.w[(li, pc * nl_len + tj)];
                        }
                    }
                    col[pn] -= rl * bl.yc[(li, 0)];
                }
            }
        }
    }
}

/// The block of one harmonic slot's dynamic stiffness with rows `rows` and columns
/// `cols` (field-local DoFs), `np` parts each: entry `(pr·|rows| + a, pc·|cols| + b)` is
/// `z(rows[a], cols[b], pr, pc)`.
fn z_block(
    rows: &[usize],
    cols: &[usize],
    np: usize,
    z: impl Fn(usize, usize, usize, usize) -> f64,
) -> Mat<f64> {
    let (nr, nc) = (rows.len(), cols.len());
    let mut out = Mat::<f64>::zeros(np * nr, np * nc);
    // column by column, without dividing the flat indices into part and DoF
    for pc in 0..np {
        for (b, &cj) in cols.iter().enumerate() {
            let col = out.col_as_slice_mut(pc * nc + b);
            for pr in 0..np {
                for (a, &ri) in rows.iter().enumerate() {
                    col[pr * nr + a] = z(ri, cj, pr, pc);
                }
            }
        }
    }
    out
}

/// A partial-pivoting LU factorization kept in one matrix (unit lower part below the
/// diagonal, upper part on and above it), factored in place: faer's `PartialPivLu` copies
/// the matrix and splits the factors into two new ones, three passes over MB-sized
/// matrices at every Newton iteration.
struct Lu {
    lu: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    /// The factors are those of `Aᵀ` (the matrix was handed over transposed), and solves
    /// are with `A`.
    transposed: bool,
    par: Par,
}

impl Lu {
    fn new(a: Mat<f64>) -> Self {
        Self::factor(a, false, get_global_parallelism())
    }

    /// Factors `a` (or, with `transposed`, keeps the factors of `a` and solves with `aᵀ`)
    /// with parallelism `par`.
    fn factor(mut a: Mat<f64>, transposed: bool, par: Par) -> Self {
        let n = a.nrows();
        let mut perm = vec![0usize; n];
        let mut perm_inv = vec![0usize; n];
        let mut mem = MemBuffer::new(lu_factor::lu_in_place_scratch::<usize, f64>(
            n,
            n,
            par,
            Default::default(),
        ));
        lu_factor::lu_in_place(
            a.as_mut(),
            &mut perm,
            &mut perm_inv,
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        Self {
            lu: a,
            perm,
            perm_inv,
            transposed,
            par,
        }
    }

    /// `A⁻¹ B`.
    fn solve(&self, b: &Mat<f64>) -> Mat<f64> {
        let mut x = b.clone();
        self.solve_in_place(x.as_mut());
        x
    }

    fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let n = self.lu.nrows();
        // a few right-hand sides: a triangular solve of a few hundred unknowns is over
        // before threads could share it (measured: the threads' wake-ups and yields took
        // more time than the solve), and the blocks of Hill's Arnoldi run beside the
        // corrector, which has the other thread
        let par = if rhs.ncols() <= 64 {
            Par::Seq
        } else {
            self.par
        };
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, n);
        // the two scratch sizes are the same (one row permutation of the right-hand sides)
        let mut mem = MemBuffer::new(lu_solve::solve_in_place_scratch::<usize, f64>(
            n,
            rhs.ncols(),
            par,
        ));
        let (l, u, stack) = (self.lu.as_ref(), self.lu.as_ref(), MemStack::new(&mut mem));
        if self.transposed {
            lu_solve::solve_transpose_in_place(l, u, perm, rhs, par, stack);
        } else {
            lu_solve::solve_in_place(l, u, perm, rhs, par, stack);
        }
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Coefficient index of (harmonic slot `hs`, part) with `nh` harmonics: `hs = 0` is the
/// constant, `hs ≥ 1` harmonic `hs − 1` (part 0 cosine, 1 sine).
fn coeff_index(nh: usize, hs: usize, part: usize) -> usize {
    if hs == 0 {
        0
    } else if part == 0 {
        hs
    } else {
        nh + hs
    }
}
