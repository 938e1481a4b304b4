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
pub mod locate;
pub mod modal;
pub mod reduced;
pub mod sip;
pub mod thermal;
pub mod variational;

pub use exp_sip::{ExpSip, IntervalMap, MeanSplit, panel_kernel_isa};
pub use expm::expm;
pub use locate::{Crossing, bisect_crossing};
pub use reduced::{CraigBampton, Reduced, ReducedOrbit, ReducedSystem, ReductionSettings};
pub use sip::{Sip, SipMonodromy};
pub use thermal::{MultiplierSplit, split_thermal, thermal_multiplier_estimates};
pub use variational::Variational;

use faer::MatRef;
use num_complex::Complex64;
use thiserror::Error;

use crate::system::{PeriodicOrbit, System};

/// Floquet multipliers of one periodic solution.
#[derive(Clone, Debug, PartialEq)]
pub struct FloquetResult {
    /// Eigenvalues of the monodromy matrix (full period), in no particular order.
    pub multipliers: Vec<Complex64>,
    /// True when every multiplier lies inside the unit circle (within the method's
    /// tolerance, see [`FloquetResult::unstable_count`]).
    pub stable: bool,
    /// Intervals per period of the product the multipliers came from, for a method that
    /// chooses them per orbit ([`ExpSip`]'s refinement); `None` otherwise.
    pub intervals: Option<usize>,
}

impl FloquetResult {
    /// Builds a result, deciding `stable` with [`UNIT_CIRCLE_TOL`].
    pub fn new(multipliers: Vec<Complex64>) -> Self {
        let stable = unstable_count(&multipliers) == 0;
        Self {
            multipliers,
            stable,
            intervals: None,
        }
    }

    /// The same result, noting the intervals of the product.
    pub fn with_intervals(self, intervals: usize) -> Self {
        Self {
            intervals: Some(intervals),
            ..self
        }
    }

    /// Number of multipliers with modulus above `1 + UNIT_CIRCLE_TOL`.
    pub fn unstable_count(&self) -> usize {
        unstable_count(&self.multipliers)
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
    /// Short lower-case label used in CSV output and recordings.
    pub fn label(self) -> &'static str {
        match self {
            Self::SaddleNode => "saddle-node",
            Self::PeriodDoubling => "period-doubling",
            Self::NeimarkSacker => "neimark-sacker",
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
    let crossing = outside
        .multipliers
        .iter()
        .filter(|m| m.norm() > 1.0 + UNIT_CIRCLE_TOL)
        .min_by(|a, b| a.norm().total_cmp(&b.norm()))?;
    Some(BifurcationKind::of_multiplier(*crossing))
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
