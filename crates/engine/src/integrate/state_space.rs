//! First-order form of a [`System`] at one value of `ω`, and its linearisation.
//!
//! The state is `y = [x, v, T]` (length `d = 2 n_mech + n_therm`), `v = ẋ`:
//!
//! ```text
//!   ẋ = v
//!   v̇ = M⁻¹ (F(t) − C v − K x − P f(x_P, v_P, T_Q, t))
//!   Ṫ = C_T⁻¹ (F_T − K_T T − Q g(x_P, v_P, T_Q, t))
//! ```
//!
//! where `P`, `Q` scatter the nonlinear terms onto their DoFs. `M` and `C_T` are factored
//! once (partial-pivot LU, faer) when the [`StateSpace`] is built, and the products
//! `M⁻¹K`, `M⁻¹C`, `C_T⁻¹K_T`, the columns `M⁻¹P`, `C_T⁻¹Q` and `C_T⁻¹F_T` are formed
//! then, so that a right-hand side costs only matrix–vector products.
//!
//! The linearisation around a solution (paper Eq. 30, written in physical time) is
//! `δẏ = B(t) δy` with
//!
//! ```text
//!          ⎡ 0                           I                           0                         ⎤
//!   B(t) = ⎢ −M⁻¹(K + P ∂f/∂x Pᵀ)        −M⁻¹(C + P ∂f/∂v Pᵀ)        −M⁻¹ P ∂f/∂T Qᵀ           ⎥
//!          ⎣ −C_T⁻¹ Q ∂g/∂x Pᵀ           −C_T⁻¹ Q ∂g/∂v Pᵀ           −C_T⁻¹(K_T + Q ∂g/∂T Qᵀ)  ⎦
//! ```
//!
//! `B(t) = B_lin + L D(t) S`: a constant part plus a part of rank at most `p + q` (`p`, `q`
//! nonlinear mechanical and thermal DoFs) that reads only the rows `x_P`, `v_P`, `T_Q` of
//! its operand (`S`), mixes them with the pointwise derivatives (`D`) and spreads them with
//! the columns `L = [0; M⁻¹P; C_T⁻¹Q]`. [`StateSpace::apply_linearization`] applies `B` to
//! a block of columns in this factored form and never forms `B`: its cost per column is
//! `2 n_mech² + n_therm²` multiply–adds (the identity block is a copy) plus `O((p+q)·d)`,
//! against `d²` for a dense product.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};

use super::IntegrateError;
use crate::system::{DenseMatrix, NonlinearDofs, NonlinearEval, System};

/// The first-order form of a [`System`] at one `ω` (see the module docs).
#[derive(Clone)]
pub struct StateSpace<'a> {
    system: &'a dyn System,
    omega: f64,
    n: usize,
    m: usize,
    dofs: NonlinearDofs,
    /// `M⁻¹` (n × n), applied to the load.
    minv: Mat<f64>,
    /// `M⁻¹K` (n × n).
    minv_k: Mat<f64>,
    /// `M⁻¹C` (n × n).
    minv_c: Mat<f64>,
    /// `[M⁻¹K, M⁻¹C]` side by side (n × 2n): one product with the rows `[x; v]`.
    minv_kc: Mat<f64>,
    /// Columns of `M⁻¹` at the nonlinear mechanical DoFs (n × p).
    minv_p: Mat<f64>,
    /// `C_T⁻¹K_T` (m × m).
    ctinv_kt: Mat<f64>,
    /// Columns of `C_T⁻¹` at the nonlinear thermal DoFs (m × q).
    ctinv_q: Mat<f64>,
    /// `C_T⁻¹F_T` (m).
    ctinv_ft: Vec<f64>,
    /// Whether `S` gathers the velocity rows `v_P` (default); see
    /// [`StateSpace::with_velocity_gather`].
    velocity: bool,
}

/// Scratch buffers for [`StateSpace`] evaluations; one per thread.
pub struct Workspace {
    force: Vec<f64>,
    xp: Vec<f64>,
    vp: Vec<f64>,
    tq: Vec<f64>,
    /// Pointwise nonlinear values and derivatives at the last evaluation.
    pub eval: NonlinearEval,
    gathered: Mat<f64>,
    mixed: Mat<f64>,
    d_mat: Mat<f64>,
}

