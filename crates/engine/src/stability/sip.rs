//! Floquet multipliers by the single-iteration-pass (SIP) product, paper Eqs. 30–33.
//!
//! The period `P` of the orbit is split into `N_k` equal intervals of length `Δ`. On each,
//! the state matrix `B(t)` of the linearised equations (Eq. 30; see
//! [`StateSpace`] for its blocks, including the thermal block
//! and all mechanical–thermal coupling blocks) is replaced by its interval mean (Eq. 32),
//! computed with `gauss_points`-point Gauss–Legendre quadrature, and the monodromy matrix is
//! the ordered product of truncated exponential series (Eq. 33):
//!
//! ```text
//!   E_SIP = Π_{k=N_k..1} ( I + Σ_{i=1}^{N_i} (Δ B_k)^i / i! )      (later intervals on the left)
//! ```
//!
//! Structure: `B(t) = B_lin + L D(t) S` with a constant `B_lin` and a low-rank part that only
//! the nonlinear DoFs feed (see [`StateSpace::apply_linearization`]). Only `D(t)` (the
//! pointwise derivatives of `f`, `g`) is averaged per interval — `B_lin` is constant, so its
//! mean is itself — and `B_k` is never formed: each factor is applied to the running
//! product by Horner's scheme, `W ← P + (Δ/i) B_k W` for `i = N_i..1`, `P ← W`, which is
//! `N_i` structured products (`2 n_mech² + n_therm²` multiply–adds per column) per interval
//! instead of `N_i + 1` dense `d³` products.
//!
//! Accuracy and defaults (the paper gives neither `N_k` nor `N_i`):
//! * replacing `B` by its interval mean keeps the first Magnus term exactly and drops the
//!   commutator term, so the product converges as `O(Δ²)` (halving `Δ` divides the error by
//!   4, see the Hill test);
//! * the truncated series is the stability polynomial of an explicit Taylor method; it must
//!   not amplify the fast, lightly damped modes of a finite-element rotor. Orders 3, 4, 7, 8
//!   contain a segment of the imaginary axis, orders 1, 2, 5, 6 do not (they would turn
//!   every undamped fast mode into a spurious instability). Default `series_order = 4`:
//!   `|R(iy)| < 1` for `0 < |y| < 2√2`, real-axis limit −2.79;
//! * `Δ·ρ(B) ≤ max_step_norm` is enforced by raising `N_k` above `intervals` when needed,
//!   with `ρ` bounded from above by `√(‖M⁻¹K‖∞ + max‖M⁻¹P ∂f/∂x‖∞) + ‖M⁻¹C‖∞ +
//!   max‖M⁻¹P ∂f/∂v‖∞` and `‖C_T⁻¹K_T‖∞ + max‖C_T⁻¹Q ∂g/∂T‖∞` (maxima over 64 instants).
//!   Default `max_step_norm = 1` (inside the stability segment with margin; fast modes are
//!   damped a little too much rather than amplified); `intervals = 256`; `gauss_points = 3`
//!   (exact for the mean of a quintic; the derivative terms are smooth on the reference
//!   problems, and for contact forces no fixed rule is exact anyway);
//! * optional extrapolation (`extrapolate`, default **off**): with the interval mean each
//!   factor is time-symmetric up to the series truncation, so the product's error expands
//!   in even powers of `Δ`. With `extrapolate = true` the same pass also forms the product
//!   on `N_k/2` pairs of intervals (pair mean = average of the two means, no extra
//!   evaluations) and returns `(4 E_Δ − E_2Δ)/3` (Richardson), for 1.5× the cost. On the
//!   Duffing resonant branch (Ω = 1.2, amplitude 2.5, 256 intervals) this takes the error
//!   against the shooting multipliers from 3.9e-4 to 5.8e-7. It is off by default because
//!   it is only safe when the series truncation is negligible for *every* mode: for a
//!   lightly damped mode with `Δω` of a few tenths, fine and coarse products carry
//!   different phase errors and `|4a − b|/3` exceeds 1 although `|a|, |b| ≤ 1` (for an
//!   undamped mode at `Δω = 0.45` and 1024 intervals, 1.27: a spurious instability). The
//!   plain product never amplifies such modes (order 4 is dissipative on the imaginary
//!   axis). Use it for small, low-frequency systems (the reference oscillators), not for
//!   finite-element models with many modes above the excitation.
//!
//! Thermal multipliers: thermal time constants are long against the period, so
//! `Δ·ρ_th ≪ 1` and the series is exact to round-off for them; they come out as
//! `exp(−P/τ) ≈ 1 − P/τ`, within `1e-5` or closer of +1, and are kept as computed (no
//! deflation), so the stable flag compares them with the circle at
//! [`UNIT_CIRCLE_TOL`](super::UNIT_CIRCLE_TOL). See [`super::thermal`] to report them
//! apart.

