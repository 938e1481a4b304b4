//! Real modal form of a constant state matrix: `A = V Λ V⁻¹` with `V` real and `Λ` real
//! block diagonal (a `1 × 1` block `[λ]` per real eigenvalue, a `2 × 2` block
//! `[[α, β], [−β, α]]` per complex pair `α ± iβ`, whose columns in `V` are the real and
//! imaginary parts of the eigenvector of `α + iβ`).
//!
//! Why: [`super::ExpSip`] propagates every column of the monodromy matrix through
//! `e^{Δ B̄}` once per interval. As a dense product that is `d²` multiply–adds per column
//! and interval, about two thirds of the work on the dual rotor; in modal coordinates
//! `e^{Δ Λ}` is a set of scalings and plane rotations (`≤ 2d`), and the low-rank fluctuation
//! `L D S` becomes `(V⁻¹ L) D (S V)`, a gather and a spread through dense but thin
//! matrices. The product is the same matrix in other coordinates (`V⁻¹ M V`): the
//! multipliers do not change, only the rounding, which `cond(V)` bounds. A matrix whose
//! eigenvector basis is ill-conditioned or not found is refused (`None`), and the caller
//! keeps the dense exponential.

use faer::linalg::solvers::Solve;
use faer::{Mat, MatMut, MatRef};
use num_complex::Complex64;

use super::expm::balance;

/// Largest accepted `cond₁(V)`: rounding in the modal product grows with it, and at `1e6`
/// it stays below `1e-9` of the product's norm, far under the refinement's error estimates.
pub const MAX_CONDITION: f64 = 1e6;

/// A real modal decomposition `A = V Λ V⁻¹` (see the module docs).
#[derive(Clone, Debug)]
pub struct RealModal {
    /// Eigenvector basis `V` (columns scaled to unit 2-norm, pairs jointly).
    pub v: Mat<f64>,
    /// `V⁻¹`.
    pub v_inv: Mat<f64>,
    /// The diagonal blocks of `Λ`.
    blocks: Vec<ModalBlock>,
    /// `‖Ṽ‖₁ ‖Ṽ⁻¹‖₁` of the balanced basis (`V = D Ṽ`, `D` the balancing scales, powers
    /// of two): the factor by which rounding grows in the modal coordinates.
    pub condition: f64,
}

/// One diagonal block of `Λ`, starting at row `row`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ModalBlock {
    Real { row: usize, lambda: f64 },
    Pair { row: usize, re: f64, im: f64 },
}

