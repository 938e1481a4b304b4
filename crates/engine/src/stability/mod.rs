//! Floquet stability of periodic solutions and the classification of bifurcations
//! (paper Section 4.2).
//!
//! The shared vocabulary lives here: [`FloquetResult`] (multipliers + stable flag),
//! [`BifurcationKind`], the [`StabilityMethod`] seam the continuation calls at every
//! point, and [`classify_crossing`], which tells from the multipliers on both sides of a
//! stability change how they left the unit circle: through +1 (saddle-node / fold),
//! through −1 (period doubling) or as a complex pair (Neimark–Sacker).
//!
//! Methods (all implement [`StabilityMethod`] on any [`System`] + [`PeriodicOrbit`]):
//!
//! | method | what | default settings | accuracy (measured) |
//! |---|---|---|---|
//! | [`Sip`] | paper Eqs. 30–33: product of truncated exponential series of interval means | 256 intervals (more when `P·ρ(B)` needs them), order 4, 3 Gauss points | `O(Δ²)`; 2e-7…6e-4 on the reference oscillators at 256 intervals (largest on strongly nonlinear orbits), exponent 0 of the Hill problem to 1e-8; opt-in extrapolation `O(Δ⁴)` |
//! | [`Variational`] | `Φ̇ = B(t)Φ` over one period with Dormand–Prince 5(4) | `rtol` 1e-10, `atol` 1e-12 | ~1e-11 against shooting |
//! | [`ExpSip`] | SIP with the orbit-mean state matrix's field blocks taken exactly, the low-rank fluctuation through the series, propagated in the modal coordinates of those blocks; Richardson-extrapolated, refined near the unit circle | 512 intervals (with 256), doubled up to 4096 while a multiplier is within twice its error estimate of the circle, order 4, 2 Gauss points, the slow thermal field updated every 16 intervals | `O(Δ²)` plain; on the dual rotor's unstable orbit at 500 rad/s 3e-3 against the variational equations (the sweep default, on a [`Reduced`] model) |
//!
//! All build `B(t)` from [`crate::integrate::StateSpace`]: mechanical block
//! `[[0, I], [−M⁻¹(K + ∂f/∂x), −M⁻¹(C + ∂f/∂v)]]`, thermal block `−C_T⁻¹(K_T + ∂g/∂T)` and
//! the coupling blocks `−M⁻¹ ∂f/∂T`, `−C_T⁻¹ ∂g/∂x`, `−C_T⁻¹ ∂g/∂v`, applied in factored
//! form (constant part + low-rank part on the nonlinear DoFs). Cost of one evaluation on a
//! 210-state system (72 mechanical DoF ×2 + 66 thermal, `benches/stability.rs`): see the
//! benchmark.
//!
//! Thermal multipliers sit within ~1e-5 of +1 (`exp(−P/τ)`, `τ` minutes, `P`
//! milliseconds). They are kept in [`FloquetResult`] as computed (a thermal runaway is an
//! instability), decided against the circle with [`UNIT_CIRCLE_TOL`], and can be reported
//! apart with [`split_thermal`], which matches them to predictions from the orbit-averaged
//! thermal block rather than by distance to +1 (which would also catch a mechanical
//! multiplier at a fold).

pub mod exp_sip;
pub mod expm;
pub mod frozen;
pub mod hill_near_zero;
pub mod locate;
pub mod modal;
pub mod reduced;
pub mod sip;
pub mod slow;
pub mod thermal;
pub mod variational;

pub use exp_sip::{ExpSip, IntervalMap, MeanSplit, panel_kernel_isa};
pub use expm::expm;
pub use frozen::{FrozenOrbit, FrozenTemperature};
mod join;
pub use hill_near_zero::{HillMode, HillOptions, HillPencil, NearZero, near_zero_exponents};
pub use locate::{Crossing, bisect_crossing};
pub use reduced::{CraigBampton, Reduced, ReducedOrbit, ReducedSystem, ReductionSettings};
pub use sip::{Sip, SipMonodromy};
pub use slow::{slow_exponents, slow_exponents_with, thermal_schur};
pub use thermal::{MultiplierSplit, split_thermal, thermal_multiplier_estimates};
pub use variational::{Shooting, Variational};

use faer::MatRef;
use num_complex::Complex64;
use thiserror::Error;