use faer::{Mat, MatRef};

use super::{FloquetResult, StabilityError, StabilityMethod, all_finite, eigenvalues_checked};
use crate::integrate::{StateSpace, Workspace};
use crate::system::{NonlinearEval, PeriodicOrbit, System};

/// The SIP method (paper Eqs. 32–33) with its settings; see the module docs for defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sip {
    /// Minimum number of intervals `N_k` over the period. Default 256.
    pub intervals: usize,
    /// Order `N_i` of the truncated exponential series. Default 4.
    pub series_order: usize,
    /// Gauss–Legendre points per interval for the mean `B_k` (1..=5). Default 3.
    pub gauss_points: usize,
    /// Upper bound on `Δ·ρ(B)`; `N_k` is raised to meet it. Default 1.0;
    /// `f64::INFINITY` uses exactly `intervals`.
    pub max_step_norm: f64,
    /// Richardson extrapolation of two SIP products, on `N_k` and `N_k/2` intervals:
    /// `(4 E_Δ − E_2Δ)/3`. Default false (see the module docs for when it is safe).
    pub extrapolate: bool,
}

/// Upper limit on the SIP interval count chosen from `Δ·ρ(B) ≤ max_step_norm`: beyond it
/// the product would take minutes and gigabytes per point, so the method reports the
/// stiffness instead.
pub const MAX_INTERVALS: usize = 200_000;

impl Default for Sip {
    fn default() -> Self {
        Self {
            intervals: 256,
            series_order: 4,
            gauss_points: 3,
            max_step_norm: 1.0,
            extrapolate: false,
        }
    }
}

/// The SIP monodromy matrix and how it was computed.
#[derive(Clone, Debug)]
pub struct SipMonodromy {
    /// `E_SIP` (`d × d`).
    pub matrix: Mat<f64>,
    /// Number of intervals used (`≥ intervals`).
    pub intervals: usize,
    /// Upper bound of `ρ(B)` used to choose the intervals (1/s).
    pub rho_bound: f64,
    /// `Σ_k ln|det E_k|` when requested ([`Sip::monodromy_with_log_det`], which computes the
    /// plain product without extrapolation): the log of the
    /// product of all multipliers, accurate even when some multipliers underflow next to
    /// others of order 1.
    pub log_abs_det: Option<f64>,
}

/// Gauss–Legendre nodes on [−1, 1] and weights, for 1..=5 points.
pub(crate) fn gauss_legendre(n: usize) -> Option<(&'static [f64], &'static [f64])> {
    const X1: [f64; 1] = [0.0];
    const W1: [f64; 1] = [2.0];
    const X2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];
    const W2: [f64; 2] = [1.0, 1.0];
    const X3: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W3: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    const X4: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W4: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    const X5: [f64; 5] = [
        -0.906_179_845_938_664,
        -0.538_469_310_105_683,
        0.0,
        0.538_469_310_105_683,
        0.906_179_845_938_664,
    ];
    const W5: [f64; 5] = [
        0.236_926_885_056_189_1,
        0.478_628_670_499_366_5,
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
    ];
    match n {
        1 => Some((&X1, &W1)),
        2 => Some((&X2, &W2)),
        3 => Some((&X3, &W3)),
        4 => Some((&X4, &W4)),
        5 => Some((&X5, &W5)),
        _ => None,
    }
}

/// Accumulates `out += w · src` over every derivative buffer.
pub(crate) fn axpy_derivs(out: &mut NonlinearEval, w: f64, src: &NonlinearEval) {
    for (o, s) in out
        .derivative_blocks_mut()
        .into_iter()
        .zip(src.derivative_blocks())
    {
        o.iter_mut().zip(s).for_each(|(a, b)| *a += w * b);
    }
}

