//! The coupled Floquet exponents nearest zero, exactly: Hill's eigenproblem of the
//! harmonic balance, solved by shift-invert Arnoldi.
//!
//! ## Why
//! A thermo-mechanical orbit has Floquet exponents on two time scales: the vibration's
//! (`|λ|` of the order of the damping rates) and the temperatures' (`1/τ`, seconds to
//! hours). Where a fast exponent comes near zero (a fold of the vibration with the
//! temperatures frozen) the two interact: the thermal feedback can turn a real fast
//! exponent and a slow one into a complex pair, a slow thermo-mechanical oscillation of
//! the whole orbit. Neither the frozen-temperature monodromy product (it holds the
//! temperatures) nor a quasi-static reduction (it assumes `|λ|` far below every fast
//! exponent) sees that. The exponents of the full coupled linearisation nearest zero do.
//!
//! ## What
//! A perturbation `e^{λt} p(t)` of a periodic orbit, `p` on the harmonic-balance basis,
//! satisfies Hill's quadratic eigenproblem
//!
//! ```text
//!   T(λ) p = (A0 + λ A1 + λ² A2) p = 0
//!   A0 = ∂R/∂A                           (the harmonic-balance Jacobian)
//!   A1 = [C + P[∂f/∂ẋ]] + 2 M D   (mech),   C_T + P[∂g/∂ẋ]  (thermal rows)
//!   A2 = M                               (mech)
//! ```
//!
//! (`D` the derivative on the basis, `P[·]` the Galerkin projection): the `λ` terms are
//! the rate of `e^{λt}p` (`ṗ + λp`) and its second derivative (`p̈ + 2λṗ + λ²p`) in the
//! equations of motion, and the thermal capacity's `λ C_T`. Each eigenvalue `λ` with
//! `|Im λ| < ω_b/2` (`ω_b = 2π/P`) is a Floquet exponent of the truncated balance, with
//! multiplier `exp(λP)`. `det T(0) = det ∂R/∂A`, so a real exponent passes zero exactly
//! where the branch folds.
//!
//! ## How
//! The linearisation `[[0, I], [−A0, 0]] w = λ [[E_mᵀ, 0], [A1, A2]] w`,
//! `w = [p; λ p_m]` (the rate only of the mechanical unknowns `p_m`: the thermal
//! equations are of first order and `A2` acts on the mechanical unknowns alone), is
//! shift-inverted at a small real shift `σ`: one application of `(L − σB)⁻¹ B` costs
//! the products with `A1` and `A2` and one solve with `T(σ)`. `T(σ)` has the harmonic-balance Jacobian's structure (per-harmonic linear
//! blocks with `K → K + σC + σ²M`, `C → C + 2σM`, `K_T → K_T + σC_T`, and the dense
//! nonlinear block plus `σ P[∂f/∂ẋ]`), so it is factored by the same condensation of
//! the linear DoFs ([`crate::hb::LinearSolver`]). Arnoldi with full
//! reorthogonalisation finds the Ritz values `θ` of largest modulus, `λ = σ + 1/θ`,
//! accepted when their residual estimate is below a relative tolerance.

use std::borrow::Cow;

use faer::Mat;
use num_complex::Complex64;

use super::StabilityError;
use crate::hb::condense::dot;
use crate::hb::{HarmonicBalance, HbSolution, JacobianParts, LinearSolver};
use crate::system::{DenseMatrix, LinearPart};

/// Settings of the near-zero Hill eigenvalues.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HillOptions {
    /// Fast (non-thermal) exponents wanted beyond the thermal ones: the solver converges
    /// the `n_therm + extra` eigenvalues nearest the shift.
    pub extra: usize,
    /// Largest radius of the disk around zero, as a fraction of the base frequency
    /// `ω_b = 2π/P`: inside `ω_b/2` each Floquet exponent appears once (its copies
    /// `λ + i k ω_b` lie outside).
    pub max_radius_fraction: f64,
    /// Relative residual estimate below which a Ritz value is accepted.
    pub tol: f64,
    /// Largest Krylov dimension (raised to twice the wanted count + 40 where that is
    /// more: a large thermal network wants many exponents).
    pub max_dim: usize,
    /// Vectors the Krylov space grows by at each step (a block Arnoldi): the shifted
    /// operator is applied to all of them with one solve of many right-hand sides, which
    /// reads the factors of `T(σ)` once per block instead of once per vector. 1 is the
    /// classical (single-vector) Arnoldi, which spaces smaller than four times the largest
    /// Krylov dimension use whatever this says; 0 chooses: [`AUTO_BLOCK`] vectors where the condensed system
    /// has [`AUTO_BLOCK_FROM`] unknowns or more, else one.
    pub block: usize,
}