use crate::system::{PeriodicOrbit, System};

/// Floquet multipliers of one periodic solution.
///
/// For a system with a thermal field the result is split by time scale (see
/// [`assess`]): `multipliers` are the fast ones, of the vibration with the temperatures
/// held on their periodic course, and `slow_exponents` the thermal ones as exponents
/// `λ` (multipliers `exp(P·λ)`, within ~1e-6 of +1 and not resolvable as multipliers).
#[derive(Clone, Debug, PartialEq)]
pub struct FloquetResult {
    /// Eigenvalues of the monodromy matrix (full period), in no particular order; with a
    /// slow/fast split, those of the frozen-temperature problem.
    pub multipliers: Vec<Complex64>,
    /// Slow (thermal) Floquet exponents, 1/s, from the quasi-static reduction
    /// ([`slow::slow_exponents`]); empty without a thermal field.
    pub slow_exponents: Vec<Complex64>,
    /// True when every multiplier lies inside the unit circle and every slow exponent in
    /// the left half-plane (see [`FloquetResult::unstable_count`]).
    pub stable: bool,
    /// Intervals per period of the product the multipliers came from, for a method that
    /// chooses them per orbit ([`ExpSip`]'s refinement); `None` otherwise.
    pub intervals: Option<usize>,
    /// `γ = min |ln μ| / P` over the fast multipliers (1/s): the fast exponent nearest
    /// zero, the scale the slow exponents must stay below; `None` without a split.
    pub fast_gap: Option<f64>,
    /// The disk around zero in which `slow_exponents` are the coupled Floquet exponents of
    /// the balance, exactly (Hill's eigenproblem, [`hill_near_zero`]); `None` when they
    /// come from the quasi-static reduction or there are none.
    pub near_zero: Option<NearZeroDisk>,
    /// With a near-zero disk, one flag per entry of `multipliers`: set where the
    /// multiplier is the frozen-temperature estimate of an exponent the disk holds, and
    /// is superseded by it ([`NearZero::superseded`]); empty without a disk (or in a
    /// result rebuilt from a recording that predates the flags, where the disk's radius
    /// decides).
    pub superseded: Vec<bool>,
    /// Set when the parity of the number of real multipliers above +1 disagrees with the
    /// number of folds the branch has passed (see [`FloquetResult::with_branch_parity`]):
    /// the harmonic balance that defines the branch then has one real Floquet exponent
    /// above zero that the monodromy product of the orbit does not show, and it is counted
    /// as one multiplier outside the circle.
    pub fold_parity_mismatch: bool,
}

/// The slow modulation a Neimark–Sacker point starts: the crossing pair's angle and the
/// period of the oscillation it grows into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Modulation {
    /// The crossing exponent `λ` (1/s, positive imaginary part) when the pair is one of
    /// the near-zero disk's; `None` for a pair of fast multipliers.
    pub exponent: Option<Complex64>,
    /// Angle of the crossing multipliers, rad (`Im λ · P`, or `arg μ`), in `(0, π]`.
    pub angle_rad: f64,
    /// Period of the modulation, s: `2π P / angle`.
    pub period_s: f64,
    /// Share of the thermal capacity in the crossing mode, 0 (purely mechanical) … 1
    /// (purely thermal): the exponent's relative change under a change of every thermal
    /// capacity, `−(C_T/λ) ∂λ/∂C_T`; `None` when not computed.
    pub thermal_share: Option<f64>,
}

impl Modulation {
    /// A thermo-mechanical modulation: the crossing mode is mostly thermal (share above
    /// one half).
    pub fn thermo_mechanical(&self) -> bool {
        self.thermal_share.is_some_and(|s| s > 0.5)
    }
}

/// One multiplier as the verdict counts it ([`FloquetResult::counted`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Counted {
    /// The multiplier (for an exponent of the near-zero disk, `exp(λP)`).
    pub multiplier: Complex64,
    /// The exponent `λ` (1/s) when it comes from the near-zero disk.
    pub exponent: Option<Complex64>,
    /// How it leaves the circle: by the multiplier's position for a fast one, by the
    /// exponent's ([`BifurcationKind::of_exponent`]) for a near-zero one.
    pub kind: BifurcationKind,
    /// Its distance outside the circle, the quantity the stable flag and a crossing search
    /// test: `|μ| − (1 + UNIT_CIRCLE_TOL)` for a fast multiplier, `(Re λ − tol)·P` for a
    /// near-zero exponent ([`NearZeroDisk::tol`]); positive outside.
    pub excess: f64,
}

