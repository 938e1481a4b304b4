//! Harmonic-balance residual and its exact Jacobian (paper Eq. 25–28).
//!
//! Unknowns `A`: the coefficients of every DoF, mechanical DoFs `0..n_mech` first, then
//! thermal DoFs, each with the basis layout `[a_0, a_1..a_H, b_1..b_H]`; DoF `d`'s block
//! starts at `d·(1+2H)`. The residual is the Galerkin projection of the equations of
//! motion onto the basis,
//!
//! ```text
//!   R(A, ω) = Z(ω) A + P[f(x, ẋ, T, t)] − P[F(t)]
//! ```
//!
//! where `P` is the AFT projection and `Z(ω)` the linear dynamic stiffness (Eq. 27), block
//! diagonal in the harmonics: for harmonic `h` with `w = ν_h ω` and a mechanical DoF pair
//! the block acting on `(a_h, b_h)` is `[[K − w² M, w C], [−w C, K − w² M]]`; thermal DoFs
//! have `M = 0`, `C = C_T`, `K = K_T`; the constant term sees `K` (or `K_T`) alone.
//! The Jacobian `∂R/∂A = Z + J_nl` has its nonlinear part `J_nl` only on the nonlinear
//! DoFs; it is assembled from the AFT of the pointwise derivatives `∂f/∂x`, `∂f/∂ẋ`,
//! `∂f/∂T`, `∂g/∂…` ([`Aft::add_product_block`]) and is exact for the discrete residual.
//! `∂R/∂ω` is a central finite difference in `ω` (the system's matrices and forces may
//! depend on `ω` in ways the engine does not know).

use num_complex::Complex64;
use rayon::prelude::*;
use thiserror::Error;

use super::aft::{Aft, AftError, Signal};
use super::basis::Basis;
use super::events::{EventNodes, PanelRule, Row, illinois, push_phases};
use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Errors of the harmonic-balance layer.
#[derive(Debug, Error)]
pub enum HbError {
    #[error(transparent)]
    Aft(#[from] AftError),
    #[error("{what} has length/size {got}, expected {expected}")]
    Dimension {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("nonlinear {field} DoF index {index} is out of range (the system has {n})")]
    NonlinearDofOutOfRange {
        field: &'static str,
        index: usize,
        n: usize,
    },
    #[error("nonlinear {field} DoF indices are not sorted and unique: {indices:?}")]
    NonlinearDofOrder {
        field: &'static str,
        indices: Vec<usize>,
    },
    #[error("{field} DoF index {index} is out of range (the system has {n})")]
    DofOutOfRange {
        field: &'static str,
        index: usize,
        n: usize,
    },
    #[error("non-finite {what} at ω = {omega} rad/s")]
    NonFinite { what: &'static str, omega: f64 },
}

/// Which derivative array of a pointwise evaluation a Jacobian block is built from.
#[derive(Clone, Copy)]
enum Derivative {
    FX,
    FV,
    FT,
    GX,
    GV,
    GT,
}

impl Derivative {
    /// The block's number in [`NonlinearEval::derivative_blocks`].
    fn block(self) -> usize {
        self as usize
    }

    #[inline(always)]
    fn of(self, e: &NonlinearEval) -> &[f64] {
        match self {
            Derivative::FX => &e.df_dx,
            Derivative::FV => &e.df_dv,
            Derivative::FT => &e.df_dt,
            Derivative::GX => &e.dg_dx,
            Derivative::GV => &e.dg_dv,
            Derivative::GT => &e.dg_dt,
        }
    }
}

/// The Jacobian `∂R/∂A` in structured form: the linear matrices (the harmonic blocks are
/// formed from them on the fly) and the dense nonlinear part on the nonlinear DoFs.
#[derive(Clone, Debug)]
pub struct JacobianParts {
    pub omega: f64,
    pub linear: LinearPart,
    /// `(P·nc) × (P·nc)` row-major, `P = n_nl_mech + n_nl_therm`; block `(k, l)` couples
    /// nonlinear DoF `k` (mechanical ones first, then thermal) with nonlinear DoF `l`.
    pub nonlinear: Vec<f64>,
    /// Whether some sample has a velocity derivative (`∂f/∂ẋ` or `∂g/∂ẋ`): where none
    /// has, the velocity sensitivity ([`HarmonicBalance::velocity_sensitivity`]) is zero
    /// and Hill's pencil needs no evaluation of its own.
    pub velocity_dependent: bool,
}

/// 2-norms of the mechanical and thermal parts of a residual vector.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResidualNorms {
    pub mech: f64,
    pub therm: f64,
}

/// The harmonic-balance equations of a [`System`] on a [`Basis`].
pub struct HarmonicBalance<'a> {
    system: &'a dyn System,
    aft: Aft,
    nl: NonlinearDofs,
    n_mech: usize,
    n_therm: usize,
    /// Integrate the nonlinear terms between located switching instants
    /// ([`HarmonicBalance::with_event_refinement`]).
    events: bool,
    /// The event quadrature's uniform panels.
    rule: PanelRule,
    /// The basis at the rule's nodes, built at the first event evaluation
    /// ([`NodeTable`]).
    node_table: std::sync::OnceLock<NodeTable>,
    /// Per-sample evaluation buffers of earlier residuals, reused: allocating and zeroing
    /// them (128 × 13 kB on the dual rotor) was about a tenth of a residual.
    eval_pool: std::sync::Mutex<Vec<Vec<NonlinearEval>>>,
    /// The last load's coefficients and the ω (its bits) they are for: a step asks for
    /// the load at one ω about twice (its residual and the convergence test's reference
    /// norms), and sampling the forcing over the AFT grid is a fifth of a residual on a
    /// small system.
    load_cache: std::sync::Mutex<Option<(u64, Vec<f64>)>>,
}