impl Default for HillOptions {
    /// `extra = 4`, disk up to `0.4 ω_b`, tolerance 1e-10, at most 400 Krylov vectors,
    /// the block size chosen by the system's size ([`AUTO_BLOCK`]).
    ///
    /// Four fast exponents beyond the thermal ones: with two, the disk's edge fell among
    /// the modes the thermal coupling reorders near a fast fold, and the joined count
    /// ([`super::join`]) had to guess across it (the single-shaft rotor of
    /// `examples/rotors/two_disk_ball_bearings.toml`: one unlocated change of stability
    /// left with two, none with four; see `docs/stability.md`).
    fn default() -> Self {
        Self {
            extra: 4,
            max_radius_fraction: 0.4,
            tol: 1e-10,
            max_dim: 400,
            block: 0,
        }
    }
}

/// The block size [`HillOptions::block`] `= 0` chooses on large condensed systems.
///
/// A block converges the same exponents with more vectors than the classical iteration
/// (on the dual rotor, 70 wanted: about 130 with blocks of 4, 170 of 8, 240 of 16, against
/// 97 one at a time), and each vector's solve gets cheaper as the factors it shares grow:
/// measured per point, order 3 (612 condensed unknowns) 53 ms either way, order 4 (756)
/// 112 → 102 ms, order 5 (900) 143 → 127 ms, order 7 (1 116) 262 → 176 ms with 4, 207 ms
/// with 8 (docs/performance.md).
pub const AUTO_BLOCK: usize = 4;

/// The condensed size from which [`HillOptions::block`] `= 0` uses [`AUTO_BLOCK`].
///
/// The dual rotor at order 3 (612 condensed unknowns, 70 exponents wanted), one thread,
/// with the binaries' allocator: 31.6–31.9 ms a point one vector a step (101 vectors on
/// average), 27.8–28.9 ms with blocks of four (138 vectors). The figures above, and an
/// earlier comparison at order 3 that favoured one vector a step, were taken with the
/// system allocator, which maps and unmaps the larger basis at every point
/// (docs/performance.md, fifth session). Below 612 (`examples/hill_spectrum.rs` over every
/// point of a sweep, one thread, two rounds; docs/performance.md, ninth session): the
/// Arnoldi iteration took less with blocks of four, or as long within 1 %, at every size
/// measured: 540 (order 3 without half orders: literature values 24.9 → 21.7 ms a point,
/// built-in 25.4 → 24.4), 468 (order 2, 19.6 → 16.7), 396 (order 2 without half orders,
/// 15.7 → 15.8) and 324 (order 1, 12.2 → 11.6). Below 324 not measured.
pub const AUTO_BLOCK_FROM: usize = 320;

/// The Floquet exponents of the truncated balance in a disk around zero.
#[derive(Clone, Debug, PartialEq)]
pub struct NearZero {
    /// Exponents `λ` (1/s), sorted by modulus, every one with `|λ| < radius`.
    pub exponents: Vec<Complex64>,
    /// Radius of the disk (1/s): every exponent of the balance inside it is in
    /// `exponents`; the fast multipliers of a monodromy product with `|ln μ|/P` below it
    /// are superseded by these.
    pub radius: f64,
    /// How far the edge may move out (1/s): the modulus of the nearest converged exponent
    /// left out of `exponents`, or the largest radius asked for. Any edge between the
    /// largest kept modulus and this one bounds the same set.
    pub outer: f64,
    /// How many of `exponents` belong to the thermal equations (one per thermal state;
    /// 0 when not known): the rest are the mechanical exponents a monodromy product of
    /// the frozen-temperature problem also estimates.
    pub thermal: usize,
    /// Arnoldi steps taken (solves with `T(σ)`).
    pub steps: usize,
}

/// A Floquet mode of the truncated balance near zero: the exponent `λ` and the harmonic
/// coefficients of its periodic factor `p` (a perturbation `Re(e^{λt} p(t))` of the
/// orbit), in the layout of the balance's unknowns (mechanical DoFs, then thermal, each
/// `1 + 2H` coefficients), complex, with unit Euclidean norm.
#[derive(Clone, Debug, PartialEq)]
pub struct HillMode {
    pub exponent: Complex64,
    pub coeffs: Vec<Complex64>,
}

