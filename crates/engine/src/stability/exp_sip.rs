//! SIP for stiff systems: the interval exponentials of paper Eq. 33 with the constant part
//! taken exactly.
//!
//! The paper's SIP product is `Π_k exp(Δ B_k)` with `B_k` the interval mean of the state
//! matrix (Eq. 32), each exponential replaced by a truncated series (Eq. 33). A truncated
//! series is an explicit method: it needs `Δ·ρ(B) ≲ 1`, and finite-element rotors with
//! stiff, heavily damped high modes push `ρ(B)` to `10⁴…10⁷ 1/s` while their periods
//! (with a `λ = 6/5` speed ratio, ten shaft revolutions) are long ([`super::Sip`] then needs
//! `10⁴…10⁷` intervals).
//!
//! Here every interval matrix is split as `B_k = B̄ + δB_k`, with `B̄` the mean of `B(t)`
//! over the whole orbit (a constant dense matrix) and `δB_k = L (D_k − D̄) S` the
//! fluctuation of the low-rank nonlinear part (see [`crate::integrate::StateSpace`]), and
//! the interval exponential is taken by Strang splitting,
//!
//! ```text
//!   exp(Δ B_k) ≈ e^{Δ B̄/2} · T_N(Δ δB_k) · e^{Δ B̄/2},     T_N(Z) = Σ_{i=0}^{N} Zⁱ/i!
//! ```
//!
//! so the monodromy matrix is
//! `e^{ΔB̄/2} T(Δ δB_N) e^{ΔB̄} T(Δ δB_{N−1}) ⋯ e^{ΔB̄} T(Δ δB_1) e^{ΔB̄/2}`
//! ([`IntervalMap::Strang`]; the default is the exponential map below).
//! `e^{ΔB̄}` is computed once per orbit ([`expm`]): the stiff constant part is propagated
//! exactly whatever `Δ·ρ(B̄)`, and only the fluctuation (the change of the bearing
//! stiffness and of the coupling along the orbit, small next to `B̄`) goes through the
//! series. The splitting error is `O(Δ³)` per interval from the commutator `[B̄, δB_k]`, so
//! the product converges as `O(Δ²)`, the order of the interval means themselves (checked
//! against the variational equations in `tests/stability_exp_sip.rs`).
//!
//! ## The exponential interval map (default)
//!
//! Strang's split lets the fluctuation act at the interval's midpoint. That is accurate
//! while `Δ·|λ| ≲ 1` for every eigenvalue `λ` of `B̄`, and the dual rotor's bearing-local
//! modes (`λ` to `−1.1e5 1/s`) are far from it: at 500 rad/s the period is 62.8 ms, and
//! 512 intervals give `Δ·|λ| ≈ 14`. A stiff mode driven by the fluctuation then gets its
//! quasi-static response wrong by orders of magnitude (a kick at the midpoint decays by
//! `e^{Δλ/2}` before the interval ends; the true response to an input spread over the
//! interval is `Δ φ₁(Δλ)`, `φ₁(z) = (e^z − 1)/z`), and the product converges only once
//! `Δ·|λ|` approaches 1 (on the unstable orbit of the test below: 1.071 / 1.256 / 1.303 /
//! 1.316 on 512 … 4096 intervals against 1.320).
//!
//! In the modal coordinates of `B̄` (`Λ` block diagonal) the variation-of-constants
//! formula gives the interval map exactly to first order in the fluctuation as
//! `e^{ΔΛ} + ∫₀^Δ e^{(Δ−s)Λ} L̂ D(s) Ŝ e^{sΛ} ds`; taking `D` as its interval mean and
//! each outer factor as its mean over the interval gives
//!
//! ```text
//!   e^{ΔΛ} + φ₁(ΔΛ) L̂ G_k Ŝ φ₁(ΔΛ),
//! ```
//!
//! with `G_k` the series factor of the Strang map but its gather-of-spread `K = Ŝ L̂`
//! weighted by `2 φ₂(ΔΛ)` (`φ₂(z) = (e^z − 1 − z)/z²`), the exact weight of the
//! second-order term through an intermediate mode (`∫∫ e^{(s₂−s₁)λ} = Δ² φ₂(Δλ)`). For
//! `Δ·|λ| → 0` the weights tend to 1 and the map to Strang's to second order; for a stiff
//! mode they give its quasi-static response (`Δ φ₁(Δλ) → 1/|λ|`) and its condensation
//! into the slow ones (`Δ² φ₂(Δλ) → Δ/|λ|`). The weights are constant per product, so an
//! interval costs what a Strang interval costs. Measured on that orbit (plain products,
//! 512 … 4096 intervals): 1.2986 / 1.3150 / 1.3191 / 1.3201 (second order, ratio 4), and
//! extrapolated from 512 intervals 1.3165 where Strang gives 1.2013
//! (`tests/stability_exp_sip.rs`). The map needs the modal coordinates; the dense
//! fallback uses Strang's.
//!
//! The product is propagated in the modal coordinates of `B̄`'s blocks ([`RealModal`],
//! `modal`, the default): there `e^{ΔB̄}` is a set of scalings and plane rotations and the
//! fluctuation a thin gather and spread, so an interval costs `(2p+q)·d + (p+q)·(2p+q) +
//! d·(p+q)`-ish multiply–adds per column instead of the dense block product's `(2n)² + m²`
//! (on the reduced dual rotor about 7.5 k against 13 k). The dense exponentials remain the fallback for a block without a
//! well-conditioned eigenvector basis. The columns are split over the rayon threads.
//!
//! With the exponential map the intervals run on panels of eight columns stored by rows,
//! through the crate's own multiply–add loops (`panel`, [`ExpSip::panels`]) instead of
//! one general matrix product per operation and interval: the same arithmetic at a higher
//! rate (measurements in docs/speed-history.md).
//!
//! ## The kicks' own directions
//!
//! The fluctuation reads and writes fewer directions than the `p + q` rows and columns of
//! `D`: on the dual rotor 8 of the 10 mechanical ones (exactly) and, above 1e-4 of their
//! largest, 12 of the 26 thermal ones. With the exponential map in modal coordinates each
//! product finds them from its own fluctuations and gathers and spreads only those
//! ([`ExpSip::kick_rank_tol`], `kick_basis`): `G_k` is then 20 × 20 and the slow thermal
//! field below works on `q = 12` directions instead of 26 temperatures.
//!
//! ## The slow thermal field
//!
//! In its modal coordinates the thermal field's gather `S̃` (`q × m`) and spread `L̃`
//! (`m × q`) are dense, and on the dual rotor they were half of the product's time
//! (`q = 26` coupled temperatures of `m = 66` nodes). The field is slow: its eigenvalues
//! lie between about −1.3 and −3e-5 1/s, so over one interval `N = e^{ΔΛ} − I` is of order
//! `Δ|λ| ≈ 3e-4`. With the exponential map the field's rows evolve as
//! `t_{k+1} = (I + N) t_k + L̃ u_k` (`u_k` the field's rows of `G_k S̃ ·`), and `n` intervals
//! after an update at `t₀`
//!
//! ```text
//!   S̃ t_n = S̃ t₀ + n S̃N t₀ + C(n,2) S̃N² t₀ + K₀ U_n + K₁ V_n + …,
//!   U_n = Σ_{j<n} u_j,  V_n = Σ_{j<n} (n−1−j) u_j,  K₀ = S̃ L̃,  K₁ = S̃ N L̃,
//! ```
//!
//! (binomial expansion of `(I + N)^n`). So the product carries the gathered temperatures
//! forward with one `q × 2q` product per interval, and brings the rows themselves up to
//! date every [`ExpSip::thermal_block`] intervals, `t ← e^{nΔΛ} t₀ + L̃ U_n + N L̃ V_n`
//! (the free evolution exact; then `S̃ t`, `S̃N t`, `S̃N² t` afresh). What is left out is
//! of order `C(n,3)|N|³` in the free drift and `C(n,2)|N|²` in the kicks' drift inside a
//! block: at 16 intervals and 500 … 300 rad/s about 2e-8 … 8e-8 and 1e-5 … 3e-5 relative
//! (`|N|` 3.3e-4 … 5.5e-4 from the fastest thermal mode). Measured on the dual rotor at
//! 450 rad/s (`tests/stability_exp_sip.rs`): the monodromy matrix within 1.1e-7
//! (relative) of the product that updates every interval, the multipliers above 1/2
//! within 2e-11; on the default sweep's points at 495–520 rad/s the multipliers above
//! 1/2 within 5e-9, the size of the rounding differences between two builds. An
//! interval's thermal cost falls from `2qm` to `2q²` multiply–adds per column plus
//! `5qm/B` per update.
//! Fields whose `B·max|N|` exceeds 0.02 are updated every interval.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use num_complex::Complex64;