fn inf_norm(a: MatRef<'_, f64>) -> f64 {
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `‖S · D‖∞` for `S` (r × p) and `D` (p × c, row-major slice).
fn inf_norm_product(s: MatRef<'_, f64>, d: &[f64], c: usize) -> f64 {
    let p = s.ncols();
    if p == 0 || c == 0 {
        return 0.0;
    }
    let dm = MatRef::from_row_major_slice(d, p, c);
    inf_norm((s * dm).as_ref())
}

/// Where the interval means of Eq. 32 are taken: `intervals` intervals of length `delta`,
/// each by Gauss–Legendre with `nodes`/`weights` on [−1, 1].
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeanGrid<'g> {
    pub delta: f64,
    pub intervals: usize,
    pub nodes: &'g [f64],
    pub weights: &'g [f64],
}

/// Eq. 32: interval means of the time-varying part (the pointwise derivatives) on `grid`.
/// The orbit is sampled sequentially (it need not be shareable between threads; that is
/// the cheap part), the nonlinear derivatives at the samples are evaluated on the rayon
/// threads.
pub(crate) fn interval_means(
    space: &StateSpace<'_>,
    orbit: &dyn PeriodicOrbit,
    grid: MeanGrid<'_>,
    ws: &mut Workspace,
) -> Vec<NonlinearEval> {
    interval_means_with(space, orbit, grid, ws, |m| m.clone())
}

/// [`interval_means`] handing each interval's mean to `keep` as it is computed (in a
/// buffer reused from interval to interval) and collecting what `keep` returns, in
/// interval order.
pub(crate) fn interval_means_with<T: Send>(
    space: &StateSpace<'_>,
    orbit: &dyn PeriodicOrbit,
    grid: MeanGrid<'_>,
    ws: &mut Workspace,
    keep: impl Fn(&NonlinearEval) -> T + Sync,
) -> Vec<T> {
    let MeanGrid {
        delta,
        intervals,
        nodes,
        weights,
    } = grid;
    use rayon::prelude::*;
    let per = nodes.len();
    let time = |k: usize, j: usize| k as f64 * delta + 0.5 * delta * (1.0 + nodes[j]);
    // the samples: the nonlinear DoFs alone when the orbit gives them so (`x_P`, `v_P`,
    // `T_Q`), the whole state otherwise
    let dofs = space.dofs();
    let (p, q) = (dofs.mech.len(), dofs.therm.len());
    let mut part = vec![0.0; (2 * p + q) * intervals * per];
    // (a linear system has no nonlinear DoFs: nothing to gather, the whole state is sampled)
    let gathered = p + q > 0 && {
        let (x, rest) = part[..2 * p + q].split_at_mut(p);
        let (v, temp) = rest.split_at_mut(p);
        orbit.dofs_at(time(0, 0), (&dofs.mech, &dofs.therm), x, v, temp)
    };
    let (n, m) = (space.n_mech(), space.n_therm());
    let (width, split) = if gathered {
        (2 * p + q, p)
    } else {
        (2 * n + m, n)
    };
    let mut states = if gathered {
        part
    } else {
        vec![0.0; width * intervals * per]
    };
    // (the orbit's answer for the first sample is already in place)
    let from = usize::from(gathered);
    for (i, y) in states.chunks_exact_mut(width).enumerate().skip(from) {
        let (x, rest) = y.split_at_mut(split);
        let (v, temp) = rest.split_at_mut(split);
        let t = time(i / per, i % per);
        if gathered {
            orbit.dofs_at(t, (&dofs.mech, &dofs.therm), x, v, temp);
        } else {
            orbit.state_at(t, x, v, temp);
        }
    }
    let mean_of = |k: usize, ws: &mut Workspace, mean: &mut NonlinearEval| {
        mean.clear();
        for (j, &wi) in weights.iter().enumerate() {
            let y = &states[(k * per + j) * width..(k * per + j + 1) * width];
            let (x, rest) = y.split_at(split);
            let (v, temp) = rest.split_at(split);
            if gathered {
                space.eval_nonlinear_gathered(time(k, j), x, v, temp, ws);
            } else {
                space.eval_nonlinear_at(time(k, j), x, v, temp, ws);
            }
            axpy_derivs(mean, 0.5 * wi, &ws.eval);
        }
        keep(mean)
    };
    if intervals >= 64 && rayon::current_num_threads() > 1 {
        (0..intervals)
            .into_par_iter()
            .map_init(
                || {
                    let w = space.workspace();
                    let mean = w.eval.clone();
                    (w, mean)
                },
                |(w, mean), k| mean_of(k, w, mean),
            )
            .collect()
    } else {
        let mut mean = ws.eval.clone();
        (0..intervals).map(|k| mean_of(k, ws, &mut mean)).collect()
    }
}