impl HillMode {
    /// The perturbation `e^{λt} p(t)` at time `t` as a complex state `[x, v, T]` (lengths
    /// `n_mech`, `n_mech`, `n_therm`), `p` on `basis` at `omega`: `x = e^{λt} p`,
    /// `v = e^{λt} (λ p + ṗ)`. Its real part (or that of any complex multiple) is a
    /// perturbation of the orbit along the mode.
    pub fn state_at(
        &self,
        basis: &crate::hb::Basis,
        omega: f64,
        n_mech: usize,
        t: f64,
    ) -> (Vec<Complex64>, Vec<Complex64>, Vec<Complex64>) {
        let part = |f: fn(&Complex64) -> f64| -> HbSolution {
            let u: Vec<f64> = self.coeffs.iter().map(f).collect();
            HbSolution::from_unknowns(omega, basis, n_mech, &u, &Default::default())
        };
        let (re, im) = (part(|c| c.re), part(|c| c.im));
        let n_therm = re.n_therm();
        let eval = |s: &HbSolution| {
            let (mut x, mut v, mut th) = (vec![0.0; n_mech], vec![0.0; n_mech], vec![0.0; n_therm]);
            crate::system::PeriodicOrbit::state_at(s, t, &mut x, &mut v, &mut th);
            (x, v, th)
        };
        let ((xr, vr, tr), (xi, vi, ti)) = (eval(&re), eval(&im));
        let g = (self.exponent * t).exp();
        let lam = self.exponent;
        let zip = |a: &[f64], b: &[f64]| -> Vec<Complex64> {
            a.iter()
                .zip(b)
                .map(|(&r, &i)| Complex64::new(r, i))
                .collect()
        };
        let (x, dp, th) = (zip(&xr, &xi), zip(&vr, &vi), zip(&tr, &ti));
        let v = x
            .iter()
            .zip(&dp)
            .map(|(&p, &d)| g * (lam * p + d))
            .collect();
        (
            x.into_iter().map(|p| g * p).collect(),
            v,
            th.into_iter().map(|p| g * p).collect(),
        )
    }
}

/// Hill's pencil `T(λ)` of the harmonic balance at a converged point.
pub struct HillPencil<'a, 'h> {
    hb: &'a HarmonicBalance<'h>,
    /// `∂R/∂A` at the point: the one handed over (borrowed: megabytes a point) or
    /// evaluated here.
    parts: Cow<'a, JacobianParts>,
    /// The velocity sensitivity ([`HarmonicBalance::velocity_sensitivity`]); `None` where
    /// it is zero.
    velocity: Option<Vec<f64>>,
    /// The `(row, column)` nonlinear-DoF blocks of `velocity` with a nonzero entry (most
    /// are zero: only velocity-dependent forces and heat have one).
    velocity_blocks: Vec<(usize, usize)>,
    /// Global DoF of each nonlinear DoF ([`HarmonicBalance::nonlinear_global`]).
    globals: Vec<usize>,
}

impl<'a, 'h> HillPencil<'a, 'h> {
    /// The pencil at `solution`, a converged point of `hb`; `parts`, when given and at the
    /// same ω, is `∂R/∂A` there (the corrector's).
    pub fn new(
        hb: &'a HarmonicBalance<'h>,
        solution: &HbSolution,
        parts: Option<&'a JacobianParts>,
    ) -> Result<Self, StabilityError> {
        let omega = solution.omega;
        let setup = |reason: String| StabilityError::Setup { omega, reason };
        let coeffs = solution.unknowns();
        // the Jacobian and the velocity sensitivity from one evaluation of the samples
        // where the Jacobian is not given
        let (parts, velocity) = match parts.filter(|p| p.omega == omega) {
            // (its flag says whether any sample has a velocity derivative)
            Some(p) if !p.velocity_dependent => (Cow::Borrowed(p), Ok(None)),
            Some(p) => (
                Cow::Borrowed(p),
                hb.velocity_sensitivity_if_any(&coeffs, omega),
            ),
            None => {
                let mut r = vec![0.0; coeffs.len()];
                let (p, v) = hb
                    .residual_jacobian_velocity(&coeffs, omega, &mut r)
                    .map_err(|e| setup(e.to_string()))?;
                (Cow::Owned(p), Ok(v))
            }
        };
        let velocity = velocity.map_err(|e| setup(e.to_string()))?;
        let nc = hb.n_coeffs();
        let globals = hb.nonlinear_global();
        let pt = globals.len();
        let ld = pt * nc;
        let velocity_blocks = match &velocity {
            Some(v) => (0..pt)
                .flat_map(|k| (0..pt).map(move |l| (k, l)))
                .filter(|&(k, l)| {
                    (0..nc).any(|r| {
                        v[(k * nc + r) * ld + l * nc..(k * nc + r) * ld + (l + 1) * nc]
                            .iter()
                            .any(|x| *x != 0.0)
                    })
                })
                .collect(),
            None => Vec::new(),
        };
        Ok(Self {
            hb,
            parts,
            velocity,
            velocity_blocks,
            globals,
        })
    }

