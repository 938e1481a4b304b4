//! Locating a stability change between two parameter values by bisection.
//!
//! Given a map `parameter → multipliers` (the caller corrects the periodic orbit at each
//! parameter value, e.g. a continuation corrector or shooting) and a bracket on whose ends
//! the number of multipliers outside the unit circle differs, [`bisect_crossing`] halves
//! the bracket until it is shorter than `tol`, keeping the half whose ends still differ,
//! and classifies the crossing with [`classify_crossing`] from the final bracket ends.
//! Bisection needs no derivative of the multipliers and is robust for all three kinds
//! (a test function such as `det(E − I)` would need one per kind); each halving costs one
//! orbit correction and one Floquet evaluation.

use super::{BifurcationKind, FloquetResult, StabilityError, classify_crossing};

/// A located stability change.
#[derive(Clone, Debug)]
pub struct Crossing {
    /// Bracket end on the side of the first evaluation (`lo` argument).
    pub lo: f64,
    /// Other bracket end; `|hi − lo| ≤ tol`.
    pub hi: f64,
    /// Multipliers at `lo`.
    pub before: FloquetResult,
    /// Multipliers at `hi`.
    pub after: FloquetResult,
    /// How the multipliers cross (None only if the classification finds no outside
    /// multiplier, which the bracket rules out).
    pub kind: Option<BifurcationKind>,
    /// Number of calls of the map.
    pub evaluations: usize,
}

impl Crossing {
    /// Midpoint of the final bracket.
    pub fn parameter(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }
}

/// Bisects `[lo, hi]` (either order) for the change in the number of multipliers outside
/// the unit circle; see the module docs.
pub fn bisect_crossing<F>(
    mut multipliers_at: F,
    lo: f64,
    hi: f64,
    tol: f64,
) -> Result<Crossing, StabilityError>
where
    F: FnMut(f64) -> Result<FloquetResult, StabilityError>,
{
    if tol.is_nan() || tol <= 0.0 {
        return Err(StabilityError::Setting {
            field: "bisection tol",
            value: tol.to_string(),
            reason: "must be positive",
        });
    }
    let (mut a, mut b) = (lo, hi);
    let mut ra = multipliers_at(a)?;
    let mut rb = multipliers_at(b)?;
    let mut evaluations = 2;
    if ra.unstable_count() == rb.unstable_count() {
        return Err(StabilityError::Setting {
            field: "bisection bracket",
            value: format!("[{lo}, {hi}]"),
            reason: "the number of multipliers outside the unit circle is the same at both ends",
        });
    }
    while (b - a).abs() > tol {
        let mid = 0.5 * (a + b);
        let rm = multipliers_at(mid)?;
        evaluations += 1;
        if rm.unstable_count() == ra.unstable_count() {
            a = mid;
            ra = rm;
        } else {
            b = mid;
            rb = rm;
        }
    }
    let kind = classify_crossing(&ra, &rb);
    Ok(Crossing {
        lo: a,
        hi: b,
        before: ra,
        after: rb,
        kind,
        evaluations,
    })
}