fn to_faer(a: &DenseMatrix) -> Mat<f64> {
    Mat::from_fn(a.n, a.n, |i, j| a.get(i, j))
}

/// Solves `A X = B` for `X` with a partial-pivot LU of `A`; `what` names `A` in errors.
fn solve(a: &Mat<f64>, b: Mat<f64>, what: &'static str) -> Result<Mat<f64>, IntegrateError> {
    use faer::linalg::solvers::Solve;
    if a.nrows() == 0 {
        return Ok(b);
    }
    let lu = a.partial_piv_lu();
    let x = lu.solve(b);
    if x.col_iter().flat_map(|c| c.iter()).any(|v| !v.is_finite()) {
        return Err(IntegrateError::Singular { matrix: what });
    }
    Ok(x)
}

impl<'a> StateSpace<'a> {
    /// Builds the first-order form of `system` at `omega` (rad/s), factoring `M` and `C_T`.
    pub fn new(system: &'a dyn System, omega: f64) -> Result<Self, IntegrateError> {
        let n = system.n_mech();
        let m = system.n_therm();
        let lin = system.linear(omega);
        let dofs = system.nonlinear_dofs().clone();
        for (what, mat, size) in [
            ("mass", &lin.mass, n),
            ("damping", &lin.damping, n),
            ("stiffness", &lin.stiffness, n),
            ("thermal_capacity", &lin.thermal_capacity, m),
            ("thermal_conductance", &lin.thermal_conductance, m),
        ] {
            if mat.n != size || mat.data.len() != size * size {
                return Err(IntegrateError::Dimension {
                    what,
                    expected: size,
                    found: mat.n,
                });
            }
        }
        if let Some(&bad) = dofs.mech.iter().find(|&&i| i >= n) {
            return Err(IntegrateError::Dimension {
                what: "nonlinear mechanical DoF index",
                expected: n,
                found: bad,
            });
        }
        if let Some(&bad) = dofs.therm.iter().find(|&&i| i >= m) {
            return Err(IntegrateError::Dimension {
                what: "nonlinear thermal DoF index",
                expected: m,
                found: bad,
            });
        }
        let mass = to_faer(&lin.mass);
        let minv = solve(&mass, Mat::identity(n, n), "mass")?;
        let minv_k = &minv * to_faer(&lin.stiffness);
        let minv_c = &minv * to_faer(&lin.damping);
        let minv_p = Mat::from_fn(n, dofs.mech.len(), |i, j| minv[(i, dofs.mech[j])]);
        let minv_kc = Mat::from_fn(n, 2 * n, |i, j| {
            if j < n {
                minv_k[(i, j)]
            } else {
                minv_c[(i, j - n)]
            }
        });
        let cap = to_faer(&lin.thermal_capacity);
        let ctinv = solve(&cap, Mat::identity(m, m), "thermal_capacity")?;
        let ctinv_kt = &ctinv * to_faer(&lin.thermal_conductance);
        let ctinv_q = Mat::from_fn(m, dofs.therm.len(), |i, j| ctinv[(i, dofs.therm[j])]);
        let mut ft = vec![0.0; m];
        system.thermal_load(omega, &mut ft);
        let ctinv_ft = (0..m)
            .map(|i| (0..m).map(|j| ctinv[(i, j)] * ft[j]).sum())
            .collect();
        Ok(Self {
            system,
            omega,
            n,
            m,
            dofs,
            minv,
            minv_k,
            minv_c,
            minv_kc,
            minv_p,
            ctinv_kt,
            ctinv_q,
            ctinv_ft,
            velocity: true,
        })
    }

    /// The same state space with (`on`) or without the velocity rows `v_P` in the gather
    /// `S`, and the columns `∂f/∂v`, `∂g/∂v` in the derivative matrix `D`. Without them
    /// `S` reads `[x_P, T_Q]` (`p + q` rows instead of `2p + q`): exact for derivatives
    /// whose `∂f/∂v` and `∂g/∂v` vanish, which are then not read. The dual rotor's forces
    /// (Hertz contacts, heat sources) do not depend on velocities, so its Floquet products
    /// gather 36 rows instead of 46 (see the exponential-split product, `stability::ExpSip`).
    pub fn with_velocity_gather(&self, on: bool) -> Self {
        Self {
            velocity: on,
            ..self.clone()
        }
    }