impl std::fmt::Debug for HarmonicBalance<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HarmonicBalance")
            .field("n_mech", &self.n_mech)
            .field("n_therm", &self.n_therm)
            .field("nl", &self.nl)
            .field("aft", &self.aft)
            .finish()
    }
}

/// The basis functions at the panel rule's nodes, as rows of the coefficients' layout
/// (`1 + 2H` per DoF): node `i`'s value row `[1, cos m_h θ_i, sin m_h θ_i]` and rate row
/// `[0, −m_h sin m_h θ_i, m_h cos m_h θ_i]` (times the base frequency). A state at a node
/// is then two contiguous dot products, which vectorise; read through the complex rows
/// `e^{−ikθ}` by multiple it was a gather per harmonic and a tenth of the contact
/// benchmark's time.
struct NodeTable {
    nc: usize,
    /// Node-major, `2 nc` per node: the value row, then the rate row.
    rows: Vec<f64>,
}

impl NodeTable {
    fn new(rule: &PanelRule, multiples: &[usize]) -> Self {
        let nh = multiples.len();
        let nc = 1 + 2 * nh;
        let n = rule.theta().len();
        let mut rows = vec![0.0; n * 2 * nc];
        for (i, r) in rows.chunks_mut(2 * nc).enumerate() {
            let phases = rule.row(i);
            let (value, rate) = r.split_at_mut(nc);
            value[0] = 1.0;
            for (h, &m) in multiples.iter().enumerate() {
                let (cs, sn) = (phases[m].re, -phases[m].im);
                let mf = m as f64;
                value[1 + h] = cs;
                value[1 + nh + h] = sn;
                rate[1 + h] = -mf * sn;
                rate[1 + nh + h] = mf * cs;
            }
        }
        Self { nc, rows }
    }

    /// The value and rate (per unit base frequency) of the DoF with coefficients `c` at
    /// node `i`.
    fn eval(&self, i: usize, c: &[f64]) -> (f64, f64) {
        let r = &self.rows[i * 2 * self.nc..(i + 1) * 2 * self.nc];
        let (value, rate) = r.split_at(self.nc);
        (dot_lanes(value, c), dot_lanes(rate, c))
    }
}

/// `Σ aᵢ bᵢ` in four interleaved partial sums (which the compiler vectorises; a single
/// running sum it may not reorder).
fn dot_lanes(a: &[f64], b: &[f64]) -> f64 {
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ac
        .remainder()
        .iter()
        .zip(bc.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut acc = [0.0; 4];
    for (x, y) in ac.zip(bc) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Nonlinear DoFs' state width (`2p + q`) from which the event nodes are evaluated in
/// parallel: below it a node costs less than handing it to another thread.
const PARALLEL_WIDTH: usize = 8;

/// The nonlinear terms over one period: at the AFT's samples, or at event nodes.
struct Evaluation {
    evals: Vec<NonlinearEval>,
    nodes: Option<EventNodes>,
}

/// Whether some evaluated sample has a velocity derivative (`∂f/∂ẋ` or `∂g/∂ẋ`).
fn has_velocity_derivatives(ev: &Evaluation) -> bool {
    ev.evals.iter().any(|e| {
        let [_, df_dv, _, _, dg_dv, _] = e.derivative_blocks();
        df_dv.iter().chain(dg_dv).any(|v| *v != 0.0)
    })
}

/// Scratch state of the nonlinear DoFs at one instant.
struct NodeState {
    x: Vec<f64>,
    v: Vec<f64>,
    temp: Vec<f64>,
    /// `e^{−ikθ}` at an instant off the panel rule's nodes ([`HarmonicBalance::state_at_phase`]).
    row: Vec<Complex64>,
}

impl NodeState {
    /// Writes `x`, `v`, `T` into `out`.
    fn write(&self, out: &mut [f64]) {
        let p = self.x.len();
        out[..p].copy_from_slice(&self.x);
        out[p..2 * p].copy_from_slice(&self.v);
        out[2 * p..].copy_from_slice(&self.temp);
    }

    /// Reads `x`, `v`, `T` from what [`Self::write`] wrote.
    fn read(&mut self, from: &[f64]) {
        let p = self.x.len();
        self.x.copy_from_slice(&from[..p]);
        self.v.copy_from_slice(&from[p..2 * p]);
        self.temp.copy_from_slice(&from[2 * p..]);
    }

    fn new(p: usize, q: usize) -> Self {
        Self {
            x: vec![0.0; p],
            v: vec![0.0; p],
            temp: vec![0.0; q],
            row: Vec::new(),
        }
    }
}

/// One field's linear matrices: (first DoF, size, mass or none, velocity matrix, stiffness).
pub(crate) struct Field<'m> {
    pub offset: usize,
    pub n: usize,
    pub mass: Option<&'m DenseMatrix>,
    pub damping: &'m DenseMatrix,
    pub stiffness: &'m DenseMatrix,
}

pub(crate) fn fields(lin: &LinearPart, n_mech: usize, n_therm: usize) -> [Field<'_>; 2] {
    [
        Field {
            offset: 0,
            n: n_mech,
            mass: Some(&lin.mass),
            damping: &lin.damping,
            stiffness: &lin.stiffness,
        },
        Field {
            offset: n_mech,
            n: n_therm,
            mass: None,
            damping: &lin.thermal_capacity,
            stiffness: &lin.thermal_conductance,
        },
    ]
}

/// One nonzero `(row, column)` of a [`LinearPart`] in the harmonic-balance layout: the
/// first coefficient of the row's and the column's DoF, and the stiffness, velocity and
/// mass entries there.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LinearEntry {
    ri: usize,
    cj: usize,
    k: f64,
    c: f64,
    m: f64,
}