/// Evaluates the orbit and the nonlinear derivatives at `t` into `ws.eval`.
pub(crate) struct OrbitSampler<'o> {
    orbit: &'o dyn PeriodicOrbit,
    x: Vec<f64>,
    v: Vec<f64>,
    temp: Vec<f64>,
}

impl<'o> OrbitSampler<'o> {
    /// Buffers sized for `space`.
    pub(crate) fn new(orbit: &'o dyn PeriodicOrbit, space: &StateSpace<'_>) -> Self {
        Self {
            orbit,
            x: vec![0.0; space.n_mech()],
            v: vec![0.0; space.n_mech()],
            temp: vec![0.0; space.n_therm()],
        }
    }

    pub(crate) fn eval(&mut self, space: &StateSpace<'_>, t: f64, ws: &mut Workspace) {
        self.orbit
            .state_at(t, &mut self.x, &mut self.v, &mut self.temp);
        space.eval_nonlinear_at(t, &self.x, &self.v, &self.temp, ws);
    }
}

impl Sip {
    /// The plain product of paper Eq. 33 with exactly `intervals` intervals and series
    /// order `series_order` (no automatic refinement, no extrapolation; 3 Gauss points).
    ///
    /// Accuracy: the error falls as `(P/N_k)²`; measured at 256 intervals 3.8e-6 (absorber,
    /// Ω = 0.8), 3.9e-4 (Duffing resonant branch, Ω = 1.2), 2e-7 (Duffing, Ω = 0.8),
    /// 6.2e-4 (double-well Duffing at its period doubling).
    pub fn fixed(intervals: usize, series_order: usize) -> Self {
        Self {
            intervals,
            series_order,
            max_step_norm: f64::INFINITY,
            extrapolate: false,
            ..Self::default()
        }
    }

    fn check(&self) -> Result<(&'static [f64], &'static [f64]), StabilityError> {
        if self.intervals == 0 {
            return Err(StabilityError::Setting {
                field: "sip.intervals",
                value: "0".into(),
                reason: "need at least one interval",
            });
        }
        if self.series_order == 0 {
            return Err(StabilityError::Setting {
                field: "sip.series_order",
                value: "0".into(),
                reason: "need at least the linear term",
            });
        }
        if self.max_step_norm.is_nan() || self.max_step_norm <= 0.0 {
            return Err(StabilityError::Setting {
                field: "sip.max_step_norm",
                value: self.max_step_norm.to_string(),
                reason: "must be positive",
            });
        }
        gauss_legendre(self.gauss_points).ok_or(StabilityError::Setting {
            field: "sip.gauss_points",
            value: self.gauss_points.to_string(),
            reason: "supported: 1 to 5",
        })
    }