/// Where the exponents of Hill's eigenproblem supersede the monodromy product's: the disk
/// `|λ| < radius` (1/s) around zero, for an orbit of period `period` (s). A fast
/// multiplier `μ` with `|ln μ| / P` below the radius is the product's estimate of an
/// exponent the disk holds exactly, with the thermal coupling the product leaves out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearZeroDisk {
    pub radius: f64,
    pub period: f64,
    /// How far the disk's set reaches (1/s): no exponent of the balance lies between the
    /// radius and this ([`NearZero::outer`]); the radius itself when unknown.
    pub outer: f64,
    /// How many of the set's exponents are the thermal equations' ([`NearZero::thermal`];
    /// 0 when unknown).
    pub thermal: usize,
}

impl NearZeroDisk {
    /// Whether the fast multiplier `m` lies in the disk (its exponent is in the Hill set).
    pub fn holds(&self, m: Complex64) -> bool {
        m.norm() > 0.0 && m.ln().norm() / self.period < self.radius
    }

    /// Whether no multiplier of a period doubling can be superseded by this disk's
    /// exponents: such a multiplier (real part negative, imaginary part at most `0.05·|μ|`,
    /// [`BifurcationKind::of_multiplier`]) has `|ln μ|/P ≥ (π − asin 0.05)/P ≈ 3.0916/P`,
    /// and the join takes its candidates from within twice the radius ([`join`]). With
    /// the radius below 1.5/P (on the dual rotor it is 14–21 1/s against 1.5/P ≈ 120–240
    /// 1/s) the multipliers of that kind, and so a period-doubling search's test function,
    /// are those of the frozen-temperature product alone.
    pub fn clear_of_flips(&self) -> bool {
        self.radius * self.period < 1.5
    }

    /// A Hill exponent's real part above this counts as unstable: a relative rounding
    /// margin of the Arnoldi eigenvalues (their residual tolerance is 1e-10).
    pub fn tol(&self) -> f64 {
        1e-9 * self.radius
    }
}

/// A slow/fast split whose [`FloquetResult::split_ratio`] exceeds this is reported as not
/// separated: the deciding slow exponent's estimated error is then larger than half of it.
pub const SPLIT_RATIO_LIMIT: f64 = 0.5;

/// A slow exponent counts as unstable when its real part exceeds this fraction of the
/// largest slow exponent's modulus: a relative rounding margin of the 66×66 eigenvalue
/// problem (well below the change of the crossing exponent between neighbouring points of
/// a branch, which is of the order of the step).
pub const SLOW_EXPONENT_TOL: f64 = 1e-10;

impl FloquetResult {
    /// Builds a result, deciding `stable` with [`UNIT_CIRCLE_TOL`].
    pub fn new(multipliers: Vec<Complex64>) -> Self {
        let stable = unstable_count(&multipliers) == 0;
        Self {
            multipliers,
            slow_exponents: Vec::new(),
            stable,
            intervals: None,
            fast_gap: None,
            near_zero: None,
            superseded: Vec::new(),
            fold_parity_mismatch: false,
        }
    }

    /// The fast multipliers of `self` joined with the coupled exponents nearest zero
    /// `nz` of an orbit of period `period` (s): the exponents in the disk replace the
    /// fast multipliers there, and `stable` is decided again on the joint set.
    pub fn with_near_zero(self, nz: NearZero, period: f64) -> Self {
        let gamma = slow::fast_gap(&self.multipliers, period);
        let disk = NearZeroDisk {
            radius: join::edge(&nz, &self.multipliers, period),
            period,
            outer: nz.outer,
            thermal: nz.thermal,
        };
        let superseded = join::superseded(&self.multipliers, &nz.exponents, &disk, None);
        let mut r = Self {
            superseded,
            fast_gap: Some(gamma),
            slow_exponents: nz.exponents,
            near_zero: Some(disk),
            ..self
        };
        r.stable = r.unstable_count() == 0;
        r
    }

