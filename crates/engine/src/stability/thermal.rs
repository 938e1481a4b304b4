//! Reporting thermal multipliers apart from mechanical ones.
//!
//! Thermal time constants (minutes) are long against vibration periods (milliseconds), so
//! the thermal DoFs contribute real multipliers `exp(−P/τ)` within ~1e-5 of +1. They are
//! genuine multipliers of the coupled problem and stay in [`FloquetResult`] (the stable
//! flag counts them: a thermal runaway *is* an instability), but next to a mechanical
//! multiplier approaching +1 at a fold they are easy to confuse with it, and plots of
//! "the" multipliers are unreadable with 66 of them piled on +1.
//!
//! The split is deliberate rather than by a distance-to-one threshold (which would also
//! catch a mechanical multiplier at a fold): the thermal multipliers are predicted from the
//! thermal block alone, `exp(P·λ)` for the eigenvalues `λ` of
//! `−C_T⁻¹(K_T + Q ⟨∂g/∂T⟩ Qᵀ)` with `⟨·⟩` the mean over the orbit
//! ([`thermal_multiplier_estimates`]), and each prediction claims the nearest unclaimed
//! computed multiplier ([`split_thermal`]). The neglected mechanical–thermal coupling
//! moves the thermal multipliers by far less than their distance to the mechanical ones
//! in the systems at hand; the split reports the largest prediction mismatch so a user
//! can see when that assumption fails.

use faer::Mat;
use num_complex::Complex64;

use super::{FloquetResult, StabilityError, eigenvalues_checked};
use crate::integrate::StateSpace;
use crate::system::{PeriodicOrbit, System};

/// Multipliers split into thermal and mechanical ones.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiplierSplit {
    /// Multipliers matched to the thermal predictions (one per thermal DoF).
    pub thermal: Vec<Complex64>,
    /// All other multipliers (`2 n_mech` of them).
    pub mechanical: Vec<Complex64>,
    /// `max |μ − μ_predicted|` over the thermal matches.
    pub max_mismatch: f64,
}

impl MultiplierSplit {
    /// True when every mechanical multiplier is inside the circle (within
    /// [`super::UNIT_CIRCLE_TOL`]).
    pub fn mechanical_stable(&self) -> bool {
        FloquetResult::new(self.mechanical.clone()).stable
    }
}

/// Predicted thermal multipliers `exp(P·λ)`, `λ` the eigenvalues of the orbit-averaged
/// thermal block (see the module docs); 64 instants for the average.
pub fn thermal_multiplier_estimates(
    system: &dyn System,
    orbit: &dyn PeriodicOrbit,
) -> Result<Vec<Complex64>, StabilityError> {
    let omega = orbit.omega();
    let period = orbit.period();
    let space = StateSpace::new(system, omega).map_err(|e| StabilityError::Setup {
        omega,
        reason: e.to_string(),
    })?;
    let m = space.n_therm();
    if m == 0 {
        return Ok(Vec::new());
    }
    let (_, _, ckt) = space.linear_blocks();
    let (_, cq) = space.spread_columns();
    let q = cq.ncols();
    let therm = space.dofs().therm.clone();
    let mut ws = space.workspace();
    let mut mean = vec![0.0; q * q];
    let n = space.n_mech();
    let (mut x, mut v, mut temp) = (vec![0.0; n], vec![0.0; n], vec![0.0; m]);
    const SAMPLES: usize = 64;
    for j in 0..SAMPLES {
        let t = j as f64 * period / SAMPLES as f64;
        orbit.state_at(t, &mut x, &mut v, &mut temp);
        space.eval_nonlinear_at(t, &x, &v, &temp, &mut ws);
        for (a, b) in mean.iter_mut().zip(&ws.eval.dg_dt) {
            *a += b / SAMPLES as f64;
        }
    }
    // A = −C_T⁻¹K_T − (C_T⁻¹Q) ⟨∂g/∂T⟩ Qᵀ.
    let mut a = Mat::from_fn(m, m, |i, j| -ckt[(i, j)]);
    for (kcol, &jt) in therm.iter().enumerate() {
        for i in 0..m {
            let s: f64 = (0..q).map(|r| cq[(i, r)] * mean[r * q + kcol]).sum();
            a[(i, jt)] -= s;
        }
    }
    let lambdas = eigenvalues_checked(a.as_ref(), omega)?;
    Ok(lambdas.iter().map(|l| (l * period).exp()).collect())
}

/// Splits `multipliers` into the ones nearest to the `predicted` thermal multipliers
/// (greedy, predictions closest to +1 first) and the rest.
pub fn split_thermal(multipliers: &[Complex64], predicted: &[Complex64]) -> MultiplierSplit {
    let mut order: Vec<usize> = (0..predicted.len()).collect();
    order.sort_by(|&a, &b| {
        (predicted[a] - 1.0)
            .norm()
            .total_cmp(&(predicted[b] - 1.0).norm())
    });
    let mut taken = vec![false; multipliers.len()];
    let mut thermal = Vec::with_capacity(predicted.len());
    let mut max_mismatch: f64 = 0.0;
    for &k in &order {
        let best = (0..multipliers.len())
            .filter(|&i| !taken[i])
            .min_by(|&a, &b| {
                (multipliers[a] - predicted[k])
                    .norm()
                    .total_cmp(&(multipliers[b] - predicted[k]).norm())
            });
        if let Some(i) = best {
            taken[i] = true;
            thermal.push(multipliers[i]);
            max_mismatch = max_mismatch.max((multipliers[i] - predicted[k]).norm());
        }
    }
    let mechanical = multipliers
        .iter()
        .zip(&taken)
        .filter(|(_, t)| !**t)
        .map(|(m, _)| *m)
        .collect();
    MultiplierSplit {
        thermal,
        mechanical,
        max_mismatch,
    }
}