    /// The share of the thermal capacity in the mode of the exponent `lambda` (one of
    /// [`Self::near_zero`]'s with `want`): `−(C_T/λ) ∂λ/∂C_T` by a relative change of
    /// 1e-3 of every thermal capacity, its real part clamped to `[0, 1]`. A purely thermal
    /// mode (`λ ∝ 1/C_T`) has share 1, a purely mechanical one 0.
    pub fn thermal_share(
        &self,
        lambda: Complex64,
        want: usize,
        options: &HillOptions,
    ) -> Result<f64, StabilityError> {
        let eps = 1e-3;
        let mut scaled_parts = (*self.parts).clone();
        scaled_parts
            .linear
            .thermal_capacity
            .data
            .iter_mut()
            .for_each(|c| *c *= 1.0 + eps);
        let scaled = HillPencil {
            hb: self.hb,
            parts: Cow::Owned(scaled_parts),
            velocity: self.velocity.clone(),
            velocity_blocks: self.velocity_blocks.clone(),
            globals: self.globals.clone(),
        };
        let nz = scaled.near_zero(want, options)?;
        let moved = nz
            .exponents
            .iter()
            .min_by(|a, b| (*a - lambda).norm().total_cmp(&(*b - lambda).norm()))
            .ok_or_else(|| StabilityError::Setup {
                omega: self.parts.omega,
                reason: "no exponent near the crossing one with the thermal capacity changed"
                    .into(),
            })?;
        let share = -((moved - lambda) / (eps * lambda)).re;
        Ok(share.clamp(0.0, 1.0))
    }

    /// `T(s)` in the structured form of the Jacobian (see the module docs).
    pub fn at(&self, s: f64) -> JacobianParts {
        let lin = &self.parts.linear;
        let comb = |terms: &[(f64, &DenseMatrix)], n: usize| {
            let mut out = DenseMatrix::zeros(n);
            for (f, m) in terms {
                if *f != 0.0 {
                    out.data
                        .iter_mut()
                        .zip(&m.data)
                        .for_each(|(o, v)| *o += f * v);
                }
            }
            out
        };
        let (n, nt) = (lin.mass.n, lin.thermal_capacity.n);
        let linear = LinearPart {
            mass: lin.mass.clone(),
            damping: comb(&[(1.0, &lin.damping), (2.0 * s, &lin.mass)], n),
            stiffness: comb(
                &[(1.0, &lin.stiffness), (s, &lin.damping), (s * s, &lin.mass)],
                n,
            ),
            thermal_capacity: lin.thermal_capacity.clone(),
            thermal_conductance: comb(
                &[(1.0, &lin.thermal_conductance), (s, &lin.thermal_capacity)],
                nt,
            ),
        };
        let nonlinear = match &self.velocity {
            Some(velocity) => self
                .parts
                .nonlinear
                .iter()
                .zip(velocity)
                .map(|(j, v)| j + s * v)
                .collect(),
            None => self.parts.nonlinear.clone(),
        };
        JacobianParts {
            omega: self.parts.omega,
            linear,
            nonlinear,
            velocity_dependent: self.velocity.is_some(),
        }
    }

    /// `out += V x` with `V` the velocity sensitivity, on its nonzero blocks.
    fn add_velocity(&self, x: &[f64], out: &mut [f64]) {
        let Some(velocity) = &self.velocity else {
            return;
        };
        let nc = self.hb.n_coeffs();
        let ld = self.globals.len() * nc;
        for &(k, l) in &self.velocity_blocks {
            let (gk, gl) = (self.globals[k], self.globals[l]);
            let xs = &x[gl * nc..(gl + 1) * nc];
            for r in 0..nc {
                let row = &velocity[(k * nc + r) * ld + l * nc..(k * nc + r) * ld + (l + 1) * nc];
                out[gk * nc + r] += dot(row, xs);
            }
        }
    }

    /// The exponents nearest zero (see [`NearZero`]), with `want` of them converged at
    /// least (fewer when the disk of `options.max_radius_fraction · ω_b` holds fewer).
    pub fn near_zero(
        &self,
        want: usize,
        options: &HillOptions,
    ) -> Result<NearZero, StabilityError> {
        self.near_zero_impl(want, options, false).map(|(z, _)| z)
    }

    /// [`Self::near_zero`] with the mode of each exponent found (in the same order): the
    /// Ritz vectors of the Arnoldi iteration, whose residual is below the same tolerance.
    pub fn near_zero_modes(
        &self,
        want: usize,
        options: &HillOptions,
    ) -> Result<Vec<HillMode>, StabilityError> {
        let (z, modes) = self.near_zero_impl(want, options, true)?;
        let nu = self.hb.n_unknowns();
        Ok(z.exponents
            .into_iter()
            .zip(modes)
            .map(|(exponent, mut v)| {
                v.truncate(nu);
                let norm = v.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
                if norm > 0.0 {
                    v.iter_mut().for_each(|c| *c /= norm);
                }
                HillMode {
                    exponent,
                    coeffs: v,
                }
            })
            .collect())
    }