mod kick_basis;
mod means;
mod panel;

use kick_basis::KickBasis;
use means::SparseMeans;
use panel::Flat;

use super::expm::expm;
use super::modal::{BlockDiagonal, MAX_CONDITION, RealModal};
use super::sip::{MeanGrid, by_column_blocks, gauss_legendre, state_space_for};
use super::{FloquetResult, StabilityError, StabilityMethod, all_finite, eigenvalues_checked};
use crate::integrate::StateSpace;
use crate::system::{NonlinearEval, PeriodicOrbit, System};

/// The exponential-split SIP product (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpSip {
    /// Number of intervals `N_k` over the period (the fine product when extrapolating; the
    /// start of the refinement). Default 512.
    pub intervals: usize,
    /// Order of the truncated series for the fluctuation factor. Default 4.
    pub series_order: usize,
    /// Gauss–Legendre points per interval for the interval means (1..=5). Default 2.
    pub gauss_points: usize,
    /// Which part of the orbit-mean state matrix is taken exactly. Default
    /// [`MeanSplit::Fields`].
    pub mean_split: MeanSplit,
    /// Richardson extrapolation `(4 P_N − P_{N/2}) / 3` of the products on `N` and `N/2`
    /// intervals (the coarse means are averages of fine pairs, so the orbit is sampled
    /// once; `N` must be even). Default `true`.
    pub extrapolate: bool,
    /// Refinement limit of [`StabilityMethod::multipliers`] (extrapolated products only):
    /// while some multiplier lies closer to the unit circle than twice its error estimate
    /// (the distance between the extrapolated and the plain product's multipliers), the
    /// intervals are doubled, up to this many. `max_intervals ≤ intervals`: no
    /// refinement. Default 4096.
    pub max_intervals: usize,
    /// Propagate in the modal coordinates of `B̄`'s blocks ([`RealModal`]): the interval
    /// exponentials become scalings and plane rotations and the fluctuation a thin gather
    /// and spread, the same product in other coordinates. A block whose eigenvector basis
    /// is ill-conditioned (`cond₁ > 1e6`) falls back to the dense exponential. Default
    /// `true`.
    pub modal: bool,
    /// The map of one interval (see the module docs). Default
    /// [`IntervalMap::Exponential`]; it needs the modal coordinates, without them the map
    /// is [`IntervalMap::Strang`].
    pub interval_map: IntervalMap,
    /// Intervals between updates of the thermal field's rows (exponential map, field
    /// split; see "The slow thermal field" in the module docs). `1`: every interval.
    /// Default 16: at 16 and 32 the multipliers above 1/2 on the dual rotor equal the
    /// every-interval product's to rounding (5e-9), and 32 was no faster (the updates'
    /// five `q × m` products against the per-interval `q × 2q` one).
    pub thermal_block: usize,
    /// Take the modal product (exponential map) through its intervals on panels of eight
    /// columns stored by rows, with the crate's own kernels, instead of the general matrix
    /// kernels on column blocks: the same arithmetic in another order (the monodromy
    /// matrices agree to rounding, test
    /// `panels_equal_the_column_blocks_on_the_dual_rotor`). Default `true`: see
    /// `docs/speed-history.md`, "2026-11-24, c63bfea".
    pub panels: bool,
    /// The kicks act on the directions the fluctuation uses (exponential map, modal
    /// coordinates; see `kick_basis`): per field, the directions of its gathered rows and
    /// spread columns whose singular value over the product's intervals is above this
    /// fraction of its block's largest are kept, the others dropped. `0`: all rows and
    /// columns. Default `1e-4`: on the dual rotor the kept directions lie at 2e-3 and
    /// above, the dropped ones at 3e-5 and below or are exact zeros, a kick shrinks from
    /// 36 × 36 to 20 × 20, and the multipliers of the default sweep move by at most 5e-8
    /// (the stable flags and bifurcations unchanged).
    pub kick_rank_tol: f64,
}

/// How one interval's map combines the exact mean part and the fluctuation (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntervalMap {
    /// `e^{ΔB̄/2} T_N(Δ δB_k) e^{ΔB̄/2}`: the fluctuation acts at the interval's midpoint.
    Strang,
    /// `e^{ΔΛ} + φ₁(ΔΛ) L̂ G_k Ŝ φ₁(ΔΛ)`, the series weighted by `2φ₂(ΔΛ)`: exact in the
    /// stiff limit of `B̄`'s modes.
    #[default]
    Exponential,
}

/// The instruction set of the Floquet panel products on this CPU (`"AVX-512"`, `"AVX2"`,
/// …): the 512-bit kernel is chosen at run time and gives the same products to the last
/// bit, so it matters for the time a sweep takes, not for its results.
pub fn panel_kernel_isa() -> &'static str {
    panel::kernel_isa()
}

impl IntervalMap {
    /// The name used in settings files and on the command line.
    pub fn label(self) -> &'static str {
        match self {
            IntervalMap::Strang => "strang",
            IntervalMap::Exponential => "exponential",
        }
    }
}

/// The constant part `B̄` of the splitting `B_k = B̄ + δB_k`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeanSplit {
    /// The whole orbit-mean state matrix (one dense `d × d` exponential).
    Coupled,
    /// Its mechanical and thermal diagonal blocks only (two exponentials, `(2n)²` and
    /// `m²`); the mean thermo-mechanical coupling joins the fluctuation. About a third
    /// cheaper per interval than [`MeanSplit::Coupled`] on the dual rotor, same accuracy
    /// (measured: thermal multipliers within 3e-8, the unstable one of the test below
    /// within 1e-5 of the coupled split).
    #[default]
    Fields,
}