/// A [`LinearPart`]'s nonzero entries ([`HarmonicBalance::sparse_linear`]): its product
/// with coefficient vectors in the cost of its nonzeros.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseLinear {
    entries: Vec<LinearEntry>,
}

impl LinearEntry {
    /// Adds this entry's terms of `L(ω) coeffs` to `out`, `w` the harmonics' angular
    /// frequencies `ν_h ω` (`nh` of them).
    #[inline]
    fn add_to(&self, w: &[f64], coeffs: &[f64], out: &mut [f64]) {
        let &LinearEntry { ri, cj, k, c, m } = self;
        let nh = w.len();
        out[ri] += k * coeffs[cj];
        for (h, &w) in w.iter().enumerate() {
            let a = k - w * w * m;
            let (xa, xb) = (coeffs[cj + 1 + h], coeffs[cj + 1 + nh + h]);
            out[ri + 1 + h] += a * xa + w * c * xb;
            out[ri + 1 + nh + h] += -w * c * xa + a * xb;
        }
    }
}

impl SparseLinear {
    /// Adds the linear terms' coefficients `L(ω) coeffs` to `out`, as
    /// [`HarmonicBalance::add_linear`] (the same sums in the same order) for the
    /// harmonic balance `hb` this was built for.
    pub fn apply(&self, hb: &HarmonicBalance<'_>, omega: f64, coeffs: &[f64], out: &mut [f64]) {
        let w = hb.harmonic_frequencies(omega);
        for e in &self.entries {
            e.add_to(&w, coeffs, out);
        }
    }
}

fn check_dofs(field: &'static str, idx: &[usize], n: usize) -> Result<(), HbError> {
    if let Some(&bad) = idx.iter().find(|&&i| i >= n) {
        return Err(HbError::NonlinearDofOutOfRange {
            field,
            index: bad,
            n,
        });
    }
    if idx.windows(2).any(|w| w[0] >= w[1]) {
        return Err(HbError::NonlinearDofOrder {
            field,
            indices: idx.to_vec(),
        });
    }
    Ok(())
}

impl<'a> HarmonicBalance<'a> {
    /// Harmonic balance of `system` on `basis` with `n_samples` AFT samples per period
    /// (`None`: [`Aft::default_samples`]).
    pub fn new(
        system: &'a dyn System,
        basis: &Basis,
        n_samples: Option<usize>,
    ) -> Result<Self, HbError> {
        let nl = system.nonlinear_dofs().clone();
        let (n_mech, n_therm) = (system.n_mech(), system.n_therm());
        check_dofs("mechanical", &nl.mech, n_mech)?;
        check_dofs("thermal", &nl.therm, n_therm)?;
        let aft = Aft::new(basis, n_samples)?;
        let m_max = basis.max_integer_multiple() as usize;
        Ok(Self {
            system,
            events: system.n_switching() > 0,
            rule: PanelRule::new((aft.n_samples() / 8).max(8 * (m_max + 1)), 2 * m_max),
            node_table: std::sync::OnceLock::new(),
            aft,
            nl,
            n_mech,
            n_therm,
            eval_pool: std::sync::Mutex::new(Vec::new()),
            load_cache: std::sync::Mutex::new(None),
        })
    }

    /// With `on`, the nonlinear terms' coefficients and Jacobian are integrated exactly
    /// between the instants where the system's switching functions change sign
    /// ([`EventNodes`]); without, they are sampled on the AFT's uniform grid. On by
    /// default for systems with switching functions ([`System::n_switching`]).
    pub fn with_event_refinement(mut self, on: bool) -> Self {
        self.events = on;
        self
    }

    /// Whether the nonlinear terms are integrated between switching instants.
    pub fn event_refinement(&self) -> bool {
        self.events
    }

    /// The event quadrature's nodes at `(A, ω)`: its switching instants (as phases
    /// `Ω_b t`), and as many nodes as a residual evaluates the nonlinear terms at. `None`
    /// without event refinement.
    pub fn event_nodes(&self, coeffs: &[f64], omega: f64) -> Option<EventNodes> {
        self.events.then(|| self.refine_nodes(coeffs, omega).0)
    }

    /// The event nodes at `(A, ω)` and the nonlinear DoFs' states at the panel rule's
    /// nodes (`x`, `v`, `T` of each, node-major).
    fn refine_nodes(&self, coeffs: &[f64], omega: f64) -> (EventNodes, Vec<f64>) {
        let (p, q) = (self.nl.mech.len(), self.nl.therm.len());
        let width = 2 * p + q;
        let ns = self.system.n_switching();
        let wb = self.aft.base_frequency(omega);
        let theta = self.rule.theta();
        let mut states = vec![0.0; theta.len() * width];
        let table = self
            .node_table
            .get_or_init(|| NodeTable::new(&self.rule, self.aft.multiples()));
        let nc = self.n_coeffs();
        let one = |st: &mut NodeState, (i, out): (usize, &mut [f64])| {
            for (k, &d) in self.nl.mech.iter().enumerate() {
                let (x, v) = table.eval(i, &coeffs[d * nc..(d + 1) * nc]);
                (st.x[k], st.v[k]) = (x, wb * v);
            }
            for (k, &d) in self.nl.therm.iter().enumerate() {
                let g = self.n_mech + d;
                st.temp[k] = table.eval(i, &coeffs[g * nc..(g + 1) * nc]).0;
            }
            st.write(out);
        };
        if width >= PARALLEL_WIDTH {
            states
                .par_chunks_mut(width)
                .enumerate()
                .with_min_len(64)
                .for_each_init(|| NodeState::new(p, q), one);
        } else if width > 0 {
            let mut st = NodeState::new(p, q);
            states
                .chunks_mut(width)
                .enumerate()
                .for_each(|io| one(&mut st, io));
        }
        let mut values = vec![0.0; theta.len() * ns];
        if ns > 0 {
            for ((out, s), &th) in values
                .chunks_mut(ns)
                .zip(states.chunks(width.max(1)))
                .zip(theta)
            {
                let (x, rest) = s.split_at(p);
                let (v, temp) = rest.split_at(p);
                self.system.switching(omega, th / wb, x, v, temp, out);
            }
        }
        let mut st = NodeState::new(p, q);
        let mut buf = vec![0.0; ns];
        // the bracket's ends are nodes whose switching values are known, but for the end
        // past the period's (see `PanelRule::refine`)
        let nodes = self.rule.refine(&values, ns, |i, (a, fa), (b, fb)| {
            let mut f = |th: f64| {
                self.state_at_phase(coeffs, wb, th, &mut st);
                self.system
                    .switching(omega, th / wb, &st.x, &st.v, &st.temp, &mut buf);
                buf[i]
            };
            let fb = fb.unwrap_or_else(|| f(b));
            illinois(&mut f, a, fa, b, fb)
        });
        (nodes, states)
    }