    /// The SIP monodromy matrix of `orbit`.
    pub fn monodromy(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<SipMonodromy, StabilityError> {
        self.run(system, orbit, false)
    }

    /// As [`Sip::monodromy`], also accumulating `ln|det E_k|` per factor (forms every
    /// factor explicitly and factors it: `O(d³)` extra per interval; for small systems and
    /// accuracy studies).
    pub fn monodromy_with_log_det(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<SipMonodromy, StabilityError> {
        self.run(system, orbit, true)
    }

    fn run(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        want_det: bool,
    ) -> Result<SipMonodromy, StabilityError> {
        let (nodes, weights) = self.check()?;
        let (space, omega, period) = state_space_for(system, orbit)?;
        let d = space.dim();
        let mut ws = space.workspace();
        let mut sampler = OrbitSampler::new(orbit, &space);

        let rho = self.rho_bound(&space, &mut sampler, period, &mut ws);
        let needed = if self.max_step_norm.is_finite() {
            (period * rho / self.max_step_norm).ceil()
        } else {
            0.0
        };
        if !needed.is_finite() {
            return Err(StabilityError::NonFinite { omega });
        }
        if needed > MAX_INTERVALS as f64 {
            return Err(StabilityError::Setting {
                field: "sip.intervals",
                value: format!("{needed:.3e}"),
                reason: "needed for Δ·ρ(B) ≤ max_step_norm exceeds the limit of 200000 \
                         intervals: the system is too stiff for the explicit SIP product \
                         (fast, heavily damped finite-element modes); reduce the model's \
                         highest frequencies or use the variational method",
            });
        }
        let mut intervals = self.intervals.max(needed as usize);
        let extrapolate = self.extrapolate && !want_det;
        if extrapolate {
            intervals += intervals % 2;
        }
        let delta = period / intervals as f64;

        let grid = MeanGrid {
            delta,
            intervals,
            nodes,
            weights,
        };
        let means = interval_means(&space, orbit, grid, &mut ws);

        let mut log_abs_det = None;
        let prod = if want_det {
            // Form every factor of Eq. 33 explicitly to accumulate its determinant.
            let ident = Mat::<f64>::identity(d, d);
            let (mut w, mut bw) = (Mat::<f64>::zeros(d, d), Mat::<f64>::zeros(d, d));
            let mut prod = Mat::<f64>::identity(d, d);
            let mut acc = 0.0;
            for mean in &means {
                self.apply_factor(&space, mean, delta, &ident, &mut w, &mut bw, &mut ws);
                acc += log_abs_det_of(w.as_ref());
                prod = &w * &prod;
            }
            log_abs_det = Some(acc);
            prod
        } else {
            // Eq. 33 on the running product. Its columns evolve independently
            // (P ← E_k P acts column by column), so blocks of columns run in parallel.
            by_column_blocks(d, |c0, c1| {
                self.product_block(&space, &means, delta, extrapolate, c0, c1)
            })
        };
        if !all_finite(prod.as_ref()) {
            return Err(StabilityError::NonFinite { omega });
        }
        Ok(SipMonodromy {
            matrix: prod,
            intervals,
            rho_bound: rho,
            log_abs_det,
        })
    }

    /// Upper bound of the spectral radius of `B(t)` (see the module docs).
    fn rho_bound(
        &self,
        space: &StateSpace<'_>,
        sampler: &mut OrbitSampler<'_>,
        period: f64,
        ws: &mut Workspace,
    ) -> f64 {
        let (mk, mc, ckt) = space.linear_blocks();
        let (mp, cq) = space.spread_columns();
        let (p, q) = (mp.ncols(), cq.ncols());
        let (mut kx, mut cv, mut tt) = (0.0f64, 0.0f64, 0.0f64);
        const SAMPLES: usize = 64;
        for j in 0..SAMPLES {
            sampler.eval(space, j as f64 * period / SAMPLES as f64, ws);
            kx = kx.max(inf_norm_product(mp, &ws.eval.df_dx, p));
            cv = cv.max(inf_norm_product(mp, &ws.eval.df_dv, p));
            tt = tt.max(inf_norm_product(cq, &ws.eval.dg_dt, q));
        }
        let mech = (inf_norm(mk) + kx).sqrt() + inf_norm(mc) + cv;
        let therm = inf_norm(ckt) + tt;
        mech.max(therm)
    }
}

/// State dimension from which a product is split into column blocks run in parallel.
const PARALLEL_MIN_DIM: usize = 48;

/// The first-order form of `system` at the orbit's `ω`, with `ω` and the period, after
/// checking the period.
pub(crate) fn state_space_for<'s>(
    system: &'s dyn System,
    orbit: &dyn PeriodicOrbit,
) -> Result<(StateSpace<'s>, f64, f64), StabilityError> {
    let omega = orbit.omega();
    let period = orbit.period();
    if !(period.is_finite() && period > 0.0) {
        return Err(StabilityError::Setting {
            field: "orbit.period",
            value: period.to_string(),
            reason: "must be positive and finite",
        });
    }
    let space = StateSpace::new(system, omega).map_err(|e| StabilityError::Setup {
        omega,
        reason: e.to_string(),
    })?;
    Ok((space, omega, period))
}

/// A `d × d` product whose columns evolve independently: `block(c0, c1)` computes columns
/// `c0..c1`; blocks run on the rayon threads when `d` is large enough.
pub(crate) fn by_column_blocks(
    d: usize,
    block: impl Fn(usize, usize) -> Mat<f64> + Sync,
) -> Mat<f64> {
    let blocks = if d >= PARALLEL_MIN_DIM {
        rayon::current_num_threads().clamp(1, d / (PARALLEL_MIN_DIM / 2))
    } else {
        1
    };
    let width = d.div_ceil(blocks).max(1);
    let ranges: Vec<(usize, usize)> = (0..d)
        .step_by(width)
        .map(|c0| (c0, (c0 + width).min(d)))
        .collect();
    let parts: Vec<Mat<f64>> = if ranges.len() > 1 {
        use rayon::prelude::*;
        ranges.par_iter().map(|&(c0, c1)| block(c0, c1)).collect()
    } else {
        ranges.iter().map(|&(c0, c1)| block(c0, c1)).collect()
    };
    let mut prod = Mat::<f64>::zeros(d, d);
    for (&(c0, c1), part) in ranges.iter().zip(&parts) {
        prod.as_mut()
            .subcols_mut(c0, c1 - c0)
            .copy_from(part.as_ref());
    }
    prod
}

impl Sip {
    /// Columns `c0..c1` of the SIP product (Eq. 33), with the optional extrapolation.
    fn product_block(
        &self,
        space: &StateSpace<'_>,
        means: &[NonlinearEval],
        delta: f64,
        extrapolate: bool,
        c0: usize,
        c1: usize,
    ) -> Mat<f64> {
        let d = space.dim();
        let c = c1 - c0;
        let start = Mat::<f64>::from_fn(d, c, |i, j| if i == c0 + j { 1.0 } else { 0.0 });
        let mut ws = space.workspace();
        let mut prod = start.clone();
        let mut coarse = extrapolate.then(|| start.clone());
        let (mut w, mut bw) = (Mat::<f64>::zeros(d, c), Mat::<f64>::zeros(d, c));
        let mut coarse_mean = means.first().cloned();
        for (k, mean) in means.iter().enumerate() {
            self.apply_factor(space, mean, delta, &prod, &mut w, &mut bw, &mut ws);
            std::mem::swap(&mut prod, &mut w);
            // The coarse product over pairs of intervals, for extrapolation; the mean over
            // a pair is the average of the two means.
            if let (Some(coarse), Some(cm)) = (coarse.as_mut(), coarse_mean.as_mut()) {
                if k % 2 == 0 {
                    cm.clear();
                    axpy_derivs(cm, 0.5, mean);
                } else {
                    axpy_derivs(cm, 0.5, mean);
                    self.apply_factor(space, cm, 2.0 * delta, coarse, &mut w, &mut bw, &mut ws);
                    std::mem::swap(coarse, &mut w);
                }
            }
        }
        if let Some(coarse) = coarse.as_ref() {
            // Richardson: E ≈ (4 E_Δ − E_2Δ) / 3 removes the Δ² error term.
            for col in 0..c {
                let (pc, cc) = (prod.col_mut(col), coarse.col(col));
                for (r, pv) in pc.iter_mut().enumerate() {
                    *pv = (4.0 * *pv - cc[r]) / 3.0;
                }
            }
        }
        prod
    }