    fn near_zero_impl(
        &self,
        want: usize,
        options: &HillOptions,
        vectors: bool,
    ) -> Result<(NearZero, Vec<Vec<Complex64>>), StabilityError> {
        let omega = self.parts.omega;
        let setup = |reason: String| StabilityError::Setup { omega, reason };
        let nu = self.hb.n_unknowns();
        let nm = self.hb.n_mech_unknowns();
        let dim = nu + nm;
        let wb = self.hb.aft().base_frequency(omega);
        let r_max = options.max_radius_fraction * wb;
        // a shift slightly off zero (the Jacobian is singular at folds), small against
        // the disk; a second one if T(σ) happens to be singular there
        let mut last_err = String::new();
        let want = want.min(dim.saturating_sub(2)).max(1);
        let block = match options.block {
            0 if self.globals.len() * self.hb.n_coeffs() >= AUTO_BLOCK_FROM => AUTO_BLOCK,
            0 => 1,
            b => b,
        };
        // the factors in the layout for the block size the iteration will use
        let (_, p) = krylov_limits(dim, want, options, block);
        for shift in [1e-3 * r_max, -2.3e-3 * r_max] {
            let (solver, t) = (LinearSolver::default(), self.at(shift));
            let factored = if p > 1 {
                solver.factor_for_blocks(self.hb, &t, None)
            } else {
                solver.factor(self.hb, &t, None)
            };
            let fact = match factored {
                Ok(f) => f,
                Err(e) => {
                    last_err = e.to_string();
                    continue;
                }
            };
            let lin = &self.parts.linear;
            // A1 (the thermal rows' C_T, the mechanical C and 2M·D) and A2 (M)
            let a1 = LinearPart {
                mass: DenseMatrix::zeros(lin.mass.n),
                damping: scaled(&lin.mass, 2.0),
                stiffness: lin.damping.clone(),
                thermal_capacity: DenseMatrix::zeros(lin.thermal_capacity.n),
                thermal_conductance: lin.thermal_capacity.clone(),
            };
            let a2 = LinearPart {
                mass: DenseMatrix::zeros(lin.mass.n),
                damping: DenseMatrix::zeros(lin.mass.n),
                stiffness: lin.mass.clone(),
                thermal_capacity: DenseMatrix::zeros(lin.thermal_capacity.n),
                thermal_conductance: DenseMatrix::zeros(lin.thermal_capacity.n),
            };
            // their nonzeros once: the operator applies them at every Arnoldi step
            let (a1, a2) = (self.hb.sparse_linear(&a1), self.hb.sparse_linear(&a2));
            // u = [x; y] with y = λ x_m on the mechanical unknowns only (the thermal
            // equations are of first order): r = A1 x + A2 (y + σ x_m),
            // z = −T(σ)⁻¹ r, out = [z; x_m + σ z_m]
            let mut w = vec![0.0; nu];
            let mut r = vec![0.0; nu];
            let op = |u: faer::MatRef<'_, f64>| -> Result<Mat<f64>, String> {
                let k = u.ncols();
                let mut rs = Mat::<f64>::zeros(nu, k);
                let mut x = vec![0.0; nu];
                for col in 0..k {
                    for (i, xi) in x.iter_mut().enumerate() {
                        *xi = u[(i, col)];
                    }
                    for i in 0..nm {
                        w[i] = u[(nu + i, col)] + shift * x[i];
                    }
                    r.iter_mut().for_each(|v| *v = 0.0);
                    a2.apply(self.hb, omega, &w, &mut r);
                    a1.apply(self.hb, omega, &x, &mut r);
                    self.add_velocity(&x, &mut r);
                    for (i, v) in r.iter().enumerate() {
                        rs[(i, col)] = *v;
                    }
                }
                let (z, _) = fact
                    .solve_many(rs.as_ref(), &vec![0.0; k])
                    .map_err(|e| e.to_string())?;
                let mut out = Mat::<f64>::zeros(dim, k);
                for col in 0..k {
                    for i in 0..nu {
                        out[(i, col)] = -z[(i, col)];
                    }
                    for i in 0..nm {
                        out[(nu + i, col)] = u[(i, col)] - shift * z[(i, col)];
                    }
                }
                Ok(out)
            };
            return arnoldi_nearest(op, dim, want, shift, r_max, options, block, vectors)
                .map_err(|e| setup(format!("Hill eigenvalues near zero: {e}")));
        }
        Err(setup(format!("Hill's matrix at the shift: {last_err}")))
    }
}