    /// The fast multipliers that count: all of them, or with a near-zero disk those it
    /// does not supersede ([`FloquetResult::superseded`]).
    pub fn counted_multipliers(&self) -> impl Iterator<Item = &Complex64> {
        let disk = self.near_zero;
        let flags = (self.superseded.len() == self.multipliers.len()).then_some(&self.superseded);
        self.multipliers
            .iter()
            .enumerate()
            .filter(move |(i, m)| match (disk, flags) {
                (Some(_), Some(f)) => !f[*i],
                (Some(d), None) => !d.holds(**m),
                (None, _) => true,
            })
            .map(|(_, m)| m)
    }

    /// The exponents of the near-zero disk with positive real part (empty without a disk).
    pub fn near_zero_unstable(&self) -> impl Iterator<Item = &Complex64> {
        let tol = self.near_zero.map_or(f64::INFINITY, |d| d.tol());
        self.slow_exponents.iter().filter(move |l| l.re > tol)
    }

    /// Every multiplier the verdict counts, as [`Counted`] entries: the fast ones (outside
    /// the near-zero disk, when there is one), then the disk's exponents.
    pub fn counted(&self) -> Vec<Counted> {
        let mut out: Vec<Counted> = self
            .counted_multipliers()
            .map(|m| Counted {
                multiplier: *m,
                exponent: None,
                kind: BifurcationKind::of_multiplier(*m),
                excess: m.norm() - (1.0 + UNIT_CIRCLE_TOL),
            })
            .collect();
        if let Some(d) = self.near_zero {
            out.extend(self.slow_exponents.iter().map(|l| Counted {
                multiplier: (l * d.period).exp(),
                exponent: Some(*l),
                kind: BifurcationKind::of_exponent(*l),
                excess: (l.re - d.tol()) * d.period,
            }));
        }
        out
    }

    /// The pair that crosses at a Neimark–Sacker point with this result on one side: of
    /// the near-zero disk, the complex exponent nearest the imaginary axis (relative to
    /// its modulus); else the complex fast multiplier nearest the unit circle. `period`
    /// is the orbit's (s). `None` when there is no complex pair.
    pub fn crossing_pair(&self, period: f64) -> Option<Modulation> {
        let near = self
            .slow_exponents
            .iter()
            .filter(|l| {
                self.near_zero.is_some()
                    && BifurcationKind::of_exponent(**l) == BifurcationKind::NeimarkSacker
            })
            .min_by(|a, b| (a.re / a.norm()).abs().total_cmp(&(b.re / b.norm()).abs()));
        if let Some(l) = near {
            let l = Complex64::new(l.re, l.im.abs());
            let angle = l.im * period;
            return Some(Modulation {
                exponent: Some(l),
                angle_rad: angle,
                period_s: std::f64::consts::TAU * period / angle,
                thermal_share: None,
            });
        }
        let m = self
            .counted_multipliers()
            .filter(|m| BifurcationKind::of_multiplier(**m) == BifurcationKind::NeimarkSacker)
            .min_by(|a, b| (a.norm() - 1.0).abs().total_cmp(&(b.norm() - 1.0).abs()))?;
        let angle = m.arg().abs();
        Some(Modulation {
            exponent: None,
            angle_rad: angle,
            period_s: std::f64::consts::TAU * period / angle,
            thermal_share: None,
        })
    }

    /// The same result, noting the intervals of the product.
    pub fn with_intervals(self, intervals: usize) -> Self {
        Self {
            intervals: Some(intervals),
            ..self
        }
    }

    /// The fast multipliers of `self` completed by the slow exponents `slow` (1/s) of an
    /// orbit of period `period` (s); `stable` decided again on both.
    pub fn with_slow(self, slow: Vec<Complex64>, period: f64) -> Self {
        let gamma = slow::fast_gap(&self.multipliers, period);
        let mut r = Self {
            fast_gap: Some(gamma),
            slow_exponents: slow,
            ..self
        };
        r.stable = r.unstable_count() == 0;
        r
    }