    /// `w = (I + Σ_{i=1}^{N_i} (Δ B)^i / i!) base` by Horner's scheme, `B` from `mean`.
    #[allow(clippy::too_many_arguments)]
    fn apply_factor(
        &self,
        space: &StateSpace<'_>,
        mean: &NonlinearEval,
        delta: f64,
        base: &Mat<f64>,
        w: &mut Mat<f64>,
        bw: &mut Mat<f64>,
        ws: &mut Workspace,
    ) {
        w.copy_from(base);
        for i in (1..=self.series_order).rev() {
            space.apply_linearization(mean, w.as_ref(), bw.as_mut(), ws);
            let c = delta / i as f64;
            for col in 0..base.ncols() {
                let (wc, bc, pc) = (w.col_mut(col), bw.col(col), base.col(col));
                for (r, wv) in wc.iter_mut().enumerate() {
                    *wv = pc[r] + c * bc[r];
                }
            }
        }
    }
}

pub(crate) fn log_abs_det_of(a: MatRef<'_, f64>) -> f64 {
    let d = a.nrows();
    if d == 0 {
        return 0.0;
    }
    let lu = a.partial_piv_lu();
    let u = lu.U();
    (0..d).map(|i| u[(i, i)].abs().ln()).sum()
}

impl StabilityMethod for Sip {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        let mono = self.monodromy(system, orbit)?;
        eigenvalues_checked(mono.matrix.as_ref(), orbit.omega()).map(FloquetResult::new)
    }
}