    /// Whether the gather reads the velocity rows (see [`Self::with_velocity_gather`]).
    pub fn gathers_velocity(&self) -> bool {
        self.velocity
    }

    /// The system this state space was built from.
    pub fn system(&self) -> &'a dyn System {
        self.system
    }

    /// Continuation parameter `ω` (rad/s).
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Number of mechanical DoFs.
    pub fn n_mech(&self) -> usize {
        self.n
    }

    /// Number of thermal DoFs.
    pub fn n_therm(&self) -> usize {
        self.m
    }

    /// State dimension `2 n_mech + n_therm`.
    pub fn dim(&self) -> usize {
        2 * self.n + self.m
    }

    /// The nonlinear DoFs.
    pub fn dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }

    /// `M⁻¹K`, `M⁻¹C`, `C_T⁻¹K_T` (for norm estimates).
    pub fn linear_blocks(&self) -> (MatRef<'_, f64>, MatRef<'_, f64>, MatRef<'_, f64>) {
        (
            self.minv_k.as_ref(),
            self.minv_c.as_ref(),
            self.ctinv_kt.as_ref(),
        )
    }

    /// Columns `M⁻¹P` (n × p) and `C_T⁻¹Q` (m × q) that spread nonlinear terms.
    pub fn spread_columns(&self) -> (MatRef<'_, f64>, MatRef<'_, f64>) {
        (self.minv_p.as_ref(), self.ctinv_q.as_ref())
    }

    /// Scratch buffers sized for this state space.
    pub fn workspace(&self) -> Workspace {
        let p = self.dofs.mech.len();
        let q = self.dofs.therm.len();
        let (g, r) = self.low_rank_dims();
        Workspace {
            force: vec![0.0; self.n],
            xp: vec![0.0; p],
            vp: vec![0.0; p],
            tq: vec![0.0; q],
            eval: NonlinearEval::new(p, q),
            gathered: Mat::zeros(g, 0),
            mixed: Mat::zeros(r, 0),
            d_mat: Mat::zeros(r, g),
        }
    }

    /// Evaluates the nonlinear terms and derivatives at time `t` for the full state
    /// `x`, `v`, `temp` into `ws.eval`.
    pub fn eval_nonlinear_at(
        &self,
        t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        ws: &mut Workspace,
    ) {
        for (k, &i) in self.dofs.mech.iter().enumerate() {
            ws.xp[k] = x[i];
            ws.vp[k] = v[i];
        }
        for (k, &i) in self.dofs.therm.iter().enumerate() {
            ws.tq[k] = temp[i];
        }
        self.system
            .eval_nonlinear(self.omega, t, &ws.xp, &ws.vp, &ws.tq, &mut ws.eval);
    }

    /// [`Self::eval_nonlinear_at`] from the nonlinear DoFs' values alone (`x_P`, `v_P`,
    /// `T_Q`, in the order of [`Self::dofs`]).
    pub fn eval_nonlinear_gathered(
        &self,
        t: f64,
        xp: &[f64],
        vp: &[f64],
        tq: &[f64],
        ws: &mut Workspace,
    ) {
        self.system
            .eval_nonlinear(self.omega, t, xp, vp, tq, &mut ws.eval);
    }

    /// Right-hand side `ẏ = φ(t, y)` of the first-order equations.
    pub fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64], ws: &mut Workspace) {
        let (n, m) = (self.n, self.m);
        let (x, rest) = y.split_at(n);
        let (v, temp) = rest.split_at(n);
        self.eval_nonlinear_at(t, x, v, temp, ws);
        self.system.forcing(self.omega, t, &mut ws.force);
        let (dx, drest) = dy.split_at_mut(n);
        let (dv, dtemp) = drest.split_at_mut(n);
        dx.copy_from_slice(v);
        dv.iter_mut().for_each(|a| *a = 0.0);
        for j in 0..n {
            let (fj, xj, vj) = (ws.force[j], x[j], v[j]);
            let (cm, ck, cc) = (self.minv.col(j), self.minv_k.col(j), self.minv_c.col(j));
            for i in 0..n {
                dv[i] += cm[i] * fj - ck[i] * xj - cc[i] * vj;
            }
        }
        for (k, &fk) in ws.eval.f.iter().enumerate() {
            let col = self.minv_p.col(k);
            for i in 0..n {
                dv[i] -= col[i] * fk;
            }
        }
        dtemp.copy_from_slice(&self.ctinv_ft);
        for j in 0..m {
            let (col, tj) = (self.ctinv_kt.col(j), temp[j]);
            for i in 0..m {
                dtemp[i] -= col[i] * tj;
            }
        }
        for (k, &gk) in ws.eval.g.iter().enumerate() {
            let col = self.ctinv_q.col(k);
            for i in 0..m {
                dtemp[i] -= col[i] * gk;
            }
        }
    }

    /// Number of rows `S` gathers (`2p + q`: `x_P`, `v_P`, `T_Q`; `p + q` without the
    /// velocity rows) and of columns `L` spreads (`p + q`).
    pub fn low_rank_dims(&self) -> (usize, usize) {
        let (p, q) = (self.dofs.mech.len(), self.dofs.therm.len());
        (self.mech_gathered() + q, p + q)
    }

    /// Number of mechanical rows `S` gathers: `2p`, or `p` without the velocity rows.
    fn mech_gathered(&self) -> usize {
        let p = self.dofs.mech.len();
        if self.velocity { 2 * p } else { p }
    }

    /// The pointwise derivative matrix
    /// `D = [[∂f/∂x, ∂f/∂v, ∂f/∂T], [∂g/∂x, ∂g/∂v, ∂g/∂T]]`, `(p+q) × (2p+q)`, into `out`
    /// (without the `∂/∂v` columns when the gather has no velocity rows).
    pub fn derivative_matrix(&self, derivs: &NonlinearEval, mut out: MatMut<'_, f64>) {
        self.for_each_derivative(derivs, |i, j, v| out[(i, j)] = v);
    }

    /// The nonzero entries `(row, column, value)` of [`Self::derivative_matrix`], into
    /// `out` (cleared first), ordered by row within each derivative block.
    pub fn derivative_nonzeros(&self, derivs: &NonlinearEval, out: &mut Vec<(usize, usize, f64)>) {
        out.clear();
        self.for_each_derivative(derivs, |i, j, v| {
            if v != 0.0 {
                out.push((i, j, v));
            }
        });
    }

    /// Calls `put(row, column, value)` for every entry of [`Self::derivative_matrix`].
    fn for_each_derivative(&self, derivs: &NonlinearEval, mut put: impl FnMut(usize, usize, f64)) {
        let blocks = derivs.derivative_blocks();
        self.for_each_derivative_slot(|b, k, i, j| put(i, j, blocks[b][k]));
    }

    /// Calls `put(block, index, row, column)` for every entry of
    /// [`Self::derivative_matrix`]: entry `index` of derivative array `block`
    /// ([`NonlinearEval::derivative_blocks`] order) sits at `(row, column)` of `D`. The
    /// order is that of [`Self::derivative_nonzeros`]: by row within each derivative block,
    /// `∂/∂x` and `∂/∂v` of one variable side by side; without the velocity gather the
    /// `∂/∂v` entries are left out.
    pub fn for_each_derivative_slot(&self, mut put: impl FnMut(usize, usize, usize, usize)) {
        let (p, q) = (self.dofs.mech.len(), self.dofs.therm.len());
        let t0 = self.mech_gathered();
        for i in 0..p {
            for j in 0..p {
                put(0, i * p + j, i, j);
                if self.velocity {
                    put(1, i * p + j, i, p + j);
                }
            }
            for j in 0..q {
                put(2, i * q + j, i, t0 + j);
            }
        }
        for i in 0..q {
            for j in 0..p {
                put(3, i * p + j, p + i, j);
                if self.velocity {
                    put(4, i * p + j, p + i, p + j);
                }
            }
            for j in 0..q {
                put(5, i * q + j, p + i, t0 + j);
            }
        }
    }

    /// `out = S W`: the rows `x_P`, `v_P` (unless left out), `T_Q` of `w` (`d × c` →
    /// `(2p+q) × c`, or `(p+q) × c`).
    pub fn gather(&self, w: MatRef<'_, f64>, mut out: MatMut<'_, f64>) {
        let n = self.n;
        let p = self.dofs.mech.len();
        let t0 = self.mech_gathered();
        for col in 0..w.ncols() {
            let wc = w.col(col);
            for (k, &i) in self.dofs.mech.iter().enumerate() {
                out[(k, col)] = wc[i];
                if self.velocity {
                    out[(p + k, col)] = wc[n + i];
                }
            }
            for (k, &i) in self.dofs.therm.iter().enumerate() {
                out[(t0 + k, col)] = wc[2 * n + i];
            }
        }
    }

    /// `out += L Y` for `y` (`(p+q) × c`), `L = −[0; M⁻¹P, 0; 0, C_T⁻¹Q]` the columns that
    /// spread the nonlinear terms (`out` is `d × c`).
    pub fn spread_add(&self, y: MatRef<'_, f64>, out: MatMut<'_, f64>) {
        let n = self.n;
        let (p, q) = (self.dofs.mech.len(), self.dofs.therm.len());
        let (_, orest) = out.split_at_row_mut(n);
        let (ov, ot) = orest.split_at_row_mut(n);
        if p > 0 {
            matmul(
                ov,
                Accum::Add,
                self.minv_p.as_ref(),
                y.subrows(0, p),
                -1.0,
                Par::Seq,
            );
        }
        if q > 0 {
            matmul(
                ot,
                Accum::Add,
                self.ctinv_q.as_ref(),
                y.subrows(p, q),
                -1.0,
                Par::Seq,
            );
        }
    }

    /// `K = S L` (`g × (p+q)`, `g` the gathered rows): the gathered rows of the spreading columns, so that
    /// `(L D S)ⁱ = L (D K)^{i−1} D S`.
    pub fn gather_of_spread(&self) -> Mat<f64> {
        let (g, r) = self.low_rank_dims();
        let mut k = Mat::<f64>::zeros(g, r);
        self.gather(self.spread_matrix().as_ref(), k.as_mut());
        k
    }

    /// `S` as a dense `g × d` selection matrix (see [`Self::gather`]).
    pub fn gather_matrix(&self) -> Mat<f64> {
        let (g, _) = self.low_rank_dims();
        let d = self.dim();
        let mut s = Mat::<f64>::zeros(g, d);
        self.gather(Mat::<f64>::identity(d, d).as_ref(), s.as_mut());
        s
    }

    /// `L` as a dense `d × (p+q)` matrix (see [`Self::spread_add`]).
    pub fn spread_matrix(&self) -> Mat<f64> {
        let (_, r) = self.low_rank_dims();
        let mut l = Mat::<f64>::zeros(self.dim(), r);
        self.spread_add(Mat::<f64>::identity(r, r).as_ref(), l.as_mut());
        l
    }

    /// `ws.mixed = D S W` for the derivatives in `derivs` (see the module docs).
    fn mix(&self, derivs: &NonlinearEval, w: MatRef<'_, f64>, ws: &mut Workspace) {
        let c = w.ncols();
        self.derivative_matrix(derivs, ws.d_mat.as_mut());
        let (g, r) = self.low_rank_dims();
        if ws.gathered.ncols() != c {
            ws.gathered = Mat::zeros(g, c);
            ws.mixed = Mat::zeros(r, c);
        }
        self.gather(w, ws.gathered.as_mut());
        if r > 0 {
            matmul(
                ws.mixed.as_mut(),
                Accum::Replace,
                ws.d_mat.as_ref(),
                ws.gathered.as_ref(),
                1.0,
                Par::Seq,
            );
        }
    }

    /// `out = L D S W`: only the part of `B` that the nonlinear terms contribute (the
    /// low-rank term of the module docs), for derivatives `derivs`. `w`, `out` are `d × c`.
    pub fn apply_nonlinear_part(
        &self,
        derivs: &NonlinearEval,
        w: MatRef<'_, f64>,
        mut out: MatMut<'_, f64>,
        ws: &mut Workspace,
    ) {
        self.mix(derivs, w, ws);
        out.fill(0.0);
        self.spread_add(ws.mixed.as_ref(), out);
    }

    /// `out = B W` (or `out += alpha·B W` with `accumulate`), with `B` built from the
    /// derivatives in `derivs` (see the module docs). `w` and `out` are `d × c`.
    pub fn apply_linearization(
        &self,
        derivs: &NonlinearEval,
        w: MatRef<'_, f64>,
        out: MatMut<'_, f64>,
        ws: &mut Workspace,
    ) {
        let (n, m) = (self.n, self.m);
        let (p, q) = (self.dofs.mech.len(), self.dofs.therm.len());
        self.mix(derivs, w, ws);
        let (wxv, wt) = w.split_at_row(2 * n);
        let wv = wxv.subrows(n, n);
        let (mut ox, orest) = out.split_at_row_mut(n);
        let (mut ov, mut ot) = orest.split_at_row_mut(n);
        ox.copy_from(wv);
        matmul(
            ov.as_mut(),
            Accum::Replace,
            self.minv_kc.as_ref(),
            wxv,
            -1.0,
            Par::Seq,
        );
        if p > 0 {
            matmul(
                ov.as_mut(),
                Accum::Add,
                self.minv_p.as_ref(),
                ws.mixed.as_ref().subrows(0, p),
                -1.0,
                Par::Seq,
            );
        }
        if m > 0 {
            matmul(
                ot.as_mut(),
                Accum::Replace,
                self.ctinv_kt.as_ref(),
                wt,
                -1.0,
                Par::Seq,
            );
            if q > 0 {
                matmul(
                    ot.as_mut(),
                    Accum::Add,
                    self.ctinv_q.as_ref(),
                    ws.mixed.as_ref().subrows(p, q),
                    -1.0,
                    Par::Seq,
                );
            }
        }
    }

    /// The dense state matrix `B` for the derivatives in `derivs` (tests, small systems).
    pub fn linearization_dense(&self, derivs: &NonlinearEval, ws: &mut Workspace) -> Mat<f64> {
        let d = self.dim();
        let mut out = Mat::zeros(d, d);
        self.apply_linearization(
            derivs,
            Mat::<f64>::identity(d, d).as_ref(),
            out.as_mut(),
            ws,
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::chain::Chain;

    #[test]
    fn derivative_matrix_places_every_block() {
        let sys = Chain::new(5, 3);
        let space = StateSpace::new(&sys, 0.9).expect("state space");
        let (p, q) = (space.dofs().mech.len(), space.dofs().therm.len());
        assert!(p > 0 && q > 0, "both fields nonlinear");
        // distinct entries, so that a misplaced one shows
        let mut d = NonlinearEval::new(p, q);
        for (k, buf) in [
            &mut d.df_dx,
            &mut d.df_dv,
            &mut d.df_dt,
            &mut d.dg_dx,
            &mut d.dg_dv,
            &mut d.dg_dt,
        ]
        .into_iter()
        .enumerate()
        {
            for (i, v) in buf.iter_mut().enumerate() {
                *v = (1000 * (k + 1) + i) as f64;
            }
        }
        let (g, r) = space.low_rank_dims();
        let mut m = Mat::<f64>::zeros(r, g);
        space.derivative_matrix(&d, m.as_mut());
        // the same through a row-major (strided) view
        let mut t = Mat::<f64>::zeros(g, r);
        space.derivative_matrix(&d, t.as_mut().transpose_mut());
        for i in 0..r {
            for j in 0..g {
                let want = match (i < p, j) {
                    (true, j) if j < p => d.df_dx[i * p + j],
                    (true, j) if j < 2 * p => d.df_dv[i * p + j - p],
                    (true, j) => d.df_dt[i * q + j - 2 * p],
                    (false, j) if j < p => d.dg_dx[(i - p) * p + j],
                    (false, j) if j < 2 * p => d.dg_dv[(i - p) * p + j - p],
                    (false, j) => d.dg_dt[(i - p) * q + j - 2 * p],
                };
                assert_eq!(m[(i, j)], want, "({i}, {j})");
                assert_eq!(t[(j, i)], want, "strided ({i}, {j})");
            }
        }
        // the nonzero list: every nonzero entry once, in its place; zeros left out
        d.df_dv.iter_mut().for_each(|v| *v = 0.0);
        d.dg_dx[0] = 0.0;
        space.derivative_matrix(&d, m.as_mut());
        let mut nonzeros = Vec::new();
        space.derivative_nonzeros(&d, &mut nonzeros);
        let mut rebuilt = Mat::<f64>::zeros(r, g);
        for &(i, j, v) in &nonzeros {
            assert_ne!(v, 0.0, "({i}, {j}) listed with a zero");
            assert_eq!(rebuilt[(i, j)], 0.0, "({i}, {j}) listed twice");
            rebuilt[(i, j)] = v;
        }
        assert_eq!(rebuilt, m);
        let zeros = (0..r)
            .flat_map(|i| (0..g).map(move |j| (i, j)))
            .filter(|&(i, j)| m[(i, j)] == 0.0)
            .count();
        assert_eq!(nonzeros.len() + zeros, r * g);
        assert!(zeros > p * p, "the zeroed entries are left out");
    }

    /// Without velocity derivatives, the state matrix applied through the gather without
    /// the velocity rows equals the one through the full gather, and equals the dense
    /// product `B_lin W + L D S W` assembled from the blocks.
    #[test]
    fn the_gather_without_velocity_rows_gives_the_same_linearization() {
        let sys = Chain::new(5, 3);
        let full = StateSpace::new(&sys, 0.9).expect("state space");
        let lean = full.with_velocity_gather(false);
        assert!(full.gathers_velocity() && !lean.gathers_velocity());
        let (p, q) = (full.dofs().mech.len(), full.dofs().therm.len());
        assert_eq!(full.low_rank_dims(), (2 * p + q, p + q));
        assert_eq!(lean.low_rank_dims(), (p + q, p + q));
        let mut d = NonlinearEval::new(p, q);
        for (k, buf) in [&mut d.df_dx, &mut d.df_dt, &mut d.dg_dx, &mut d.dg_dt]
            .into_iter()
            .enumerate()
        {
            for (i, v) in buf.iter_mut().enumerate() {
                *v = ((3 * k + 7 * i) % 11) as f64 - 5.0;
            }
        }
        let dim = full.dim();
        let w = Mat::from_fn(dim, 4, |i, j| ((i * 5 + j * 3) % 7) as f64 - 3.0);
        let (mut a, mut b) = (Mat::<f64>::zeros(dim, 4), Mat::<f64>::zeros(dim, 4));
        let mut ws = full.workspace();
        full.apply_linearization(&d, w.as_ref(), a.as_mut(), &mut ws);
        let mut ws = lean.workspace();
        lean.apply_linearization(&d, w.as_ref(), b.as_mut(), &mut ws);
        assert_eq!(a, b);
        // S, D and L of the lean form rebuild the low-rank part
        let (g, r) = lean.low_rank_dims();
        let mut dm = Mat::<f64>::zeros(r, g);
        lean.derivative_matrix(&d, dm.as_mut());
        let low_rank = lean.spread_matrix() * &dm * lean.gather_matrix() * &w;
        let mut nl = Mat::<f64>::zeros(dim, 4);
        lean.apply_nonlinear_part(&d, w.as_ref(), nl.as_mut(), &mut ws);
        for i in 0..dim {
            for j in 0..4 {
                assert!((low_rank[(i, j)] - nl[(i, j)]).abs() <= 1e-12 * (1.0 + nl[(i, j)].abs()));
            }
        }
        // T_Q sits right after x_P
        let s = lean.gather_matrix();
        let n = sys.n_mech();
        for (k, &i) in lean.dofs().therm.iter().enumerate() {
            assert_eq!(s[(p + k, 2 * n + i)], 1.0);
        }
    }
}