impl Default for ExpSip {
    /// 512 intervals extrapolated with 256 and refined up to 4096 where a multiplier is
    /// close to the circle; the exponential interval map, series order 4, 2 Gauss points,
    /// field split.
    ///
    /// Why: on the built-in dual rotor the interval count is set by the bearing stiffness,
    /// which varies with every rolling-element pass while the bearing-local modes are
    /// stiff (eigenvalues to −1.1e5 1/s and −1.6e4 ± 3.0e4i 1/s). At ω = 500 rad/s on the
    /// unstable branch the variational equations give a multiplier of modulus 1.3200. With
    /// the exponential map the plain product gives 1.236 / 1.299 / 1.315 / 1.319 on
    /// 256 / 512 / 1024 / 2048 intervals (second order) and the extrapolation from 512
    /// 1.3165, 3.5e-3 from the reference; the error estimate there (0.018) is far below the
    /// distance from the circle, so the product stays at 512 (on the default sweep 315 of
    /// 320 evaluations do). Strang's map gives 0.99999 (the instability missed) / 1.071 /
    /// 1.256 / 1.303 and 1.2013 extrapolated from 512, and needed the refinement to 1024 at
    /// such points (`tests/stability_exp_sip.rs`). Gauss points 1, 2, 3 gave the same
    /// figures to 3e-3 (Strang's map).
    fn default() -> Self {
        Self {
            intervals: 512,
            series_order: 4,
            gauss_points: 2,
            mean_split: MeanSplit::Fields,
            extrapolate: true,
            max_intervals: 4096,
            modal: true,
            interval_map: IntervalMap::Exponential,
            thermal_block: 16,
            panels: true,
            kick_rank_tol: 1e-4,
        }
    }
}