    /// The nonlinear DoFs' values, rates and temperatures at the phase whose row
    /// `e^{−ikθ}` is `row` (base frequency `wb`).
    fn state_from_row(&self, coeffs: &[f64], wb: f64, row: &[Complex64], st: &mut NodeState) {
        let nc = self.n_coeffs();
        let multiples = self.aft.multiples();
        let nh = multiples.len();
        let eval = |c: &[f64]| {
            let (mut x, mut v) = (c[0], 0.0);
            for (h, &m) in multiples.iter().enumerate() {
                let (cs, sn) = (row[m].re, -row[m].im);
                let (a, b) = (c[1 + h], c[1 + nh + h]);
                x += a * cs + b * sn;
                v += m as f64 * wb * (b * cs - a * sn);
            }
            (x, v)
        };
        for (k, &d) in self.nl.mech.iter().enumerate() {
            (st.x[k], st.v[k]) = eval(&coeffs[d * nc..(d + 1) * nc]);
        }
        for (k, &d) in self.nl.therm.iter().enumerate() {
            let g = self.n_mech + d;
            st.temp[k] = eval(&coeffs[g * nc..(g + 1) * nc]).0;
        }
    }

    /// The nonlinear DoFs' values, rates and temperatures at phase `theta` (`Ω_b t`, base
    /// frequency `wb`), off the panel rule's nodes.
    fn state_at_phase(&self, coeffs: &[f64], wb: f64, theta: f64, st: &mut NodeState) {
        let mut row = std::mem::take(&mut st.row);
        row.clear();
        push_phases(
            &[theta],
            self.aft.basis().max_integer_multiple() as usize + 1,
            &mut row,
        );
        self.state_from_row(coeffs, wb, &row, st);
        st.row = row;
    }

    /// The normalised spectrum of `series` (values at the AFT samples, or at `nodes`).
    fn spectrum(&self, nodes: Option<&EventNodes>, series: &[f64], buf: &mut Vec<Complex64>) {
        match nodes {
            Some(q) => q.spectrum(&self.rule, series, self.aft.n_samples(), buf),
            None => self.aft.spectrum(series, buf),
        }
    }