    /// The result on a branch that has passed an odd (`true`) or even number of folds
    /// since its start, where the count is assumed right: at each fold of a branch of
    /// harmonic-balance solutions the determinant of the balance's Jacobian changes sign
    /// and one real Floquet exponent of the balance passes zero, so the number of real
    /// multipliers above +1 has the parity of the folds passed. Where the product's count
    /// has the other parity, the balance's real exponent is one the product does not
    /// resolve (the truncated balance and the orbit's linearisation disagree there, see
    /// `docs/stability.md`): it is counted, and the disagreement recorded
    /// ([`FloquetResult::fold_parity_mismatch`]).
    ///
    /// With a near-zero disk the superseded multipliers are chosen again knowing the
    /// parity ([`join`]).
    pub fn with_branch_parity(self, odd_folds: bool) -> Self {
        let superseded = match &self.near_zero {
            Some(d) => {
                join::superseded(&self.multipliers, &self.slow_exponents, d, Some(odd_folds))
            }
            None => self.superseded.clone(),
        };
        let base = Self {
            fold_parity_mismatch: false,
            superseded,
            ..self
        };
        let mismatch = (base.product_real_above_one() % 2 == 1) != odd_folds;
        let mut r = Self {
            fold_parity_mismatch: mismatch,
            ..base
        };
        r.stable = r.unstable_count() == 0;
        r
    }

    /// Number of multipliers with modulus above `1 + UNIT_CIRCLE_TOL`, plus the slow
    /// complex pairs in the right half-plane ([`Self::slow_unstable_count`]), plus one for
    /// a fold-parity mismatch: the count of multipliers outside the unit circle.
    pub fn unstable_count(&self) -> usize {
        let outside = self.counted().iter().filter(|c| c.excess > 0.0).count();
        let legacy_slow = if self.near_zero.is_some() {
            0
        } else {
            self.slow_unstable_count()
        };
        outside + legacy_slow + usize::from(self.fold_parity_mismatch)
    }

    /// The slow exponents in the right half-plane whose sign the split decides: real part
    /// above [`SLOW_EXPONENT_TOL`] of the largest modulus, and modulus below
    /// [`SPLIT_RATIO_LIMIT`] of the fast gap (beyond it the exponent is not slow against
    /// the fast exponent nearest zero and the reduction does not hold for it).
    pub fn decided_slow(&self) -> impl Iterator<Item = &Complex64> {
        let scale = self
            .slow_exponents
            .iter()
            .map(|l| l.norm())
            .fold(0.0, f64::max);
        let gap = self.fast_gap.unwrap_or(f64::INFINITY);
        self.slow_exponents.iter().filter(move |l| {
            l.re > SLOW_EXPONENT_TOL * scale && slow::ratio_to_gap(**l, gap) <= SPLIT_RATIO_LIMIT
        })
    }

    /// Number of slow exponents of complex pairs in the right half-plane (a slow,
    /// oscillating thermo-mechanical instability), counted in the verdict.
    ///
    /// Real slow exponents are not counted one by one: `det J = det J_rr · det S`, so a
    /// real one passes zero only where the branch folds, and the fold parity
    /// ([`Self::with_branch_parity`]) accounts for it. Counted directly they would also
    /// carry the poles of the reduction: where the balance's mechanical block `J_rr` is
    /// nearly singular next to a fold the product does not confirm, `S` has a pole and a
    /// real slow exponent passes through infinity (measured on the 10 L/min run at
    /// 582.33 rad/s: +0.16 1/s one point before the fold, −3.4e-5 1/s elsewhere; see
    /// `docs/stability.md`).
    pub fn slow_unstable_count(&self) -> usize {
        if self.near_zero.is_some() {
            return self.near_zero_unstable().count();
        }
        self.decided_slow()
            .filter(|l| BifurcationKind::of_exponent(**l) == BifurcationKind::NeimarkSacker)
            .count()
    }

    /// Number of real multipliers above +1: real fast multipliers beyond
    /// `1 + UNIT_CIRCLE_TOL`, and one for a fold-parity mismatch.
    pub fn real_above_one(&self) -> usize {
        self.product_real_above_one() + usize::from(self.fold_parity_mismatch)
    }

    /// Number of real fast multipliers beyond `1 + UNIT_CIRCLE_TOL` (the monodromy
    /// product's own count, without the fold-parity correction).
    ///
    /// With a near-zero disk, the fast multipliers outside it and the real exponents in
    /// it with positive real part: the count of the joint set.
    pub fn product_real_above_one(&self) -> usize {
        self.counted()
            .iter()
            .filter(|c| c.excess > 0.0 && c.kind == BifurcationKind::SaddleNode)
            .count()
    }