impl ExpSip {
    /// The monodromy matrix of `orbit` on `intervals` intervals (extrapolated when
    /// `extrapolate`), without refinement.
    pub fn monodromy(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<Mat<f64>, StabilityError> {
        let (space, _, period) = state_space_for(system, orbit)?;
        self.monodromy_pair(&space, orbit, period, self.intervals, None)
            .map(|(m, _)| m)
    }

    /// The monodromy matrix on `n_k` intervals (extrapolated when `extrapolate`) and, when
    /// extrapolating, the plain product on the `n_k` intervals as well. `coarse`: the
    /// plain product on `n_k / 2` intervals when already known (the previous refinement
    /// level's), used for the extrapolation instead of a product over averaged pairs.
    fn monodromy_pair(
        &self,
        space: &StateSpace<'_>,
        orbit: &dyn PeriodicOrbit,
        period: f64,
        n_k: usize,
        coarse: Option<Mat<f64>>,
    ) -> Result<(Mat<f64>, Option<Mat<f64>>), StabilityError> {
        if n_k == 0 {
            return Err(StabilityError::Setting {
                field: "exp_sip.intervals",
                value: "0".into(),
                reason: "need at least one interval",
            });
        }
        if self.extrapolate && !n_k.is_multiple_of(2) {
            return Err(StabilityError::Setting {
                field: "exp_sip.intervals",
                value: n_k.to_string(),
                reason: "extrapolation pairs the intervals: need an even number",
            });
        }
        let omega = orbit.omega();
        let d = space.dim();
        let (means, mean, b_bar, delta) = self.split_mean(space, orbit, period, n_k)?;
        // Without velocity derivatives along the orbit (the dual rotor's forces depend on
        // displacements and temperatures only) the velocity rows are not gathered: the
        // same products with 36 instead of 46 gathered rows there.
        let without_velocity;
        let space = if space.gathers_velocity() && !means.reads_velocity() {
            without_velocity = space.with_velocity_gather(false);
            &without_velocity
        } else {
            space
        };
        let mut modal = if self.modal {
            ModalField::all(space, &b_bar, &self.exact_blocks(space))
        } else {
            None
        };
        let basis = match modal.as_mut() {
            Some(fields) if self.interval_map == IntervalMap::Exponential => {
                self.kick_basis(space, &means, &mean, fields)
            }
            _ => None,
        };
        let split = Split {
            b_bar: &b_bar,
            mean: &mean,
            modal: modal.as_deref(),
            basis: basis.as_ref(),
        };
        if !self.extrapolate {
            return Ok((self.product(space, &split, means, delta, omega)?, None));
        }
        let rough = match coarse {
            Some(rough) => rough,
            None => {
                // Coarse means: each the average of two fine ones (a composite Gauss rule).
                let coarse = means.pair_averages();
                self.product(space, &split, coarse, 2.0 * delta, omega)?
            }
        };
        let fine = self.product(space, &split, means, delta, omega)?;
        let extrapolated = Mat::from_fn(d, d, |i, j| (4.0 * fine[(i, j)] - rough[(i, j)]) / 3.0);
        Ok((extrapolated, Some(fine)))
    }

    /// The interval means on `n_k` intervals, their orbit mean `D̄` (without the mean
    /// coupling between the fields with [`MeanSplit::Fields`]), the constant state matrix
    /// `B̄` built from it, and the interval length.
    fn split_mean(
        &self,
        space: &StateSpace<'_>,
        orbit: &dyn PeriodicOrbit,
        period: f64,
        n_k: usize,
    ) -> Result<(SparseMeans, NonlinearEval, Mat<f64>, f64), StabilityError> {
        let (nodes, weights) =
            gauss_legendre(self.gauss_points).ok_or(StabilityError::Setting {
                field: "exp_sip.gauss_points",
                value: self.gauss_points.to_string(),
                reason: "supported: 1 to 5",
            })?;
        let mut ws = space.workspace();
        let delta = period / n_k as f64;
        let grid = MeanGrid {
            delta,
            intervals: n_k,
            nodes,
            weights,
        };
        let means = SparseMeans::sample(space, orbit, grid, &mut ws);
        // Orbit mean D̄ (the same for both products when extrapolating).
        let mut mean = ws.eval.clone();
        means.weighted_sum(1.0 / n_k as f64, &mut mean);
        if self.mean_split == MeanSplit::Fields {
            // the mean coupling between the fields goes with the fluctuation
            for c in [&mut mean.df_dt, &mut mean.dg_dx, &mut mean.dg_dv] {
                c.iter_mut().for_each(|v| *v = 0.0);
            }
        }
        let b_bar = space.linearization_dense(&mean, &mut ws);
        Ok((means, mean, b_bar, delta))
    }

    /// The directions the fluctuations of `means` about `mean` use in each of `fields`
    /// ([`KickBasis`]), with the fields' gathers and spreads taken into them; `None` (and
    /// the fields unchanged) when none can be dropped or [`ExpSip::kick_rank_tol`] is 0.
    fn kick_basis(
        &self,
        space: &StateSpace<'_>,
        means: &SparseMeans,
        mean: &NonlinearEval,
        fields: &mut [ModalField],
    ) -> Option<KickBasis> {
        if self.kick_rank_tol <= 0.0 {
            return None;
        }
        let layout = means.layout(space);
        let ranges: Vec<_> = fields.iter().map(|f| (f.gather, f.spread)).collect();
        let r = space.low_rank_dims().1;
        let basis = KickBasis::new(means, mean, &layout, &ranges, r, self.kick_rank_tol)?;
        for (i, f) in fields.iter_mut().enumerate() {
            let (s_hat, l_hat) = basis.compress_field(i, &f.s_hat, &f.l_hat);
            f.s_hat = s_hat;
            f.l_hat = l_hat;
            (f.gather, f.spread) = basis.ranges(i);
        }
        Some(basis)
    }

    /// Row ranges of the diagonal blocks of `B̄` taken exactly (see [`MeanSplit`]).
    fn exact_blocks(&self, space: &StateSpace<'_>) -> Vec<(usize, usize)> {
        let d = space.dim();
        match self.mean_split {
            MeanSplit::Coupled => vec![(0, d)],
            MeanSplit::Fields => {
                let dm = 2 * space.n_mech();
                [(0, dm), (dm, d)]
                    .into_iter()
                    .filter(|b| b.1 > b.0)
                    .collect()
            }
        }
    }

    /// `cond₁` of the (balanced) modal bases of `B̄`'s blocks on `orbit` at
    /// [`ExpSip::intervals`], one per block; `None` when a block has no acceptable basis
    /// and the product falls back to the dense exponentials (also when `modal` is off).
    pub fn modal_conditions(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<Option<Vec<f64>>, StabilityError> {
        if !self.modal {
            return Ok(None);
        }
        let (space, _, period) = state_space_for(system, orbit)?;
        let (_, _, b_bar, _) = self.split_mean(&space, orbit, period, self.intervals)?;
        let blocks = self.exact_blocks(&space);
        Ok(ModalField::all(&space, &b_bar, &blocks)
            .map(|fields| fields.iter().map(|f| f.modal.condition).collect()))
    }

    /// The split product over the intervals whose means are `means` (consumed: turned into
    /// the fluctuations about `mean`, whose state matrix is `b_bar`).
    fn product(
        &self,
        space: &StateSpace<'_>,
        split: &Split<'_>,
        mut means: SparseMeans,
        delta: f64,
        omega: f64,
    ) -> Result<Mat<f64>, StabilityError> {
        means.subtract(split.mean);
        let prod = match split.modal {
            Some(fields) => {
                let kicks = Kicks::new(space, fields, delta, self.interval_map, self.thermal_block);
                let factors = self.fluctuation_factors(space, &means, delta, &kicks.k, split.basis);
                self.modal_product(space, &factors, fields, &kicks)
            }
            None => {
                let k = space.gather_of_spread();
                let factors = self.fluctuation_factors(space, &means, delta, &k, None);
                self.dense_product(space, split.b_bar, &factors, delta, omega)?
            }
        };
        if !all_finite(prod.as_ref()) {
            return Err(StabilityError::NonFinite { omega });
        }
        Ok(prod)
    }

    /// The product in the modal coordinates of `fields`, returned in the physical ones:
    /// `M = V M̂ V⁻¹` with `V` block diagonal.
    fn modal_product(
        &self,
        space: &StateSpace<'_>,
        factors: &[Flat],
        fields: &[ModalField],
        kicks: &Kicks,
    ) -> Mat<f64> {
        let d = space.dim();
        let panels = self
            .panels
            .then(|| Self::modal_product_panels(space, factors, fields, kicks))
            .flatten();
        let prod = panels.unwrap_or_else(|| {
            by_column_blocks(d, |c0, c1| {
                Self::product_block_modal(space, factors, fields, kicks, c0, c1)
            })
        });
        let mut v = Mat::<f64>::zeros(d, d);
        let mut v_inv = Mat::<f64>::zeros(d, d);
        for f in fields {
            let (r0, len) = (f.rows.0, f.rows.1 - f.rows.0);
            v.as_mut()
                .submatrix_mut(r0, r0, len, len)
                .copy_from(&f.modal.v);
            v_inv
                .as_mut()
                .submatrix_mut(r0, r0, len, len)
                .copy_from(&f.modal.v_inv);
        }
        &v * &prod * &v_inv
    }

    /// The product with the dense exponentials of `B̄`'s blocks.
    fn dense_product(
        &self,
        space: &StateSpace<'_>,
        b_bar: &Mat<f64>,
        factors: &[Flat],
        delta: f64,
        omega: f64,
    ) -> Result<Mat<f64>, StabilityError> {
        let blocks = self.exact_blocks(space);
        let mut e_half = Vec::with_capacity(blocks.len());
        let mut e_full = Vec::with_capacity(blocks.len());
        for &(r0, r1) in &blocks {
            let len = r1 - r0;
            let half = Mat::from_fn(len, len, |i, j| 0.5 * delta * b_bar[(r0 + i, r0 + j)]);
            let eh = expm(&half).ok_or(StabilityError::NonFinite { omega })?;
            e_full.push(&eh * &eh);
            e_half.push(eh);
        }
        let exps = Exponentials {
            blocks: &blocks,
            half: &e_half,
            full: &e_full,
        };
        Ok(by_column_blocks(space.dim(), |c0, c1| {
            Self::product_block(space, factors, &exps, c0, c1)
        }))
    }

    /// `G_k` with `T_N(Δ L D_k S) = I + L G_k S` for every interval: since
    /// `(L D S)ⁱ = L (D K)^{i−1} D S` with `K = S L`,
    /// `G_k = [Σ_{i=1}^{N} Δⁱ/i! (D_k K)^{i−1}] D_k`, evaluated by Horner's scheme on
    /// `(p+q) × (p+q)` matrices. `k_mat` is `K` (Strang) or its weighted form
    /// ([`IntervalMap::Exponential`]).
    ///
    /// `D_k` is sparse (each bearing's force depends on its own rings' displacements and a
    /// few temperatures, each heat source on its bearing's load: about 200 of the dual
    /// rotor's 36 × 46 entries), so the two products with it, `D_k K` and `H D_k`, run over
    /// its nonzeros; only the Horner products are dense.
    ///
    /// With `basis` the factors are those of `Uᵀ D_k V` in the kicks' own coordinates
    /// ([`KickBasis`]), `k_mat` already in them; the factor's size is `k_mat`'s transpose.
    fn fluctuation_factors(
        &self,
        space: &StateSpace<'_>,
        fluctuations: &SparseMeans,
        delta: f64,
        k_mat: &Mat<f64>,
        basis: Option<&KickBasis>,
    ) -> Vec<Flat> {
        use rayon::prelude::*;
        let (g, r) = (k_mat.nrows(), k_mat.ncols());
        let k_t = k_mat.transpose().to_owned();
        let layout = fluctuations.layout(space);
        let factor = |(bufs, nonzeros, compressed): &mut FactorBuffers, k: usize| {
            let [y, y_t, h, tmp] = bufs;
            if let (Some(b), Some((t, dk))) = (basis, compressed.as_mut()) {
                // the kicks' own coordinates: D_k dense and small, Y = D K
                b.compress(fluctuations.row(k), t, dk.as_mut());
                matmul(
                    y.as_mut(),
                    Accum::Replace,
                    dk.as_ref(),
                    k_mat.as_ref(),
                    1.0,
                    Par::Seq,
                );
            } else {
                fluctuations.nonzeros(k, &layout, nonzeros);
                // Y = D K over D's nonzeros, as Yᵀ = Kᵀ Dᵀ (contiguous columns of Kᵀ)
                y_t.fill(0.0);
                for &(i, j, v) in nonzeros.iter() {
                    let kj = column(&k_t, j);
                    for (yv, kv) in column_mut(y_t, i).iter_mut().zip(kj) {
                        *yv += v * kv;
                    }
                }
                y.copy_from(y_t.transpose());
            }
            // innermost Horner factor I + (Δ/N)·Y without a product by the identity
            let order = self.series_order;
            let first = if order >= 2 {
                delta / order as f64
            } else {
                0.0
            };
            for j in 0..r {
                let hj = column_mut(h, j);
                for (hv, yv) in hj.iter_mut().zip(column(y, j)) {
                    *hv = first * yv;
                }
                hj[j] += 1.0;
            }
            for i in (2..order).rev() {
                matmul(
                    tmp.as_mut(),
                    Accum::Replace,
                    y.as_ref(),
                    h.as_ref(),
                    delta / i as f64,
                    Par::Seq,
                );
                for j in 0..r {
                    tmp[(j, j)] += 1.0;
                }
                std::mem::swap(h, tmp);
            }
            let mut gk = Flat::zeros(r, g);
            if let Some((_, dk)) = compressed.as_ref() {
                matmul(
                    gk.as_mut(),
                    Accum::Replace,
                    h.as_ref(),
                    dk.as_ref(),
                    delta,
                    Par::Seq,
                );
                return gk;
            }
            // G = Δ H D over D's nonzeros: column j of G gathers H's columns i
            for &(i, j, v) in nonzeros.iter() {
                let w = delta * v;
                let hi = column(h, i);
                for (gv, hv) in gk.col_mut(j).iter_mut().zip(hi) {
                    *gv += w * hv;
                }
            }
            gk
        };
        let buffers = || {
            (
                [
                    Mat::<f64>::zeros(r, r),
                    Mat::<f64>::zeros(r, r),
                    Mat::<f64>::zeros(r, r),
                    Mat::<f64>::zeros(r, r),
                ],
                Vec::new(),
                basis.map(|b| (b.scratch(), Mat::<f64>::zeros(r, g))),
            )
        };
        (0..fluctuations.len())
            .into_par_iter()
            .with_min_len(32)
            .map_init(buffers, factor)
            .collect()
    }

    /// Columns `c0..c1` of the product.
    fn product_block(
        space: &StateSpace<'_>,
        factors: &[Flat],
        exps: &Exponentials<'_>,
        c0: usize,
        c1: usize,
    ) -> Mat<f64> {
        let d = space.dim();
        let c = c1 - c0;
        let (g, r) = space.low_rank_dims();
        let mut prod = Mat::<f64>::zeros(d, c);
        for (b, &(r0, r1)) in exps.blocks.iter().enumerate() {
            // columns c0..c1 of the block-diagonal e^{ΔB̄/2}
            if let Some((lo, hi)) = column_window((r0, r1), c0, c1) {
                prod.as_mut()
                    .submatrix_mut(r0, lo - c0, r1 - r0, hi - lo)
                    .copy_from(exps.half[b].as_ref().subcols(lo - r0, hi - lo));
            }
        }
        let mut w = Mat::<f64>::zeros(d, c);
        let mut gathered = Mat::<f64>::zeros(g, c);
        let mut mixed = Mat::<f64>::zeros(r, c);
        let last = factors.len().saturating_sub(1);
        for (k, gk) in factors.iter().enumerate() {
            // w = T_N(Δ δB_k) prod = prod + L G_k S prod
            w.copy_from(&prod);
            if r > 0 {
                space.gather(prod.as_ref(), gathered.as_mut());
                matmul(
                    mixed.as_mut(),
                    Accum::Replace,
                    gk.as_ref(),
                    gathered.as_ref(),
                    1.0,
                    Par::Seq,
                );
                space.spread_add(mixed.as_ref(), w.as_mut());
            }
            let e = if k == last { exps.half } else { exps.full };
            for (b, &(r0, r1)) in exps.blocks.iter().enumerate() {
                matmul(
                    prod.as_mut().subrows_mut(r0, r1 - r0),
                    Accum::Replace,
                    e[b].as_ref(),
                    w.as_ref().subrows(r0, r1 - r0),
                    1.0,
                    Par::Seq,
                );
            }
        }
        prod
    }

    /// Columns `c0..c1` of the product in modal coordinates (see [`ModalField`]).
    ///
    /// Strang: `prod ← e^{ΔΛ} (prod + L̂ G_k Ŝ prod)` from `e^{ΔΛ/2}`, the last exponential
    /// a half one. Exponential: `prod ← e^{ΔΛ} prod + L̃ G_k S̃ prod` from the identity, with
    /// the weighted gather and spread of `kicks`.
    fn product_block_modal(
        space: &StateSpace<'_>,
        factors: &[Flat],
        fields: &[ModalField],
        kicks: &Kicks,
        c0: usize,
        c1: usize,
    ) -> Mat<f64> {
        let d = space.dim();
        let c = c1 - c0;
        let (g, r) = (kicks.k.nrows(), kicks.k.ncols());
        let strang = kicks.map == IntervalMap::Strang;
        let mut prod = Mat::<f64>::zeros(d, c);
        for (f, [start, _]) in fields.iter().zip(&kicks.exps) {
            // columns c0..c1 of the block-diagonal start (e^{ΔΛ/2} or the identity)
            let (r0, r1) = f.rows;
            if let Some((lo, hi)) = column_window(f.rows, c0, c1) {
                start.columns_into(
                    lo - r0,
                    prod.as_mut().submatrix_mut(r0, lo - c0, r1 - r0, hi - lo),
                );
            }
        }
        let mut gathered = Mat::<f64>::zeros(g, c);
        let mut mixed = Mat::<f64>::zeros(r, c);
        let last = factors.len().saturating_sub(1);
        // the thermal field in blocks of intervals (exponential map only)
        let slow_index = kicks.slow.as_ref().map(|s| s.field);
        let rows_of = |f: &ModalField| (f.rows.0, f.rows.1 - f.rows.0);
        let mut slow_state = kicks.slow.as_ref().map(|slow| {
            let f = &fields[slow.field];
            let mut st = SlowState::new(f.gather.1 - f.gather.0, c);
            let (r0, len) = rows_of(f);
            st.restart(
                slow,
                &kicks.gather[slow.field],
                prod.as_ref().subrows(r0, len),
            );
            st
        });
        let propagate = |prod: &mut Mat<f64>, k: usize| {
            for (i, (f, [half, full])) in fields.iter().zip(&kicks.exps).enumerate() {
                if Some(i) == slow_index {
                    continue;
                }
                let e = if strang && k == last { half } else { full };
                e.apply(prod.as_mut().subrows_mut(f.rows.0, f.rows.1 - f.rows.0));
            }
        };
        for (k, gk) in factors.iter().enumerate() {
            if r > 0 {
                for (i, (f, s)) in fields.iter().zip(&kicks.gather).enumerate() {
                    if f.gather.1 <= f.gather.0 {
                        continue;
                    }
                    let mut rows = gathered
                        .as_mut()
                        .subrows_mut(f.gather.0, f.gather.1 - f.gather.0);
                    match (&slow_state, Some(i) == slow_index) {
                        (Some(st), true) => rows.copy_from(&st.y),
                        _ => matmul(
                            rows,
                            Accum::Replace,
                            s.as_ref(),
                            prod.as_ref().subrows(f.rows.0, f.rows.1 - f.rows.0),
                            1.0,
                            Par::Seq,
                        ),
                    }
                }
                matmul(
                    mixed.as_mut(),
                    Accum::Replace,
                    gk.as_ref(),
                    gathered.as_ref(),
                    1.0,
                    Par::Seq,
                );
                if !strang {
                    // the free propagation of the interval's start, then the kick
                    propagate(&mut prod, k);
                }
                for (i, (f, l)) in fields.iter().zip(&kicks.spread).enumerate() {
                    if f.spread.1 <= f.spread.0 || Some(i) == slow_index {
                        continue;
                    }
                    matmul(
                        prod.as_mut().subrows_mut(f.rows.0, f.rows.1 - f.rows.0),
                        Accum::Add,
                        l.as_ref(),
                        mixed.as_ref().subrows(f.spread.0, f.spread.1 - f.spread.0),
                        1.0,
                        Par::Seq,
                    );
                }
                if strang {
                    propagate(&mut prod, k);
                }
            } else {
                propagate(&mut prod, k);
            }
            if let (Some(st), Some(slow)) = (slow_state.as_mut(), kicks.slow.as_ref()) {
                let f = &fields[slow.field];
                let u = mixed.as_ref().subrows(f.spread.0, f.spread.1 - f.spread.0);
                st.advance(slow, u);
                if st.n == slow.block || k == last {
                    let (r0, len) = rows_of(f);
                    let spread = &kicks.spread[slow.field];
                    st.finish(
                        slow,
                        f,
                        spread,
                        kicks.delta,
                        prod.as_mut().subrows_mut(r0, len),
                    );
                    if k != last {
                        let gather = &kicks.gather[slow.field];
                        st.restart(slow, gather, prod.as_ref().subrows(r0, len));
                    }
                }
            }
        }
        prod
    }
}

/// Per-thread scratch of [`ExpSip::fluctuation_factors`]: `Y`, `Yᵀ`, the Horner factor and
/// its product, the interval's derivative nonzeros `(row, column, value)`, and with a
/// [`KickBasis`] its scratch and the interval's `D_k` in the kicks' coordinates.
type FactorBuffers = (
    [Mat<f64>; 4],
    Vec<(usize, usize, f64)>,
    Option<(Vec<f64>, Mat<f64>)>,
);

/// Column `j` of an owned (column-major, contiguous) matrix as a slice.
fn column(m: &Mat<f64>, j: usize) -> &[f64] {
    let n = m.nrows();
    &m.col_as_slice(j)[..n]
}

/// Column `j` of an owned matrix as a mutable slice.
fn column_mut(m: &mut Mat<f64>, j: usize) -> &mut [f64] {
    let n = m.nrows();
    &mut m.col_as_slice_mut(j)[..n]
}

/// The columns `lo..hi` of `c0..c1` that fall in the diagonal block on rows (and
/// columns) `r0..r1`, if any.
fn column_window((r0, r1): (usize, usize), c0: usize, c1: usize) -> Option<(usize, usize)> {
    let (lo, hi) = (c0.max(r0), c1.min(r1));
    (lo < hi).then_some((lo, hi))
}

/// One diagonal block of `B̄` (a field, or the whole state with [`MeanSplit::Coupled`]) in
/// its modal coordinates `z = V⁻¹ y`: the rows of the gathered operand `S y` and the
/// columns of the spread `L` that belong to it, taken into the modal coordinates
/// (`Ŝ = S V`, `L̂ = V⁻¹ L`).
struct ModalField {
    /// State rows `r0..r1`, gathered rows `g0..g1` and spread columns `s0..s1`.
    rows: (usize, usize),
    gather: (usize, usize),
    spread: (usize, usize),
    modal: RealModal,
    s_hat: Mat<f64>,
    l_hat: Mat<f64>,
}

/// The constant part of the splitting, shared by the products of one refinement level: `B̄`,
/// the mean derivatives it was built from, and its modal form when taken.
struct Split<'s> {
    b_bar: &'s Mat<f64>,
    mean: &'s NonlinearEval,
    modal: Option<&'s [ModalField]>,
    /// The kicks' own coordinates, when the modal fields are in them.
    basis: Option<&'s KickBasis>,
}

impl ModalField {
    /// The modal form of every block in `blocks` (row ranges of `b_bar`), or `None` when
    /// one block has no well-conditioned eigenvector basis.
    ///
    /// The gathered rows are `[x_P, v_P, T_Q]` and the spread columns `[P, Q]`
    /// ([`StateSpace::gather`], [`StateSpace::spread_add`]): with the field split, `x_P`,
    /// `v_P` and `P` belong to the mechanical block and `T_Q`, `Q` to the thermal one.
    fn all(
        space: &StateSpace<'_>,
        b_bar: &Mat<f64>,
        blocks: &[(usize, usize)],
    ) -> Option<Vec<Self>> {
        use rayon::prelude::*;
        let d = space.dim();
        let dm = 2 * space.n_mech();
        let (p, q) = (space.dofs().mech.len(), space.dofs().therm.len());
        let (g, r) = space.low_rank_dims();
        // the mechanical gathered rows, x_P and (when gathered) v_P, come first
        let gm = g - q;
        let s = space.gather_matrix();
        let l = space.spread_matrix();
        // the blocks' eigenvalue problems are independent: side by side
        blocks
            .par_iter()
            .map(|&(r0, r1)| {
                let (gather, spread) = if (r0, r1) == (0, d) {
                    ((0, g), (0, r))
                } else if (r0, r1) == (0, dm) {
                    ((0, gm), (0, p))
                } else {
                    ((gm, g), (p, p + q))
                };
                let len = r1 - r0;
                let modal =
                    RealModal::new(b_bar.as_ref().submatrix(r0, r0, len, len), MAX_CONDITION)?;
                let s_hat = s.as_ref().submatrix(gather.0, r0, gather.1 - gather.0, len) * &modal.v;
                let l_hat =
                    &modal.v_inv * l.as_ref().submatrix(r0, spread.0, len, spread.1 - spread.0);
                Some(Self {
                    rows: (r0, r1),
                    gather,
                    spread,
                    modal,
                    s_hat,
                    l_hat,
                })
            })
            .collect()
    }
}

/// What one product's intervals apply in the modal coordinates, per field: the start and
/// interval exponentials, the gather and spread around `G_k`, and the gather-of-spread
/// `K` of the series (see [`IntervalMap`]).
struct Kicks {
    map: IntervalMap,
    /// Interval length.
    delta: f64,
    /// `[start, interval]`: `[e^{ΔΛ/2}, e^{ΔΛ}]` (Strang) or `[I, e^{ΔΛ}]`; the last
    /// Strang interval ends with the half exponential.
    exps: Vec<[BlockDiagonal; 2]>,
    /// `Ŝ` or `S̃ = Ŝ φ₁(ΔΛ)` per field.
    gather: Vec<Mat<f64>>,
    /// `L̂` or `L̃ = φ₁(ΔΛ) L̂` per field.
    spread: Vec<Mat<f64>>,
    /// `K = Σ_f Ŝ_f L̂_f` or `Σ_f Ŝ_f 2φ₂(ΔΛ_f) L̂_f` (gathered rows × `p+q`).
    k: Mat<f64>,
    /// The thermal field brought forward in blocks of intervals, when it is.
    slow: Option<SlowField>,
}

/// What the product needs to bring the thermal field forward every `block` intervals
/// (module docs, "The slow thermal field"): with `N = e^{ΔΛ} − I` on that field,
/// `S̃`, `L̃` its weighted gather and spread.
struct SlowField {
    /// Index of the field in the field list.
    field: usize,
    block: usize,
    /// `[K₀ K₁]`, `K₀ = S̃ L̃`, `K₁ = S̃ N L̃` (`q × 2q`).
    k01: Mat<f64>,
    /// `S̃ N` and `S̃ N²` (`q × m`).
    sn: Mat<f64>,
    sn2: Mat<f64>,
    /// `N L̃` (`m × q`).
    nl: Mat<f64>,
    /// `e^{BΔΛ}` for a whole block.
    exp_block: BlockDiagonal,
}

/// Largest `B·max|e^{Δλ} − 1|` over the thermal modes for which the field is brought
/// forward in blocks of `B` intervals; above it, every interval.
const SLOW_FIELD_MAX_DRIFT: f64 = 0.02;

impl SlowField {
    /// For field `index` of `fields` on intervals of length `delta`, with its weighted
    /// gather `s` and spread `l`; `None` when the field is not the thermal one of the
    /// field split, `block < 2`, or the field is not slow enough.
    fn new(
        space: &StateSpace<'_>,
        fields: &[ModalField],
        index: usize,
        delta: f64,
        block: usize,
        (s, l): (&Mat<f64>, &Mat<f64>),
    ) -> Option<Self> {
        let f = &fields[index];
        let thermal = fields.len() == 2 && f.rows == (2 * space.n_mech(), space.dim());
        if block < 2 || !thermal || s.nrows() == 0 || l.ncols() == 0 {
            return None;
        }
        let n_mat = f.modal.function(|z| (z * delta).exp() - 1.0).to_dense();
        let drift = n_mat.norm_max();
        if drift.is_nan() || drift * block as f64 > SLOW_FIELD_MAX_DRIFT {
            return None;
        }
        let sn = s * &n_mat;
        let sn2 = &sn * &n_mat;
        let k0 = s * l;
        let k1 = &sn * l;
        let q = k0.nrows();
        let mut k01 = Mat::<f64>::zeros(q, 2 * q);
        k01.as_mut().subcols_mut(0, q).copy_from(&k0);
        k01.as_mut().subcols_mut(q, q).copy_from(&k1);
        Some(Self {
            field: index,
            block,
            k01,
            sn,
            sn2,
            nl: &n_mat * l,
            exp_block: f.modal.exp(block as f64 * delta),
        })
    }
}

/// The thermal field's state inside a product's column block between two updates: the
/// gathered temperatures `y = S̃ t` carried forward, the free drift of `t` at the last
/// update (`S̃ N t`, `S̃ N² t`), and the kicks since then, summed (`U`) and summed with
/// their age (`V`).
struct SlowState {
    y: Mat<f64>,
    a1: Mat<f64>,
    a2: Mat<f64>,
    /// `[u_n; U_n]`, the operand of `[K₀ K₁]` (`2q × c`).
    stack: Mat<f64>,
    v: Mat<f64>,
    n: usize,
}

impl SlowState {
    fn new(q: usize, c: usize) -> Self {
        Self {
            y: Mat::zeros(q, c),
            a1: Mat::zeros(q, c),
            a2: Mat::zeros(q, c),
            stack: Mat::zeros(2 * q, c),
            v: Mat::zeros(q, c),
            n: 0,
        }
    }