    pub fn system(&self) -> &'a dyn System {
        self.system
    }
    pub fn basis(&self) -> &Basis {
        self.aft.basis()
    }
    pub fn aft(&self) -> &Aft {
        &self.aft
    }
    pub fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.nl
    }
    pub fn n_mech(&self) -> usize {
        self.n_mech
    }
    pub fn n_therm(&self) -> usize {
        self.n_therm
    }
    /// Coefficients per DoF `1 + 2H`.
    pub fn n_coeffs(&self) -> usize {
        self.aft.basis().n_coeffs()
    }
    /// Number of unknowns `(n_mech + n_therm)·(1 + 2H)`.
    pub fn n_unknowns(&self) -> usize {
        (self.n_mech + self.n_therm) * self.n_coeffs()
    }
    /// Number of mechanical unknowns (they come first).
    pub fn n_mech_unknowns(&self) -> usize {
        self.n_mech * self.n_coeffs()
    }
    /// Global DoF indices (thermal offset by `n_mech`) of the nonlinear DoFs, mechanical first.
    pub fn nonlinear_global(&self) -> Vec<usize> {
        self.nl
            .mech
            .iter()
            .copied()
            .chain(self.nl.therm.iter().map(|&j| self.n_mech + j))
            .collect()
    }

    fn check_len(&self, what: &'static str, got: usize) -> Result<(), HbError> {
        let expected = self.n_unknowns();
        if got != expected {
            return Err(HbError::Dimension {
                what,
                expected,
                got,
            });
        }
        Ok(())
    }

    /// Checks the sizes of the system's linear matrices against `n_mech`, `n_therm`.
    fn check_linear(&self, lin: &LinearPart) -> Result<(), HbError> {
        for (what, m, n) in [
            ("mass matrix", &lin.mass, self.n_mech),
            ("damping matrix", &lin.damping, self.n_mech),
            ("stiffness matrix", &lin.stiffness, self.n_mech),
            (
                "thermal capacity matrix",
                &lin.thermal_capacity,
                self.n_therm,
            ),
            (
                "thermal conductance matrix",
                &lin.thermal_conductance,
                self.n_therm,
            ),
        ] {
            if m.n != n || m.data.len() != n * n {
                return Err(HbError::Dimension {
                    what,
                    expected: n,
                    got: m.n,
                });
            }
        }
        Ok(())
    }

    /// 2-norms of the mechanical and thermal parts of `r`.
    pub fn norms(&self, r: &[f64]) -> ResidualNorms {
        let m = self.n_mech_unknowns();
        let n2 = |s: &[f64]| (s.iter().map(|v| v * v).sum::<f64>() + 0.0).sqrt();
        ResidualNorms {
            mech: n2(&r[..m]),
            therm: n2(&r[m..]),
        }
    }

    /// Coefficients of the loads `F(t; ω)` (projected by AFT) and `F_T(ω)` (constant term).
    pub fn load_coeffs(&self, omega: f64) -> Vec<f64> {
        let key = omega.to_bits();
        if let Ok(cache) = self.load_cache.lock()
            && let Some((k, load)) = cache.as_ref()
            && *k == key
        {
            return load.clone();
        }
        let out = self.load_coeffs_uncached(omega);
        if let Ok(mut cache) = self.load_cache.lock() {
            *cache = Some((key, out.clone()));
        }
        out
    }

    fn load_coeffs_uncached(&self, omega: f64) -> Vec<f64> {
        let nc = self.n_coeffs();
        let n = self.aft.n_samples();
        let mut out = vec![0.0; self.n_unknowns()];
        let mut samples = vec![0.0; self.n_mech * n];
        let mut f = vec![0.0; self.n_mech];
        for j in 0..n {
            self.system.forcing(omega, self.aft.time(omega, j), &mut f);
            for (d, fd) in f.iter().enumerate() {
                samples[d * n + j] = *fd;
            }
        }
        let mut buf = Vec::new();
        for d in 0..self.n_mech {
            let s = &samples[d * n..(d + 1) * n];
            if s.iter().any(|v| *v != 0.0) {
                self.aft
                    .project(s, &mut out[d * nc..(d + 1) * nc], &mut buf);
            }
        }
        let mut ft = vec![0.0; self.n_therm];
        self.system.thermal_load(omega, &mut ft);
        for (j, v) in ft.iter().enumerate() {
            out[(self.n_mech + j) * nc] = *v;
        }
        out
    }

    /// Adds `Z(ω) A` to `out`.
    pub fn add_linear(&self, lin: &LinearPart, omega: f64, coeffs: &[f64], out: &mut [f64]) {
        let w = self.harmonic_frequencies(omega);
        for e in self.linear_entries(lin) {
            e.add_to(&w, coeffs, out);
        }
    }

    /// The nonzero entries of `lin` in the order [`Self::add_linear`] visits them, for
    /// applying the same linear part to many vectors ([`SparseLinear::apply`]) without
    /// scanning its zeros each time.
    pub fn sparse_linear(&self, lin: &LinearPart) -> SparseLinear {
        SparseLinear {
            entries: self.linear_entries(lin).collect(),
        }
    }

    /// The angular frequencies `ν_h ω` of the basis's harmonics.
    fn harmonic_frequencies(&self, omega: f64) -> Vec<f64> {
        self.aft
            .basis()
            .harmonics()
            .iter()
            .map(|r| r.value() * omega)
            .collect()
    }

    /// The nonzero `(row, column)` entries of `lin`, field by field, row by row.
    fn linear_entries<'l>(&self, lin: &'l LinearPart) -> impl Iterator<Item = LinearEntry> + 'l {
        let nc = self.n_coeffs();
        fields(lin, self.n_mech, self.n_therm)
            .into_iter()
            .flat_map(move |fld| {
                (0..fld.n).flat_map(move |i| {
                    (0..fld.n).filter_map(move |j| {
                        let k = fld.stiffness.get(i, j);
                        let c = fld.damping.get(i, j);
                        let m = fld.mass.map_or(0.0, |m| m.get(i, j));
                        (k != 0.0 || c != 0.0 || m != 0.0).then_some(LinearEntry {
                            ri: (fld.offset + i) * nc,
                            cj: (fld.offset + j) * nc,
                            k,
                            c,
                            m,
                        })
                    })
                })
            })
    }

    /// Time samples of the nonlinear DoFs: `x`, `v` (p series each) and `T` (q series),
    /// each `N` long, concatenated.
    fn nonlinear_samples(&self, coeffs: &[f64], omega: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let nc = self.n_coeffs();
        let n = self.aft.n_samples();
        let (p, q) = (self.nl.mech.len(), self.nl.therm.len());
        let mut xs = vec![0.0; p * n];
        let mut vs = vec![0.0; p * n];
        let mut ts = vec![0.0; q * n];
        let mut buf = Vec::new();
        let mut dc = vec![0.0; nc];
        for (k, &d) in self.nl.mech.iter().enumerate() {
            let c = &coeffs[d * nc..(d + 1) * nc];
            self.aft
                .synthesize(c, &mut xs[k * n..(k + 1) * n], &mut buf);
            self.aft.derivative_coeffs(c, omega, &mut dc);
            self.aft
                .synthesize(&dc, &mut vs[k * n..(k + 1) * n], &mut buf);
        }
        for (k, &d) in self.nl.therm.iter().enumerate() {
            let g = self.n_mech + d;
            self.aft.synthesize(
                &coeffs[g * nc..(g + 1) * nc],
                &mut ts[k * n..(k + 1) * n],
                &mut buf,
            );
        }
        (xs, vs, ts)
    }

    /// Pointwise evaluations of the nonlinear terms at every sample (in buffers from the
    /// pool; hand them back with [`Self::recycle`]).
    /// The nonlinear terms at every AFT sample; their derivatives too when
    /// `derivatives`.
    fn evaluate(&self, coeffs: &[f64], omega: f64, derivatives: bool) -> Evaluation {
        let (p, q) = (self.nl.mech.len(), self.nl.therm.len());
        let mut evals = self
            .eval_pool
            .lock()
            .ok()
            .and_then(|mut pool| pool.pop())
            .unwrap_or_default();
        if self.events {
            let (nodes, states) = self.refine_nodes(coeffs, omega);
            let width = 2 * p + q;
            let wb = self.aft.base_frequency(omega);
            evals.resize_with(nodes.len(), || NonlinearEval::new(p, q));
            let eval_one =
                |st: &mut NodeState, ((th, row), e): ((&f64, &Row), &mut NonlinearEval)| {
                    let t = th / wb;
                    match *row {
                        Row::Rule(i) => st.read(&states[i * width..(i + 1) * width]),
                        Row::Own(_) => {
                            self.state_from_row(coeffs, wb, nodes.row(&self.rule, *row), st)
                        }
                    }
                    if derivatives {
                        self.system
                            .eval_nonlinear(omega, t, &st.x, &st.v, &st.temp, e);
                    } else {
                        self.system
                            .eval_nonlinear_values(omega, t, &st.x, &st.v, &st.temp, e);
                    }
                };
            if width >= PARALLEL_WIDTH {
                nodes
                    .theta
                    .par_iter()
                    .zip(nodes.rows.par_iter())
                    .zip(evals.par_iter_mut())
                    .with_min_len(64)
                    .for_each_init(|| NodeState::new(p, q), eval_one);
            } else {
                let mut st = NodeState::new(p, q);
                nodes
                    .theta
                    .iter()
                    .zip(&nodes.rows)
                    .zip(evals.iter_mut())
                    .for_each(|n| eval_one(&mut st, n));
            }
            return Evaluation {
                evals,
                nodes: Some(nodes),
            };
        }
        let n = self.aft.n_samples();
        let (xs, vs, ts) = self.nonlinear_samples(coeffs, omega);
        evals.resize_with(n, || NonlinearEval::new(p, q));
        let eval_one = |(x, v, t): &mut (Vec<f64>, Vec<f64>, Vec<f64>),
                        (j, e): (usize, &mut NonlinearEval)| {
            for k in 0..p {
                x[k] = xs[k * n + j];
                v[k] = vs[k * n + j];
            }
            for (k, tk) in t.iter_mut().enumerate() {
                *tk = ts[k * n + j];
            }
            let time = self.aft.time(omega, j);
            if derivatives {
                self.system.eval_nonlinear(omega, time, x, v, t, e);
            } else {
                self.system.eval_nonlinear_values(omega, time, x, v, t, e);
            }
        };
        let buffers = || (vec![0.0; p], vec![0.0; p], vec![0.0; q]);
        if (p + q) * n >= 512 {
            evals
                .par_iter_mut()
                .enumerate()
                .with_min_len(8)
                .for_each_init(buffers, eval_one);
        } else {
            let mut b = buffers();
            evals
                .iter_mut()
                .enumerate()
                .for_each(|je| eval_one(&mut b, je));
        }
        Evaluation { evals, nodes: None }
    }

    /// Returns the buffers of [`Self::evaluate`] to the pool.
    fn recycle(&self, Evaluation { evals, .. }: Evaluation) {
        if let Ok(mut pool) = self.eval_pool.lock() {
            // one per thread that may evaluate at once is plenty
            if pool.len() < 4 {
                pool.push(evals);
            }
        }
    }

    /// Residual `R(A, ω)` into `out`.
    pub fn residual(&self, coeffs: &[f64], omega: f64, out: &mut [f64]) -> Result<(), HbError> {
        self.residual_inner(coeffs, omega, out, None, None)
            .map(|_| ())
    }

    /// Residual into `out` and the Jacobian `∂R/∂A` in structured form.
    pub fn residual_jacobian(
        &self,
        coeffs: &[f64],
        omega: f64,
        out: &mut [f64],
    ) -> Result<JacobianParts, HbError> {
        self.jacobian_parts(coeffs, omega, out, None)
    }

    /// [`Self::residual_jacobian`] and [`Self::velocity_sensitivity`] from one evaluation
    /// of the samples (Hill's pencil wants both at a point); the sensitivity is `None`
    /// where it is zero: no sample has a velocity derivative (the dual rotor's forces
    /// and heat depend on displacements and temperatures alone).
    pub fn residual_jacobian_velocity(
        &self,
        coeffs: &[f64],
        omega: f64,
        out: &mut [f64],
    ) -> Result<(JacobianParts, Option<Vec<f64>>), HbError> {
        let mut velocity = None;
        let parts = self.jacobian_parts(coeffs, omega, out, Some(&mut velocity))?;
        Ok((parts, velocity))
    }

    /// The residual into `out` and `∂R/∂A`, with the velocity sensitivity into `velocity`
    /// when asked for ([`Self::residual_jacobian_velocity`]).
    fn jacobian_parts(
        &self,
        coeffs: &[f64],
        omega: f64,
        out: &mut [f64],
        velocity: Option<&mut Option<Vec<f64>>>,
    ) -> Result<JacobianParts, HbError> {
        let pn = (self.nl.mech.len() + self.nl.therm.len()) * self.n_coeffs();
        let mut jac = vec![0.0; pn * pn];
        let (lin, velocity_dependent) =
            self.residual_inner(coeffs, omega, out, Some(&mut jac), velocity)?;
        Ok(JacobianParts {
            omega,
            linear: lin,
            nonlinear: jac,
            velocity_dependent,
        })
    }

    fn residual_inner(
        &self,
        coeffs: &[f64],
        omega: f64,
        out: &mut [f64],
        jac: Option<&mut Vec<f64>>,
        velocity: Option<&mut Option<Vec<f64>>>,
    ) -> Result<(LinearPart, bool), HbError> {
        self.check_len("coefficient vector", coeffs.len())?;
        self.check_len("residual vector", out.len())?;
        let nc = self.n_coeffs();
        let (p, q) = (self.nl.mech.len(), self.nl.therm.len());
        let load = self.load_coeffs(omega);
        for (o, l) in out.iter_mut().zip(&load) {
            *o = -l;
        }
        let lin = self.system.linear(omega);
        self.check_linear(&lin)?;
        self.add_linear(&lin, omega, coeffs, out);
        let mut velocity_dependent = false;
        if p + q > 0 {
            let ev = self.evaluate(coeffs, omega, jac.is_some());
            let mut buf = Vec::new();
            let mut series = vec![0.0; ev.evals.len()];
            let mut proj = vec![0.0; nc];
            let globals = self.nonlinear_global();
            for (k, &g) in globals.iter().enumerate() {
                for (j, e) in ev.evals.iter().enumerate() {
                    series[j] = if k < p { e.f[k] } else { e.g[k - p] };
                }
                self.spectrum(ev.nodes.as_ref(), &series, &mut buf);
                self.aft.project_spectrum(&buf, &mut proj);
                for (o, v) in out[g * nc..(g + 1) * nc].iter_mut().zip(&proj) {
                    *o += v;
                }
            }
            if let Some(jac) = jac {
                self.nonlinear_jacobian(&ev, omega, jac, false);
                velocity_dependent = has_velocity_derivatives(&ev);
            }
            let velocity_part = velocity.map(|v| (v, self.velocity_part(&ev, omega)));
            self.recycle(ev);
            if let Some((v, part)) = velocity_part {
                *v = part?;
            }
        }
        if out.iter().any(|v| !v.is_finite()) {
            return Err(HbError::NonFinite {
                what: "residual",
                omega,
            });
        }
        Ok((lin, velocity_dependent))
    }

    /// The Galerkin matrix of the velocity sensitivities alone, `P[∂f/∂ẋ ·]` and
    /// `P[∂g/∂ẋ ·]` acting on the nonlinear mechanical DoFs' coefficients (the layout of
    /// [`JacobianParts::nonlinear`]; zero in the thermal columns). It is the part of the
    /// nonlinear terms that multiplies `λ` in Hill's eigenproblem: a perturbation
    /// `e^{λt} p(t)` has the rate `e^{λt} (ṗ + λ p)`.
    pub fn velocity_sensitivity(&self, coeffs: &[f64], omega: f64) -> Result<Vec<f64>, HbError> {
        self.velocity_sensitivity_if_any(coeffs, omega).map(|v| {
            v.unwrap_or_else(|| {
                let pn = (self.nl.mech.len() + self.nl.therm.len()) * self.n_coeffs();
                vec![0.0; pn * pn]
            })
        })
    }

    /// [`Self::velocity_sensitivity`], `None` where it is zero (no sample has a velocity
    /// derivative).
    pub fn velocity_sensitivity_if_any(
        &self,
        coeffs: &[f64],
        omega: f64,
    ) -> Result<Option<Vec<f64>>, HbError> {
        self.check_len("coefficient vector", coeffs.len())?;
        if self.nl.mech.len() + self.nl.therm.len() == 0 {
            return Ok(None);
        }
        let ev = self.evaluate(coeffs, omega, true);
        let out = self.velocity_part(&ev, omega);
        self.recycle(ev);
        out
    }

    /// The velocity sensitivity from the evaluated samples `ev` (see
    /// [`Self::velocity_sensitivity`]); `None` when no sample has a velocity derivative.
    fn velocity_part(&self, ev: &Evaluation, omega: f64) -> Result<Option<Vec<f64>>, HbError> {
        if !has_velocity_derivatives(ev) {
            return Ok(None);
        }
        let pn = (self.nl.mech.len() + self.nl.therm.len()) * self.n_coeffs();
        let mut out = vec![0.0; pn * pn];
        self.nonlinear_jacobian(ev, omega, &mut out, true);
        if out.iter().any(|v| !v.is_finite()) {
            return Err(HbError::NonFinite {
                what: "velocity sensitivity",
                omega,
            });
        }
        Ok(Some(out))
    }

    /// Assembles `∂P[f, g]/∂A` into `jac`; with `velocity_only`, the Galerkin matrix of the
    /// velocity derivatives taken as values instead ([`Self::velocity_sensitivity`]).
    fn nonlinear_jacobian(
        &self,
        ev: &Evaluation,
        omega: f64,
        jac: &mut [f64],
        velocity_only: bool,
    ) {
        let evals = &ev.evals[..];
        let nc = self.n_coeffs();
        let n = evals.len();
        let (p, q) = (self.nl.mech.len(), self.nl.therm.len());
        let pt = p + q;
        let ld = pt * nc;
        let aft = &self.aft;
        // the entries that are nonzero in some sample, found in one pass over the samples'
        // contiguous arrays (most of the dual rotor's 1 700 are zero in all of them), so
        // the loop below gathers only those entries' time series
        let mut nonzero: [Vec<bool>; 6] = match evals.first() {
            Some(e) => e.derivative_blocks().map(|b| vec![false; b.len()]),
            None => return,
        };
        for e in evals {
            for (mask, block) in nonzero.iter_mut().zip(e.derivative_blocks()) {
                for (m, v) in mask.iter_mut().zip(block) {
                    *m |= *v != 0.0;
                }
            }
        }
        // each row block (nonlinear DoF k) is independent
        jac.par_chunks_mut(nc * ld)
            .enumerate()
            .for_each(|(k, rows)| {
                let mut series = vec![0.0; n];
                let mut buf: Vec<Complex64> = Vec::new();
                for l in 0..pt {
                    let mut terms: [(Option<Derivative>, Signal, usize); 2] =
                        [(None, Signal::Value, 0), (None, Signal::Rate, 0)];
                    match (k < p, l < p) {
                        (true, true) if velocity_only => {
                            terms[0] = (Some(Derivative::FV), Signal::Value, k * p + l);
                        }
                        (false, true) if velocity_only => {
                            terms[0] = (Some(Derivative::GV), Signal::Value, (k - p) * p + l);
                        }
                        _ if velocity_only => {}
                        (true, true) => {
                            terms[0] = (Some(Derivative::FX), Signal::Value, k * p + l);
                            terms[1] = (Some(Derivative::FV), Signal::Rate, k * p + l);
                        }
                        (true, false) => {
                            terms[0] = (Some(Derivative::FT), Signal::Value, k * q + (l - p));
                        }
                        (false, true) => {
                            terms[0] = (Some(Derivative::GX), Signal::Value, (k - p) * p + l);
                            terms[1] = (Some(Derivative::GV), Signal::Rate, (k - p) * p + l);
                        }
                        (false, false) => {
                            terms[0] = (Some(Derivative::GT), Signal::Value, (k - p) * q + (l - p));
                        }
                    }
                    for (which, signal, idx) in terms {
                        let Some(which) = which else { continue };
                        if !nonzero[which.block()][idx] {
                            continue;
                        }
                        for (s, e) in series.iter_mut().zip(evals) {
                            *s = which.of(e)[idx];
                        }
                        self.spectrum(ev.nodes.as_ref(), &series, &mut buf);
                        aft.add_product_block(&buf, signal, omega, 1.0, &mut rows[l * nc..], ld);
                    }
                }
            });
    }

    /// `∂R/∂ω` at `(A, ω)` by a central difference with step `1e-6·|ω|` (truncation error
    /// `O(1e-12)` relative).
    pub fn d_residual_d_omega(
        &self,
        coeffs: &[f64],
        omega: f64,
        out: &mut [f64],
    ) -> Result<(), HbError> {
        let h = 1e-6 * omega.abs().max(1e-6);
        let mut rp = vec![0.0; out.len()];
        self.residual(coeffs, omega + h, &mut rp)?;
        self.residual(coeffs, omega - h, out)?;
        for (o, p) in out.iter_mut().zip(&rp) {
            *o = (p - *o) / (2.0 * h);
        }
        Ok(())
    }

    /// `∂R/∂ω` at `(A, ω)` by a forward difference from `r_at = R(A, ω)`, with step
    /// `h = 1.5e-8·|ω|` (`√ε`): one residual instead of the central difference's two,
    /// truncation and rounding errors both about `1e-8` relative. For the Newton border
    /// column and the tangent, where it changes only the convergence rate and the
    /// predictor.
    pub fn d_residual_d_omega_from(
        &self,
        coeffs: &[f64],
        omega: f64,
        r_at: &[f64],
        out: &mut [f64],
    ) -> Result<(), HbError> {
        self.check_len("residual vector", r_at.len())?;
        let h = 1.5e-8 * omega.abs().max(1e-6);
        // the step as represented, so that the quotient divides by what was added
        let h = (omega + h) - omega;
        self.residual(coeffs, omega + h, out)?;
        for (o, r) in out.iter_mut().zip(r_at) {
            *o = (*o - r) / h;
        }
        Ok(())
    }

    /// `out = (∂R/∂A) x` for the Jacobian `parts`, without assembling it: the linear part
    /// applied harmonic by harmonic, the dense nonlinear block on the nonlinear DoFs'
    /// coefficients (about 0.2 ms on the dual rotor, against 11 ms for a factorization).
    pub fn apply_jacobian(&self, parts: &JacobianParts, x: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.add_linear(&parts.linear, parts.omega, x, out);
        let nc = self.n_coeffs();
        let g = self.nonlinear_global();
        let ld = g.len() * nc;
        let xn: Vec<f64> = g
            .iter()
            .flat_map(|&gl| x[gl * nc..(gl + 1) * nc].iter().copied())
            .collect();
        for (k, &gk) in g.iter().enumerate() {
            for i in 0..nc {
                let row = &parts.nonlinear[(k * nc + i) * ld..(k * nc + i + 1) * ld];
                out[gk * nc + i] += row.iter().zip(&xn).map(|(a, b)| a * b).sum::<f64>();
            }
        }
    }

    /// Dense `∂R/∂A` (all unknowns, row-major): used by the uncondensed solver and tests.
    pub fn dense_jacobian(&self, parts: &JacobianParts) -> Vec<f64> {
        let nu = self.n_unknowns();
        let nc = self.n_coeffs();
        let mut jac = vec![0.0; nu * nu];
        let mut e = vec![0.0; nu];
        let mut col = vec![0.0; nu];
        // linear part column by column (Z is cheap to apply)
        for c in 0..nu {
            e.iter_mut().for_each(|v| *v = 0.0);
            col.iter_mut().for_each(|v| *v = 0.0);
            e[c] = 1.0;
            self.add_linear(&parts.linear, parts.omega, &e, &mut col);
            for r in 0..nu {
                jac[r * nu + c] = col[r];
            }
        }
        let g = self.nonlinear_global();
        let ld = g.len() * nc;
        for (k, &gk) in g.iter().enumerate() {
            for (l, &gl) in g.iter().enumerate() {
                for i in 0..nc {
                    for j in 0..nc {
                        jac[(gk * nc + i) * nu + gl * nc + j] +=
                            parts.nonlinear[(k * nc + i) * ld + l * nc + j];
                    }
                }
            }
        }
        jac
    }
}