fn norm1(a: MatRef<'_, f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.col(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

impl RealModal {
    /// The decomposition of the square matrix `a`, or `None` when the eigensolver fails, an
    /// eigenvalue is not finite, the basis has `cond₁(V) > max_condition`, or `V Λ V⁻¹`
    /// does not reproduce `a` to `1e-9` relative (1-norm).
    pub fn new(a: MatRef<'_, f64>, max_condition: f64) -> Option<Self> {
        let d = a.nrows();
        if a.ncols() != d {
            return None;
        }
        if d == 0 {
            return Some(Self {
                v: Mat::zeros(0, 0),
                v_inv: Mat::zeros(0, 0),
                blocks: Vec::new(),
                condition: 1.0,
            });
        }
        // balanced first (a diagonal similarity with powers of two, exact): the state mixes
        // displacements, velocities and temperatures, and unscaled eigenvectors would
        // carry those scales into cond(V)
        let mut balanced = a.to_owned();
        let scale = balance(&mut balanced);
        let eig = faer::linalg::solvers::Eigen::new_from_real(balanced.as_ref()).ok()?;
        let (u, s) = (eig.U(), eig.S());
        let s = s.column_vector();
        let mut v = Mat::<f64>::zeros(d, d);
        let mut blocks = Vec::with_capacity(d);
        let mut col = 0;
        // real eigenvalues first, then the pairs: e^{tΛ} applies as one scaling of the
        // leading rows and rotations of the trailing row pairs
        for pairs in [false, true] {
            for k in 0..d {
                let lam = s[k];
                if !(lam.re.is_finite() && lam.im.is_finite()) {
                    return None;
                }
                if lam.im < 0.0 || (lam.im > 0.0) != pairs {
                    continue; // a conjugate of a pair taken, or not this pass's kind
                }
                let width = if pairs { 2 } else { 1 };
                if col + width > d {
                    return None;
                }
                let norm = (0..d).map(|i| u[(i, k)].norm_sqr()).sum::<f64>().sqrt();
                if !(norm.is_finite() && norm > 0.0) {
                    return None;
                }
                for i in 0..d {
                    v[(i, col)] = u[(i, k)].re / norm;
                    if pairs {
                        v[(i, col + 1)] = u[(i, k)].im / norm;
                    }
                }
                blocks.push(if pairs {
                    ModalBlock::Pair {
                        row: col,
                        re: lam.re,
                        im: lam.im,
                    }
                } else {
                    ModalBlock::Real {
                        row: col,
                        lambda: lam.re,
                    }
                });
                col += width;
            }
        }
        if col != d {
            return None;
        }
        let mut v_inv = v.partial_piv_lu().solve(Mat::<f64>::identity(d, d));
        if v_inv.col_iter().any(|c| c.iter().any(|x| !x.is_finite())) {
            return None;
        }
        let condition = norm1(v.as_ref()) * norm1(v_inv.as_ref());
        if condition.is_nan() || condition > max_condition {
            return None;
        }
        // undo the balancing: A = (D Ṽ) Λ (Ṽ⁻¹ D⁻¹)
        for i in 0..d {
            for j in 0..d {
                v[(i, j)] *= scale[i];
                v_inv[(j, i)] /= scale[i];
            }
        }
        let modal = Self {
            v,
            v_inv,
            blocks,
            condition,
        };
        // A V − V Λ, relative to ‖A‖ ‖V‖
        let mut v_lambda = modal.v.clone();
        modal.apply_right_lambda(v_lambda.as_mut());
        let av = a * &modal.v;
        let residual = norm1((&av - &v_lambda).as_ref());
        let size = norm1(a) * norm1(modal.v.as_ref());
        (residual <= 1e-9 * size.max(f64::MIN_POSITIVE)).then_some(modal)
    }

    /// Dimension of the matrix.
    pub fn dim(&self) -> usize {
        self.v.nrows()
    }

    /// `X ← X Λ` (used for the reconstruction check).
    fn apply_right_lambda(&self, mut x: MatMut<'_, f64>) {
        for b in &self.blocks {
            match *b {
                ModalBlock::Real { row, lambda } => {
                    x.as_mut()
                        .col_mut(row)
                        .iter_mut()
                        .for_each(|v| *v *= lambda);
                }
                ModalBlock::Pair { row, re, im } => {
                    for i in 0..x.nrows() {
                        let (a, b) = (x[(i, row)], x[(i, row + 1)]);
                        x[(i, row)] = re * a - im * b;
                        x[(i, row + 1)] = im * a + re * b;
                    }
                }
            }
        }
    }

    /// `f(Λ)` for a function `f` analytic on the eigenvalues and real on the real axis:
    /// `f(λ)` on a real block, `[[Re f, Im f], [−Im f, Re f]]` at `α + iβ` on a pair block.
    pub fn function(&self, f: impl Fn(Complex64) -> Complex64) -> BlockDiagonal {
        let mut scale = Vec::new();
        let mut rotations = Vec::new();
        for b in &self.blocks {
            match *b {
                ModalBlock::Real { lambda, .. } => {
                    scale.push(f(Complex64::new(lambda, 0.0)).re);
                }
                ModalBlock::Pair { re, im, .. } => {
                    let v = f(Complex64::new(re, im));
                    rotations.push([v.re, -v.im, v.im, v.re]);
                }
            }
        }
        BlockDiagonal { scale, rotations }
    }

    /// `e^{tΛ}` as scalings and plane rotations.
    pub fn exp(&self, t: f64) -> BlockDiagonal {
        self.function(|z| (z * t).exp())
    }
}

/// A real block-diagonal matrix such as `e^{tΛ}`: `1 × 1` blocks on the leading rows, then
/// `2 × 2` blocks on consecutive row pairs.
#[derive(Clone, Debug)]
pub struct BlockDiagonal {
    /// The `1 × 1` blocks (rows `0..scale.len()`).
    scale: Vec<f64>,
    /// The `2 × 2` blocks by columns, `[e₁₁, e₂₁, e₁₂, e₂₂]`, row pairs after the
    /// scalings (by columns so that a block's product is two 2-lane multiply–adds).
    rotations: Vec<[f64; 4]>,
}

impl BlockDiagonal {
    /// Dimension of the matrix.
    pub fn dim(&self) -> usize {
        self.scale.len() + 2 * self.rotations.len()
    }

    /// `X ← E X` for `x` with `dim` rows.
    pub fn apply(&self, mut x: MatMut<'_, f64>) {
        debug_assert_eq!(x.nrows(), self.dim());
        let nr = self.scale.len();
        for j in 0..x.ncols() {
            let Some(c) = x.as_mut().col_mut(j).try_as_col_major_mut() else {
                // strided rows: entry by entry
                let mut c = x.as_mut().col_mut(j);
                for (i, e) in self.scale.iter().enumerate() {
                    c[i] *= e;
                }
                for (k, e) in self.rotations.iter().enumerate() {
                    let (a, b) = (c[nr + 2 * k], c[nr + 2 * k + 1]);
                    c[nr + 2 * k] = e[0] * a + e[2] * b;
                    c[nr + 2 * k + 1] = e[1] * a + e[3] * b;
                }
                continue;
            };
            let c = c.as_slice_mut();
            let (real, pairs) = c.split_at_mut(nr);
            real.iter_mut().zip(&self.scale).for_each(|(v, e)| *v *= e);
            for (p, e) in pairs.chunks_exact_mut(2).zip(&self.rotations) {
                let (a, b) = (p[0], p[1]);
                p[0] = e[0] * a + e[2] * b;
                p[1] = e[1] * a + e[3] * b;
            }
        }
    }

    /// `X ← E X` for `x` stored by rows of `W` columns each (the panels of the
    /// exponential-split product), `dim` rows.
    pub fn apply_rows<const W: usize>(&self, x: &mut [[f64; W]]) {
        debug_assert_eq!(x.len(), self.dim());
        let (real, pairs) = x.split_at_mut(self.scale.len());
        for (row, &e) in real.iter_mut().zip(&self.scale) {
            row.iter_mut().for_each(|v| *v *= e);
        }
        for (p, e) in pairs.chunks_exact_mut(2).zip(&self.rotations) {
            let (a, b) = (p[0], p[1]);
            for l in 0..W {
                p[0][l] = e[0] * a[l] + e[2] * b[l];
                p[1][l] = e[1] * a[l] + e[3] * b[l];
            }
        }
    }

    /// The matrix as a dense one.
    pub fn to_dense(&self) -> Mat<f64> {
        let mut m = Mat::zeros(self.dim(), self.dim());
        self.columns_into(0, m.as_mut());
        m
    }

    /// Columns `c0..c0 + out.ncols()` of the matrix, written into `out` (`dim` rows).
    pub fn columns_into(&self, c0: usize, mut out: MatMut<'_, f64>) {
        out.fill(0.0);
        let c1 = c0 + out.ncols();
        let nr = self.scale.len();
        for (i, &e) in self.scale.iter().enumerate() {
            if (c0..c1).contains(&i) {
                out[(i, i - c0)] = e;
            }
        }
        for (k, e) in self.rotations.iter().enumerate() {
            let row = nr + 2 * k;
            for dc in 0..2 {
                let j = row + dc;
                if (c0..c1).contains(&j) {
                    for dr in 0..2 {
                        out[(row + dr, j - c0)] = e[dc * 2 + dr];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stability::expm;

    fn max_abs_diff(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
        (0..a.nrows())
            .flat_map(|i| (0..a.ncols()).map(move |j| (i, j)))
            .map(|(i, j)| (a[(i, j)] - b[(i, j)]).abs())
            .fold(0.0, f64::max)
    }

    /// A damped, gyroscopically coupled 3-DoF oscillator in first-order form (complex
    /// pairs) next to two real decays.
    fn test_matrix() -> Mat<f64> {
        let n = 3;
        let k = [[4.0, -1.0, 0.0], [-1.0, 3.0, -0.5], [0.0, -0.5, 2.0]];
        let c = [[0.1, 0.3, 0.0], [-0.3, 0.2, 0.0], [0.0, 0.0, 0.05]];
        let d = 2 * n + 2;
        let mut a = Mat::<f64>::zeros(d, d);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                a[(n + i, j)] = -k[i][j];
                a[(n + i, n + j)] = -c[i][j];
            }
        }
        a[(6, 6)] = -0.7;
        a[(7, 7)] = -0.02;
        a[(6, 7)] = 0.1;
        a[(0, 6)] = 0.2; // a coupling that keeps the matrix non-normal
        a
    }

    #[test]
    fn the_modal_exponential_equals_the_pade_exponential() {
        let a = test_matrix();
        let modal = RealModal::new(a.as_ref(), MAX_CONDITION).expect("diagonalisable");
        assert!(modal.condition < 1e3, "cond {}", modal.condition);
        for t in [1e-3, 0.37, 2.0] {
            let scaled = Mat::from_fn(a.nrows(), a.ncols(), |i, j| t * a[(i, j)]);
            let reference = expm(&scaled).expect("expm");
            // V e^{tΛ} V⁻¹
            let mut e = Mat::<f64>::zeros(a.nrows(), a.ncols());
            modal.exp(t).columns_into(0, e.as_mut());
            let got = &modal.v * &e * &modal.v_inv;
            assert!(
                max_abs_diff(got.as_ref(), reference.as_ref()) < 1e-12,
                "t = {t}"
            );
            // apply() agrees with the dense block matrix
            let x = Mat::from_fn(a.nrows(), 3, |i, j| (i as f64 + 1.0) * (j as f64 - 0.5));
            let mut y = x.clone();
            modal.exp(t).apply(y.as_mut());
            assert!(max_abs_diff(y.as_ref(), (&e * &x).as_ref()) < 1e-14);
            // …also on rows that are not contiguous (a transposed view)
            let mut yt = x.transpose().to_owned();
            modal.exp(t).apply(yt.as_mut().transpose_mut());
            assert!(max_abs_diff(yt.transpose(), (&e * &x).as_ref()) < 1e-14);
        }
    }

    #[test]
    fn a_defective_matrix_is_refused() {
        // a Jordan block: no basis of eigenvectors
        let mut a = Mat::<f64>::zeros(2, 2);
        a[(0, 0)] = -1.0;
        a[(1, 1)] = -1.0;
        a[(0, 1)] = 1.0;
        assert!(RealModal::new(a.as_ref(), MAX_CONDITION).is_none());
    }
}