    /// Starts a block from the field's rows `t`.
    fn restart(&mut self, slow: &SlowField, gather: &Mat<f64>, t: MatRef<'_, f64>) {
        // y = S̃ t, a₁ = S̃N t, a₂ = S̃N² t
        for (out, by) in [
            (&mut self.y, gather),
            (&mut self.a1, &slow.sn),
            (&mut self.a2, &slow.sn2),
        ] {
            matmul(out.as_mut(), Accum::Replace, by.as_ref(), t, 1.0, Par::Seq);
        }
        self.stack.fill(0.0);
        self.v.fill(0.0);
        self.n = 0;
    }

    /// One interval with kick `u` (`q × c`):
    /// `y ← y + S̃N t₀ + n S̃N² t₀ + K₀ u + K₁ U`, then `V ← V + U`, `U ← U + u`.
    fn advance(&mut self, slow: &SlowField, u: MatRef<'_, f64>) {
        let q = self.y.nrows();
        self.stack.as_mut().subrows_mut(0, q).copy_from(u);
        let n = self.n as f64;
        for j in 0..self.y.ncols() {
            let (a1, a2) = (column(&self.a1, j), column(&self.a2, j));
            for ((y, a), b) in column_mut(&mut self.y, j).iter_mut().zip(a1).zip(a2) {
                *y += a + n * b;
            }
        }
        matmul(
            self.y.as_mut(),
            Accum::Add,
            slow.k01.as_ref(),
            self.stack.as_ref(),
            1.0,
            Par::Seq,
        );
        for j in 0..self.y.ncols() {
            let (kick, sum) = column_mut(&mut self.stack, j).split_at_mut(q);
            for ((v, s), k) in column_mut(&mut self.v, j).iter_mut().zip(sum).zip(kick) {
                *v += *s;
                *s += *k;
            }
        }
        self.n += 1;
    }