/// The coupled exponents nearest zero of `solution`, a converged point of `hb` with a
/// thermal field: the `n_therm + options.extra` nearest (see [`HillPencil::near_zero`]).
/// `jacobian`, when given, is `∂R/∂A` at the point.
pub fn near_zero_exponents(
    hb: &HarmonicBalance<'_>,
    solution: &HbSolution,
    jacobian: Option<&JacobianParts>,
    options: &HillOptions,
) -> Result<NearZero, StabilityError> {
    let mut nz = HillPencil::new(hb, solution, jacobian)?
        .near_zero(hb.n_therm() + options.extra, options)?;
    nz.thermal = hb.n_therm();
    Ok(nz)
}

fn scaled(m: &DenseMatrix, f: f64) -> DenseMatrix {
    DenseMatrix {
        n: m.n,
        data: m.data.iter().map(|v| f * v).collect(),
    }
}

/// Deterministic vectors with no structure (a linear congruential sequence): the start
/// block's columns, then fresh directions for a block whose vectors became dependent.
struct Directions(u64);

impl Directions {
    fn new() -> Self {
        Self(0x9E37_79B9_7F4A_7C15)
    }

    /// The next vector of length `dim`.
    fn next(&mut self, dim: usize) -> Vec<f64> {
        (0..dim)
            .map(|_| {
                self.0 = self
                    .0
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((self.0 >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect()
    }
}

/// Takes the orthonormal columns of `q` out of `v`, two passes (modified Gram–Schmidt);
/// what was taken out, one coefficient per column.
fn take_out(q: faer::MatRef<'_, f64>, mut v: faer::ColMut<'_, f64>) -> Vec<f64> {
    let mut taken = vec![0.0; q.ncols()];
    for _ in 0..2 {
        for (l, t) in taken.iter_mut().enumerate() {
            let d = q.col(l).transpose() * v.as_ref();
            v.as_mut()
                .iter_mut()
                .zip(q.col(l).iter())
                .for_each(|(x, y)| *x -= d * y);
            *t += d;
        }
    }
    taken
}

/// Orthonormalises the columns of `w` against the `q` columns (two passes of classical
/// Gram–Schmidt as products) and among themselves (two passes of modified Gram–Schmidt):
/// `w_in = q c + w_out r` with `r` upper triangular. Returns `(c, r, deflated)`. A column
/// that falls below `1e-13` of its norm before the projections is dependent on `q` and
/// the block's earlier columns (with one column: the Krylov space is invariant, the
/// classical iteration's breakdown): its `r` diagonal is that remainder and, when `fresh`
/// is given, its place is taken by a vector from `fresh` orthonormalised in the same way
/// (the block grows on past a dependent direction).
fn orthonormalise(
    q: faer::MatRef<'_, f64>,
    w: &mut Mat<f64>,
    mut fresh: Option<&mut Directions>,
) -> (Mat<f64>, Mat<f64>, bool) {
    let p = w.ncols();
    let mut r = Mat::<f64>::zeros(p, p);
    let mut deflated = false;
    let against_q = |w: &mut Mat<f64>| {
        let mut total = Mat::<f64>::zeros(q.ncols(), w.ncols());
        if q.ncols() > 0 {
            for _ in 0..2 {
                let d = q.transpose() * w.as_ref();
                *w -= q * d.as_ref();
                total += d;
            }
        }
        total
    };
    // each column's norm before any projection: what a dependent column is measured by
    let norms: Vec<f64> = (0..p).map(|i| w.col(i).norm_l2()).collect();
    let c = against_q(w);
    for i in 0..p {
        let (done, mut rest) = w.as_mut().split_at_col_mut(i);
        for (l, d) in take_out(done.as_ref(), rest.as_mut().col_mut(0))
            .into_iter()
            .enumerate()
        {
            r[(l, i)] = d;
        }
        let norm = w.col(i).norm_l2();
        r[(i, i)] = norm;
        if norm > 1e-13 * norms[i] && norm > 0.0 {
            w.col_mut(i).iter_mut().for_each(|x| *x /= norm);
            continue;
        }
        deflated = true;
        let Some(directions) = fresh.as_deref_mut() else {
            continue;
        };
        // a fresh direction, orthogonal to q and the block's earlier columns
        let f = directions.next(w.nrows());
        let mut v = Mat::from_fn(w.nrows(), 1, |k, _| f[k]);
        against_q(&mut v);
        take_out(w.as_ref().subcols(0, i), v.col_mut(0));
        let nv = v.col(0).norm_l2();
        w.col_mut(i)
            .iter_mut()
            .zip(v.col(0).iter())
            .for_each(|(x, y)| *x = y / nv);
    }
    (c, r, deflated)
}

/// The largest Krylov dimension and the block size of [`arnoldi_nearest`] for `want`
/// eigenvalues of an operator of dimension `dim`, `block` vectors asked for a step.
fn krylov_limits(dim: usize, want: usize, options: &HillOptions, block: usize) -> (usize, usize) {
    // at least twice the wanted count (a large thermal network wants many)
    let max_dim = options.max_dim.max(2 * want + 40).min(dim);
    // blocks only where the space is far larger than the part of it used: on a small one
    // (the one-DoF oscillator's 57 unknowns, blocks of 4) the Krylov space becomes
    // invariant, the block's dependent vectors are replaced by fresh ones, and the
    // wanted values were not all converged when the space ran out
    let p = if dim >= 4 * max_dim {
        block.clamp(1, (max_dim / 4).max(1))
    } else {
        1
    };
    // in whole blocks
    (if p > 1 { (max_dim / p) * p } else { max_dim }, p)
}

/// Block Arnoldi on the shift-inverted operator `op` (dimension `dim`, applied to a block
/// of vectors at once) until the `want` eigenvalues nearest `shift` and the next one are
/// converged, or every eigenvalue in the disk of radius `r_max` is, or the Krylov space
/// is exhausted. The space grows by `block` vectors a step (see [`HillOptions::block`]);
/// with one it is the classical Arnoldi iteration.
#[allow(clippy::too_many_arguments)]
fn arnoldi_nearest(
    mut op: impl FnMut(faer::MatRef<'_, f64>) -> Result<Mat<f64>, String>,
    dim: usize,
    want: usize,
    shift: f64,
    r_max: f64,
    options: &HillOptions,
    block: usize,
    vectors: bool,
) -> Result<(NearZero, Vec<Vec<Complex64>>), String> {
    let (max_dim, p) = krylov_limits(dim, want, options, block);
    let round = |k: usize| k.div_ceil(p) * p;
    // the Krylov basis as columns, orthogonalised by Gram–Schmidt in matrix form (the
    // cost of the method besides the solves), allocated for the first look and grown as
    // the iteration goes on: most points converge in a quarter of `max_dim`, and a basis
    // allocated in full is megabytes of fresh pages zeroed at every point
    // The first look: the classical iteration has converged the wanted values after
    // about a third more vectors than wanted (on the dual rotor, 70 wanted: 85–103), a
    // block one after a third more again (blocks of 4, checked after every block: 116–144
    // at order 3, 45 % by 128; 128–144 at order 5, 48 % by 128), and each look that finds
    // too few costs an eigendecomposition of the Hessenberg matrix (measured on one
    // thread: about 2 ms at 96 columns, 3 ms at 120–132): a block iteration looks at 128
    // and then every two blocks, the classical one at 96 and then every twelve vectors.
    let first = (want + want / 3 + 4).min(96);
    let first = if p > 1 { first + first / 3 } else { first };
    let mut next_check = round(first).min(max_dim);
    let mut basis = Mat::<f64>::zeros(dim, (next_check + p).min(max_dim + p));
    // the block Hessenberg matrix: `hh[(i, j)]` for the columns so far, one block of
    // rows more than the basis has columns, grown with it (in full it is another
    // megabyte of fresh pages at every point)
    let mut hh = Mat::<f64>::zeros(basis.ncols() + p, basis.ncols());
    let mut directions = Directions::new();
    let columns: Vec<Vec<f64>> = (0..p).map(|_| directions.next(dim)).collect();
    let mut start = Mat::from_fn(dim, p, |i, j| columns[j][i]);
    orthonormalise(basis.as_ref().subcols(0, 0), &mut start, None);
    basis.as_mut().subcols_mut(0, p).copy_from(&start);
    // the first look as above (`next_check`), then every twelve vectors (eight with
    // blocks; early enough for a large network whose disk holds fewer than the wanted
    // count), in whole blocks
    let mut m = 0;
    loop {
        let mut w = op(basis.as_ref().subcols(m, p))?;
        if w.col_iter().any(|c| c.iter().any(|x| !x.is_finite())) {
            return Err("the shifted operator gave non-finite values".into());
        }
        let q = basis.as_ref().subcols(0, m + p);
        let fresh = (p > 1).then_some(&mut directions);
        let (c, r, deflated) = orthonormalise(q, &mut w, fresh);
        hh.as_mut().submatrix_mut(0, m, m + p, p).copy_from(&c);
        hh.as_mut().submatrix_mut(m + p, m, p, p).copy_from(&r);
        m += p;
        // the classical iteration breaks down when the new vector vanishes: the space
        // is invariant and its Ritz values exact
        let breakdown = p == 1 && deflated;
        if m >= next_check || breakdown || m >= max_dim {
            let qm = vectors.then(|| basis.as_ref().subcols(0, m));
            let hm = hh.as_ref().submatrix(0, 0, m, m);
            let coupling = hh.as_ref().submatrix(m, m - p, p, p);
            if let Some((found, modes)) = ritz_check(
                hm,
                coupling,
                want,
                (shift, r_max),
                options.tol,
                breakdown || m >= dim,
                qm,
            ) {
                return Ok((NearZero { steps: m, ..found }, modes));
            }
            if breakdown || m >= max_dim {
                return Err(format!(
                    "not converged in {m} Arnoldi steps (dimension {dim})"
                ));
            }
            next_check = (m + round(if p > 1 { 8 } else { 12 })).min(max_dim);
        }
        if basis.ncols() < m + p {
            let cols = (next_check + p).min(max_dim + p).max(m + p);
            basis.resize_with(dim, cols, |_, _| 0.0);
            hh.resize_with(cols + p, cols, |_, _| 0.0);
        }
        basis.as_mut().subcols_mut(m, p).copy_from(&w);
    }
}

/// The converged eigenvalues nearest the shift from the block Hessenberg matrix `hm` of
/// the steps so far (`coupling`: its last block's entries in the next block of vectors),
/// when the `want` nearest and the one after them (or all in the disk `r_max`) are; with
/// `basis` (the Krylov vectors), the Ritz vector of each too.
fn ritz_check(
    hm: faer::MatRef<'_, f64>,
    coupling: faer::MatRef<'_, f64>,
    want: usize,
    (shift, r_max): (f64, f64),
    tol: f64,
    exact: bool,
    basis: Option<faer::MatRef<'_, f64>>,
) -> Option<(NearZero, Vec<Vec<Complex64>>)> {
    let m = hm.nrows();
    let p = coupling.nrows();
    let eig = hm.to_owned().eigen().ok()?;
    let (s, u) = (eig.S(), eig.U());
    let mut ritz: Vec<(Complex64, bool, usize)> = (0..m)
        .filter_map(|k| {
            let theta: Complex64 = s[k];
            if !theta.re.is_finite() || !theta.im.is_finite() || theta.norm() == 0.0 {
                return None;
            }
            let norm = (0..m).map(|i| u[(i, k)].norm_sqr()).sum::<f64>().sqrt();
            // the residual `‖(A V − V H) y‖ = ‖R y_last‖`, `y_last` the Ritz vector's
            // last block
            let last = (0..p)
                .map(|i| {
                    (0..p)
                        .fold(Complex64::new(0.0, 0.0), |acc, l| {
                            acc + coupling[(i, l)] * u[(m - p + l, k)]
                        })
                        .norm_sqr()
                })
                .sum::<f64>()
                .sqrt()
                / norm.max(f64::MIN_POSITIVE);
            let converged = exact || last <= tol * theta.norm();
            Some((Complex64::new(shift, 0.0) + theta.inv(), converged, k))
        })
        .collect();
    ritz.sort_by(|a, b| (a.0 - shift).norm().total_cmp(&(b.0 - shift).norm()));
    // the leading run of converged values
    let lead = ritz.iter().take_while(|(_, c, _)| *c).count();
    let last_outside = lead > 0 && ritz[lead - 1].0.norm() >= r_max;
    if !(lead > want || last_outside || (exact && lead > 0)) {
        return None;
    }
    // the disk: the wanted count (a conjugate pair kept whole) within r_max, its edge
    // halfway to the next converged value
    let mut k = want.min(lead);
    while k > 0 && k < lead && (ritz[k].0 - ritz[k - 1].0.conj()).norm() <= 1e-8 * ritz[k].0.norm()
    {
        k += 1;
    }
    let mut inside: Vec<(Complex64, usize)> = ritz[..k]
        .iter()
        .map(|&(l, _, e)| (l, e))
        .filter(|(l, _)| l.norm() < r_max)
        .collect();
    let edge_in = inside.iter().map(|(l, _)| l.norm()).fold(0.0, f64::max);
    let edge_out = ritz[k..lead]
        .iter()
        .map(|(l, _, _)| l.norm())
        .fold(r_max, f64::min);
    let radius = 0.5 * (edge_in + edge_out.max(edge_in));
    inside.sort_by(|a, b| a.0.norm().total_cmp(&b.0.norm()));
    // the Ritz vectors `Q y` of the exponents kept, when asked for
    let modes = match basis {
        Some(q) => inside
            .iter()
            .map(|&(_, e)| {
                (0..q.nrows())
                    .map(|i| {
                        (0..m).fold(Complex64::new(0.0, 0.0), |acc, j| {
                            acc + u[(j, e)] * q[(i, j)]
                        })
                    })
                    .collect()
            })
            .collect(),
        None => Vec::new(),
    };
    Some((
        NearZero {
            exponents: inside.into_iter().map(|(l, _)| l).collect(),
            radius,
            outer: edge_out.max(edge_in),
            thermal: 0,
            steps: m,
        },
        modes,
    ))
}