    /// Estimated relative error of the slow exponent with the largest real part (the one
    /// that decides the slow part of the verdict): `|λ|/γ`, `γ` the fast exponent nearest
    /// zero ([`FloquetResult::fast_gap`]). Above [`SPLIT_RATIO_LIMIT`] the time scales are
    /// not separated (a fast multiplier near +1) and the verdict is uncertain. `None`
    /// without a split.
    pub fn split_ratio(&self) -> Option<f64> {
        if self.near_zero.is_some() {
            return None;
        }
        let gap = self.fast_gap?;
        self.slow_exponents
            .iter()
            .max_by(|a, b| a.re.total_cmp(&b.re))
            .map(|l| slow::ratio_to_gap(*l, gap))
    }

    /// Whether the time scales of the split are too close for a sure verdict (see
    /// [`FloquetResult::split_ratio`]).
    pub fn split_uncertain(&self) -> bool {
        self.split_ratio().is_some_and(|r| r > SPLIT_RATIO_LIMIT)
    }

    /// Largest multiplier modulus.
    pub fn spectral_radius(&self) -> f64 {
        self.multipliers
            .iter()
            .map(|m| m.norm())
            .fold(0.0, f64::max)
    }
}

/// A multiplier counts as outside the unit circle when `|μ| > 1 + UNIT_CIRCLE_TOL`.
///
/// Why 1e-6: slow thermal modes give real multipliers `exp(−P/τ_th)` just below +1
/// (thermal time constants of minutes against periods of milliseconds), and the
/// trivial multiplier of an autonomous direction sits at +1 to within the accuracy of
/// the monodromy matrix; a tolerance keeps both from flipping the stable flag.
pub const UNIT_CIRCLE_TOL: f64 = 1e-6;

fn unstable_count(multipliers: &[Complex64]) -> usize {
    multipliers
        .iter()
        .filter(|m| m.norm() > 1.0 + UNIT_CIRCLE_TOL)
        .count()
}

/// How a periodic solution loses or gains stability.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BifurcationKind {
    /// A real multiplier crosses the unit circle at +1 (fold / saddle-node; also
    /// transcritical or symmetry breaking).
    SaddleNode,
    /// A real multiplier crosses at −1.
    PeriodDoubling,
    /// A complex-conjugate pair crosses away from the real axis.
    NeimarkSacker,
}

impl BifurcationKind {
    /// Short lower-case label used in text: messages, logs, the report.
    pub fn label(self) -> &'static str {
        match self {
            Self::SaddleNode => "saddle-node",
            Self::PeriodDoubling => "period-doubling",
            Self::NeimarkSacker => "neimark-sacker",
        }
    }

    /// Identifier used in tables (CSV, DataFrames): `saddle_node`, `period_doubling`,
    /// `neimark_sacker`.
    pub fn key(self) -> &'static str {
        match self {
            Self::SaddleNode => "saddle_node",
            Self::PeriodDoubling => "period_doubling",
            Self::NeimarkSacker => "neimark_sacker",
        }
    }

    /// Abbreviation used on figures: `SN`, `PD`, `NS`.
    pub fn abbreviation(self) -> &'static str {
        match self {
            Self::SaddleNode => "SN",
            Self::PeriodDoubling => "PD",
            Self::NeimarkSacker => "NS",
        }
    }

    /// The kind of crossing a multiplier `m` makes when it leaves the unit circle where it
    /// lies: a complex pair (imaginary part above `0.05·|μ|`) makes a Neimark–Sacker
    /// point, a real multiplier a saddle-node on the positive and a period doubling on the
    /// negative side (the criterion of [`classify_crossing`]).
    pub fn of_multiplier(m: Complex64) -> Self {
        if m.im.abs() > 0.05 * m.norm() {
            Self::NeimarkSacker
        } else if m.re > 0.0 {
            Self::SaddleNode
        } else {
            Self::PeriodDoubling
        }
    }
}

impl BifurcationKind {
    /// The kind of crossing a slow exponent `λ` makes when it leaves the left half-plane:
    /// a real one (imaginary part at most `0.05·|λ|`) a saddle-node (its multiplier
    /// `exp(P·λ)` passes +1), a complex pair a Neimark–Sacker point.
    pub fn of_exponent(l: Complex64) -> Self {
        if l.im.abs() > 0.05 * l.norm() {
            Self::NeimarkSacker
        } else {
            Self::SaddleNode
        }
    }
}