    /// Brings the field's rows `t` to the end of the block:
    /// `t ← e^{nΔΛ} t + L̃ U + N L̃ V`.
    fn finish(
        &self,
        slow: &SlowField,
        field: &ModalField,
        spread: &Mat<f64>,
        delta: f64,
        mut t: MatMut<'_, f64>,
    ) {
        let q = self.y.nrows();
        if self.n == slow.block {
            slow.exp_block.apply(t.as_mut());
        } else {
            field.modal.exp(self.n as f64 * delta).apply(t.as_mut());
        }
        let sum = self.stack.as_ref().subrows(q, q);
        matmul(t.as_mut(), Accum::Add, spread.as_ref(), sum, 1.0, Par::Seq);
        matmul(
            t.as_mut(),
            Accum::Add,
            slow.nl.as_ref(),
            self.v.as_ref(),
            1.0,
            Par::Seq,
        );
    }
}

impl Kicks {
    fn new(
        space: &StateSpace<'_>,
        fields: &[ModalField],
        delta: f64,
        map: IntervalMap,
        thermal_block: usize,
    ) -> Self {
        // the fields' gathered rows and spread columns (in the kicks' own coordinates when
        // they were taken into them)
        let (g, r) = fields
            .iter()
            .fold((0, 0), |(g, r), f| (g.max(f.gather.1), r.max(f.spread.1)));
        let mut kicks = Self {
            map,
            delta,
            exps: Vec::with_capacity(fields.len()),
            gather: Vec::with_capacity(fields.len()),
            spread: Vec::with_capacity(fields.len()),
            // Strang: K = S L as it is; exponential: assembled per field below
            k: match map {
                IntervalMap::Strang => space.gather_of_spread(),
                IntervalMap::Exponential => Mat::zeros(g, r),
            },
            slow: None,
        };
        for f in fields {
            let full = f.modal.exp(delta);
            let (start, s, l) = match map {
                IntervalMap::Strang => (f.modal.exp(0.5 * delta), f.s_hat.clone(), f.l_hat.clone()),
                IntervalMap::Exponential => {
                    let p1 = f.modal.function(|z| phi1(z * delta)).to_dense();
                    let w2 = f.modal.function(|z| 2.0 * phi2(z * delta)).to_dense();
                    // K is block diagonal in the fields: a field's gathered rows see only
                    // its own spread columns
                    let (gn, sn) = (f.gather.1 - f.gather.0, f.spread.1 - f.spread.0);
                    if gn > 0 && sn > 0 {
                        kicks
                            .k
                            .as_mut()
                            .submatrix_mut(f.gather.0, f.spread.0, gn, sn)
                            .copy_from(&f.s_hat * &w2 * &f.l_hat);
                    }
                    (f.modal.exp(0.0), &f.s_hat * &p1, &p1 * &f.l_hat)
                }
            };
            kicks.exps.push([start, full]);
            kicks.gather.push(s);
            kicks.spread.push(l);
        }
        if map == IntervalMap::Exponential {
            kicks.slow = (0..fields.len()).find_map(|i| {
                SlowField::new(
                    space,
                    fields,
                    i,
                    delta,
                    thermal_block,
                    (&kicks.gather[i], &kicks.spread[i]),
                )
            });
        }
        kicks
    }
}

/// `φ₁(z) = (e^z − 1)/z`, by its series near 0 (five terms: error below `|z|⁵/720`).
fn phi1(z: Complex64) -> Complex64 {
    if z.norm() < 1e-2 {
        1.0 + z * (1.0 / 2.0 + z * (1.0 / 6.0 + z * (1.0 / 24.0 + z / 120.0)))
    } else {
        (z.exp() - 1.0) / z
    }
}

/// `φ₂(z) = (e^z − 1 − z)/z²`, by its series near 0.
fn phi2(z: Complex64) -> Complex64 {
    if z.norm() < 1e-2 {
        0.5 + z * (1.0 / 6.0 + z * (1.0 / 24.0 + z * (1.0 / 120.0 + z / 720.0)))
    } else {
        (z.exp() - 1.0 - z) / (z * z)
    }
}

/// The exponentials of the mean part, one per diagonal block of `B̄`.
struct Exponentials<'e> {
    /// Row (and column) ranges of the blocks.
    blocks: &'e [(usize, usize)],
    half: &'e [Mat<f64>],
    full: &'e [Mat<f64>],
}