/// Errors of the stability layer.
#[derive(Debug, Error)]
pub enum StabilityError {
    #[error("monodromy matrix has non-finite entries at ω = {omega} rad/s")]
    NonFinite { omega: f64 },
    #[error("eigenvalue solver failed for the {dim}×{dim} monodromy matrix: {reason}")]
    Eigen { dim: usize, reason: String },
    #[error("cannot set up the linearised equations at ω = {omega} rad/s: {reason}")]
    Setup { omega: f64, reason: String },
    #[error("invalid stability setting {field} = {value}: {reason}")]
    Setting {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
}

/// True when every entry of `a` is finite.
pub(crate) fn all_finite(a: MatRef<'_, f64>) -> bool {
    (0..a.ncols()).all(|j| a.col(j).iter().all(|v| v.is_finite()))
}

/// Eigenvalues of a monodromy matrix (faer's real Schur-based solver), rejecting
/// non-finite input. `omega` only labels errors.
pub fn eigenvalues_checked(
    monodromy: MatRef<'_, f64>,
    omega: f64,
) -> Result<Vec<Complex64>, StabilityError> {
    if !all_finite(monodromy) {
        return Err(StabilityError::NonFinite { omega });
    }
    monodromy.eigenvalues().map_err(|e| StabilityError::Eigen {
        dim: monodromy.nrows(),
        reason: format!("{e:?}"),
    })
}

/// A way of computing the Floquet multipliers of a periodic solution. The continuation
/// calls it at every point; implementations live in this module's submodules.
pub trait StabilityMethod: Sync {
    /// Multipliers of `orbit`, a periodic solution of `system`.
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError>;

    /// Multipliers for the trials of a bifurcation search between two points whose
    /// results are `ends`; the trials by design come ever closer to the unit circle. A
    /// method that refines its accuracy near the circle ([`ExpSip`]) uses one fixed
    /// accuracy here, that of the finer end: the trials then see one smooth function of
    /// the branch (a refinement level that changes between neighbouring trials makes the
    /// crossing multiplier jump by the size of its error), as accurate as the ends that
    /// bracket the crossing. Default: [`Self::multipliers`].
    fn search_multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        ends: [&FloquetResult; 2],
    ) -> Result<FloquetResult, StabilityError> {
        let _ = ends;
        self.multipliers(system, orbit)
    }
}

/// Classifies the stability change between two neighbouring points of a branch from
/// their multipliers, or `None` when the number of multipliers outside the unit circle is
/// the same on both sides.
///
/// The multiplier(s) that crossed are taken from the side where they are outside: the
/// ones outside the circle there that lie closest to it. A crossing multiplier with an
/// imaginary part above `0.05·|μ|` (a genuine complex pair) is Neimark–Sacker; otherwise the
/// sign of its real part decides between saddle-node (+1) and period doubling (−1).
pub fn classify_crossing(before: &FloquetResult, after: &FloquetResult) -> Option<BifurcationKind> {
    let (nb, na) = (before.unstable_count(), after.unstable_count());
    if nb == na {
        return None;
    }
    let outside = if na > nb { after } else { before };
    if outside.near_zero.is_some()
        && before.slow_unstable_count() != after.slow_unstable_count()
        && let Some(l) = outside
            .near_zero_unstable()
            .min_by(|a, b| a.re.total_cmp(&b.re))
    {
        return Some(BifurcationKind::of_exponent(*l));
    }
    if before.slow_unstable_count() != after.slow_unstable_count()
        && let Some(l) = outside.decided_slow().min_by(|a, b| a.re.total_cmp(&b.re))
    {
        return Some(BifurcationKind::of_exponent(*l));
    }
    if before.fold_parity_mismatch != after.fold_parity_mismatch {
        return Some(BifurcationKind::SaddleNode);
    }
    let crossing = outside
        .multipliers
        .iter()
        .filter(|m| m.norm() > 1.0 + UNIT_CIRCLE_TOL)
        .min_by(|a, b| a.norm().total_cmp(&b.norm()))?;
    Some(BifurcationKind::of_multiplier(*crossing))
}

/// Whether the monodromy product confirms a fold between two neighbouring points with
/// results `before` and `after`: its own count of real multipliers above +1 (without the
/// fold-parity correction) changes between them.
pub fn confirms_fold(before: &FloquetResult, after: &FloquetResult) -> bool {
    before.product_real_above_one() != after.product_real_above_one()
}

/// Multipliers of `solution`, a converged point of `hb`, by `evaluate` (a
/// [`StabilityMethod`]'s evaluation), split by time scale when the system has a thermal
/// field: the fast multipliers from `evaluate` on the frozen-temperature problem
/// ([`FrozenTemperature`]), the slow exponents from the quasi-static reduction of the
/// harmonic-balance Jacobian ([`slow::slow_exponents`]; `jacobian`, when given, is
/// `∂R/∂A` at the point), side by side. Without thermal DoFs: `evaluate` on the system
/// itself.
pub fn assess(
    method: &dyn StabilityMethod,
    hb: &crate::hb::HarmonicBalance<'_>,
    solution: &crate::hb::HbSolution,
    jacobian: Option<&crate::hb::JacobianParts>,
    evaluate: impl FnOnce(
        &dyn StabilityMethod,
        &dyn System,
        &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError>
    + Send,
) -> Result<FloquetResult, StabilityError> {
    let system = hb.system();
    if system.n_therm() == 0 {
        return evaluate(method, system, solution);
    }
    let (fast, slow) = rayon::join(
        || assess_fast(method, hb, solution, evaluate),
        || hill_near_zero::near_zero_exponents(hb, solution, jacobian, &HillOptions::default()),
    );
    Ok(fast?.with_near_zero(slow?, solution.period()))
}

/// The fast half of [`assess`]: the multipliers of `evaluate` on the frozen-temperature
/// problem alone, without the coupled exponents nearest zero (on a system without thermal
/// DoFs, `evaluate` on the system itself, as [`assess`]). For what needs only multipliers
/// the near-zero disk cannot supersede: a period doubling's multiplier near −1 has
/// `|ln μ|/P ≥ (π − asin 0.05)/P`, outside any disk of radius below half that
/// ([`NearZeroDisk::clear_of_flips`]).
pub fn assess_fast(
    method: &dyn StabilityMethod,
    hb: &crate::hb::HarmonicBalance<'_>,
    solution: &crate::hb::HbSolution,
    evaluate: impl FnOnce(
        &dyn StabilityMethod,
        &dyn System,
        &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError>,
) -> Result<FloquetResult, StabilityError> {
    let system = hb.system();
    if system.n_therm() == 0 {
        return evaluate(method, system, solution);
    }
    let frozen = FrozenTemperature::new(system, solution);
    evaluate(
        method,
        &frozen,
        &FrozenOrbit::new(solution, system.n_therm()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn res(m: &[(f64, f64)]) -> FloquetResult {
        FloquetResult::new(m.iter().map(|&(re, im)| Complex64::new(re, im)).collect())
    }

    #[test]
    fn crossings_are_classified_by_where_they_leave_the_circle() {
        let stable = res(&[(0.9, 0.0), (0.2, 0.3), (0.2, -0.3)]);
        let fold = res(&[(1.1, 0.0), (0.2, 0.3), (0.2, -0.3)]);
        let flip = res(&[(-1.05, 0.0), (0.2, 0.3), (0.2, -0.3)]);
        let ns = res(&[(0.9, 0.0), (0.6, 0.9), (0.6, -0.9)]);
        assert!(stable.stable && !fold.stable);
        assert_eq!(
            classify_crossing(&stable, &fold),
            Some(BifurcationKind::SaddleNode)
        );
        assert_eq!(
            classify_crossing(&fold, &stable),
            Some(BifurcationKind::SaddleNode)
        );
        assert_eq!(
            classify_crossing(&stable, &flip),
            Some(BifurcationKind::PeriodDoubling)
        );
        assert_eq!(
            classify_crossing(&stable, &ns),
            Some(BifurcationKind::NeimarkSacker)
        );
        assert_eq!(classify_crossing(&stable, &stable), None);
    }

    #[test]
    fn thermal_multipliers_just_below_one_stay_stable() {
        let r = res(&[(1.0 - 1e-9, 0.0), (1.0 + 1e-9, 0.0)]);
        assert!(r.stable);
    }
}