impl StabilityMethod for ExpSip {
    /// Multipliers of the (extrapolated) product, refined: while a multiplier lies closer
    /// to the unit circle than twice its error estimate, the intervals are doubled, up to
    /// `max_intervals` (see the field's docs). Each level's plain product is the next
    /// level's coarse one, so a refinement from `N` to `2N` costs one product on `2N`
    /// intervals (measured on the default sweep when introduced: 70 → 62 s, the same stable flags and
    /// bifurcations, the located points within 0.005 rad/s).
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        let (space, omega, period) = state_space_for(system, orbit)?;
        let mut n_k = self.intervals;
        let mut coarse = None;
        loop {
            let (mono, fine) = self.monodromy_pair(&space, orbit, period, n_k, coarse.take())?;
            // the two eigenvalue problems are independent: side by side
            let (mu, mu_fine) = rayon::join(
                || eigenvalues_checked(mono.as_ref(), omega),
                || match &fine {
                    Some(fine) if n_k < self.max_intervals => {
                        eigenvalues_checked(fine.as_ref(), omega).map(Some)
                    }
                    _ => Ok(None),
                },
            );
            let (mu, mu_fine) = (mu?, mu_fine?);
            let refine = mu_fine.is_some_and(|mu_fine| !clear_of_the_circle(&mu, &mu_fine));
            if !refine {
                return Ok(FloquetResult::new(mu).with_intervals(n_k));
            }
            // this level's plain product is the next level's coarse one
            coarse = fine;
            n_k *= 2;
        }
    }

    /// The (extrapolated) product on the intervals of the finer end (at least
    /// [`ExpSip::intervals`]), without refinement.
    fn search_multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        ends: [&FloquetResult; 2],
    ) -> Result<FloquetResult, StabilityError> {
        let n = ends
            .iter()
            .filter_map(|f| f.intervals)
            .fold(self.intervals, usize::max);
        let fixed = ExpSip {
            intervals: n,
            max_intervals: n,
            ..*self
        };
        fixed.multipliers(system, orbit)
    }
}

/// True when every multiplier of `mu` (extrapolated) whose modulus is above 1/2 lies
/// farther from the unit circle than twice its error estimate: its distance to the
/// nearest multiplier of `mu_fine` (the plain product on the same intervals, whose error
/// the extrapolation removes to leading order).
fn clear_of_the_circle(mu: &[Complex64], mu_fine: &[Complex64]) -> bool {
    mu.iter().filter(|m| m.norm() > 0.5).all(|m| {
        let est = mu_fine
            .iter()
            .map(|f| (m - f).norm())
            .fold(f64::INFINITY, f64::min);
        (m.norm() - 1.0).abs() > 2.0 * est
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    #[test]
    fn phi_functions_match_their_closed_forms_and_limits() {
        // across the switch to the series, on and off the real axis
        for z in [c(9.9e-3, 0.0), c(-9.9e-3, 1e-4), c(0.0, 9.9e-3)] {
            let closed1 = (z.exp() - 1.0) / z;
            let closed2 = (z.exp() - 1.0 - z) / (z * z);
            assert!((phi1(z) - closed1).norm() < 1e-12, "φ₁({z})");
            assert!((phi2(z) - closed2).norm() < 1e-9, "φ₂({z})");
        }
        assert!((phi1(c(0.0, 0.0)) - c(1.0, 0.0)).norm() < 1e-15);
        assert!((phi2(c(0.0, 0.0)) - c(0.5, 0.0)).norm() < 1e-15);
        // φ₂(1) = e − 2; φ₁(iπ) = −2/(iπ) = 2i/π
        assert!((phi2(c(1.0, 0.0)) - c(std::f64::consts::E - 2.0, 0.0)).norm() < 1e-14);
        let pi = std::f64::consts::PI;
        assert!((phi1(c(0.0, pi)) - c(0.0, 2.0 / pi)).norm() < 1e-14);
        // the stiff limits that make the map exact for quasi-static modes
        let x = 1e5;
        assert!((phi1(c(-x, 0.0)).re * x - 1.0).abs() < 1e-4);
        assert!((phi2(c(-x, 0.0)).re * x - 1.0).abs() < 1e-4);
    }

    #[test]
    fn refinement_is_asked_for_only_near_the_circle() {
        // thermal multipliers just below +1, known to 1e-8, and damped mechanical ones
        let fine = [c(0.999_995, 0.0), c(0.6, 0.3), c(0.01, 0.0)];
        let ext = [c(0.999_995 + 1e-8, 0.0), c(0.62, 0.31), c(0.011, 0.0)];
        assert!(clear_of_the_circle(&ext, &fine));
        // an unstable multiplier whose estimate is larger than its distance to the circle
        let fine = [c(1.07, 0.0), c(0.999_995, 0.0)];
        let ext = [c(1.20, 0.0), c(0.999_995, 0.0)];
        assert!(!clear_of_the_circle(&ext, &fine));
        // …and the same once the estimate has shrunk
        let fine = [c(1.256, 0.0), c(0.999_995, 0.0)];
        let ext = [c(1.317, 0.0), c(0.999_995, 0.0)];
        assert!(clear_of_the_circle(&ext, &fine));
        // small multipliers never ask for refinement
        assert!(clear_of_the_circle(&[c(0.3, 0.0)], &[c(0.1, 0.0)]));
    }

    #[test]
    fn sparse_fluctuation_factors_equal_the_dense_series() {
        use crate::systems::chain::Chain;
        let sys = Chain::new(5, 3);
        let space = StateSpace::new(&sys, 0.9).expect("state space");
        let (p, q) = (space.dofs().mech.len(), space.dofs().therm.len());
        let (g, r) = space.low_rank_dims();
        // a sparse fluctuation: a few entries of every block, one block left empty
        let mut fl = NonlinearEval::new(p, q);
        for (k, buf) in [&mut fl.df_dx, &mut fl.df_dt, &mut fl.dg_dx, &mut fl.dg_dt]
            .into_iter()
            .enumerate()
        {
            for (i, v) in buf.iter_mut().enumerate().filter(|(i, _)| i % 3 == k % 2) {
                *v = 0.5 - 0.1 * k as f64 + 0.03 * i as f64;
            }
        }
        let k_mat = Mat::from_fn(g, r, |i, j| ((i * r + j) as f64 * 0.37).sin());
        let delta = 0.2;
        for order in 1..=5 {
            let sip = ExpSip {
                series_order: order,
                ..ExpSip::default()
            };
            let sparse = SparseMeans::from_dense(&space, std::slice::from_ref(&fl));
            let factors = sip.fluctuation_factors(&space, &sparse, delta, &k_mat, None);
            // reference: Σ_{i=1}^{N} Δⁱ/i! (D K)^{i−1} D term by term, dense
            let mut d = Mat::<f64>::zeros(r, g);
            space.derivative_matrix(&fl, d.as_mut());
            let dk = &d * &k_mat;
            let mut power = Mat::<f64>::identity(r, r);
            let mut want = Mat::<f64>::zeros(r, g);
            let mut coeff = 1.0;
            for i in 1..=order {
                coeff *= delta / i as f64;
                want += coeff * &power * &d;
                power = &power * &dk;
            }
            let err = (factors[0].as_ref() - &want).norm_max();
            assert!(err < 1e-13 * want.norm_max(), "order {order}: {err:e}");
        }
    }
}
