//! Hertzian rolling-element bearing force (paper Eqs. 3–5).
//!
//! For a bearing with `N` rolling elements, the deflection of element `k` is (Eq. 3)
//!
//! ```text
//!   δ_k = dx cos θ_k + dy sin θ_k − δe,      θ_k = 2π (k − 1)/N + ω_c t,
//!   δe  = δ0 + δv
//! ```
//!
//! where `dx`, `dy` are the displacements of the inner-ring node minus those of the
//! outer-ring node (x vertical, y horizontal), `δ0` the initial radial clearance and `δv`
//! the thermal clearance variation ([`super::expansion`]). The restoring force on the
//! inner ring (acting on the left-hand side, i.e. it *opposes* `dx`, `dy`) and the radial
//! bearing load are (Eqs. 4–5)
//!
//! ```text
//!   [Fx, Fy] = k Σ δ_k^n H(δ_k) [cos θ_k, sin θ_k],     Fb = k Σ δ_k^n H(δ_k)
//! ```
//!
//! with `n = 3/2` for ball and `n = 10/9` for roller bearings, `H` the Heaviside step
//! (`H(0) = 0`). The cage turns at `ω_c = (d_i ω_i + d_o ω_o)/(d_i + d_o)` with `d_i`,
//! `d_o` the inner and outer raceway diameters; for the inter-shaft bearing both rings
//! turn. The exact derivatives follow from `∂δ_k/∂dx = cos θ_k`, `∂δ_k/∂dy = sin θ_k`,
//! `∂δ_k/∂δv = −1` and `d(δ^n)/dδ = n δ^(n−1)`; both exponents exceed 1, so the force is
//! C¹ in the displacements across contact onset (the derivative vanishes at `δ_k = 0`).

use super::{BearingError, check_positive};
use std::f64::consts::PI;

/// The contact law of a rolling element: the one definition of a bearing kind, used by the
/// model file (`kind = "ball" | "roller"`), the linearised bearings of the modal analysis
/// ([`super::linear`]), the thermal network's contact resistances and the coupled rotor's
/// nonlinear force ([`HertzBearing`]). A new law is a new variant with its
/// [`Self::element_load`]; everything above takes it from there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactLaw {
    /// Point contact, `n = 3/2`.
    Ball,
    /// Line contact, `n = 10/9`.
    Roller,
}

impl ContactLaw {
    /// Load–deflection exponent `n`.
    pub fn exponent(self) -> f64 {
        match self {
            ContactLaw::Ball => 1.5,
            ContactLaw::Roller => 10.0 / 9.0,
        }
    }

    /// The name in model files (`"ball"`, `"roller"`).
    pub fn label(self) -> &'static str {
        match self {
            ContactLaw::Ball => "ball",
            ContactLaw::Roller => "roller",
        }
    }

    /// Volume (m³) of one rolling element of diameter `d` (m): a sphere, or a cylinder of
    /// length `roller_length` (m; ignored for balls). The thermal network's element
    /// capacity and the generated network's cage mass both use it.
    pub fn element_volume(self, d: f64, roller_length: f64) -> f64 {
        match self {
            ContactLaw::Ball => std::f64::consts::PI / 6.0 * d * d * d,
            ContactLaw::Roller => std::f64::consts::PI / 4.0 * d * d * roller_length,
        }
    }

    /// Surface (m²) of one rolling element of diameter `d` (m): a sphere, or a cylinder of
    /// length `roller_length` (m) with its two end faces.
    pub fn element_area(self, d: f64, roller_length: f64) -> f64 {
        match self {
            ContactLaw::Ball => std::f64::consts::PI * d * d,
            ContactLaw::Roller => {
                std::f64::consts::PI * d * roller_length + 0.5 * std::f64::consts::PI * d * d
            }
        }
    }

    /// Load `p = k δⁿ` (N) of one rolling element with contact stiffness `k` (N/m^n) at
    /// deflection `δ` (m), and its exact slope `dp/dδ = n k δⁿ⁻¹`; both 0 for `δ ≤ 0`
    /// (Heaviside contact, Eq. 4).
    #[inline]
    pub fn element_load(self, stiffness: f64, delta: f64) -> (f64, f64) {
        if delta <= 0.0 {
            return (0.0, 0.0);
        }
        // δ^{3/2} = δ √δ for balls (cheaper than powf, exact to rounding)
        let p = stiffness
            * match self {
                ContactLaw::Ball => delta * delta.sqrt(),
                ContactLaw::Roller => delta.powf(self.exponent()),
            };
        (p, self.exponent() * p / delta)
    }
}

/// Cage angular speed (rad/s) from the ring speeds and raceway diameters (section 2.1):
/// `ω_c = (d_i ω_i + d_o ω_o)/(d_i + d_o)`.
pub fn cage_speed_rad_s(
    inner_raceway_m: f64,
    outer_raceway_m: f64,
    inner_speed_rad_s: f64,
    outer_speed_rad_s: f64,
) -> f64 {
    (inner_raceway_m * inner_speed_rad_s + outer_raceway_m * outer_speed_rad_s)
        / (inner_raceway_m + outer_raceway_m)
}

/// Mechanical data of one rolling-element bearing for Eqs. 3–5.
#[derive(Clone, Debug, PartialEq)]
pub struct HertzBearing {
    /// Contact type (exponent).
    pub law: ContactLaw,
    /// Number of rolling elements `N`.
    pub n_elements: usize,
    /// Hertzian contact stiffness `k` (N/m^n).
    pub stiffness: f64,
    /// Initial radial clearance `δ0` (m).
    pub clearance_m: f64,
    /// Inner raceway diameter `d_i` (m), for the cage speed.
    pub inner_raceway_m: f64,
    /// Outer raceway diameter `d_o` (m), for the cage speed.
    pub outer_raceway_m: f64,
}

/// Force, load and derivatives of one bearing at one instant.
///
/// `jac[r][c]` is the derivative of output `r ∈ {Fx, Fy, Fb}` with respect to input
/// `c ∈ {dx, dy, δv}`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BearingForce {
    /// Restoring force on the inner ring along x (N); the outer ring gets `−fx`.
    pub fx: f64,
    /// Restoring force on the inner ring along y (N).
    pub fy: f64,
    /// Radial bearing load `Fb` (N, Eq. 5).
    pub fb: f64,
    /// Number of rolling elements with `δ_k > 0`.
    pub n_loaded: usize,
    /// Exact partial derivatives, rows (Fx, Fy, Fb), columns (dx, dy, δv).
    pub jac: [[f64; 3]; 3],
}

impl HertzBearing {
    /// Checks the data (positive stiffness, raceways, at least one element, clearance
    /// finite; a negative initial clearance, i.e. a preload, is allowed).
    pub fn validate(&self) -> Result<(), BearingError> {
        if self.n_elements == 0 {
            return Err(BearingError::NoElements(0));
        }
        check_positive("stiffness", self.stiffness)?;
        check_positive("inner_raceway_m", self.inner_raceway_m)?;
        check_positive("outer_raceway_m", self.outer_raceway_m)?;
        if !self.clearance_m.is_finite() {
            return Err(BearingError::NotPositive {
                field: "clearance_m",
                value: self.clearance_m,
            });
        }
        Ok(())
    }

    /// Cage speed (rad/s) for the given ring speeds.
    pub fn cage_speed_rad_s(&self, inner_speed_rad_s: f64, outer_speed_rad_s: f64) -> f64 {
        cage_speed_rad_s(
            self.inner_raceway_m,
            self.outer_raceway_m,
            inner_speed_rad_s,
            outer_speed_rad_s,
        )
    }

    /// Each rolling element's penetration `δ_j = Δx cos φ_j + Δy sin φ_j − (δ0 + δv)` with
    /// `cos φ_j`, `sin φ_j`, `φ_j = ω_c t + 2πj/N` (arguments as [`Self::force`]): the
    /// element carries load while it is positive.
    pub fn penetrations(
        &self,
        dx_m: f64,
        dy_m: f64,
        delta_v_m: f64,
        cage_angle_rad: f64,
    ) -> impl Iterator<Item = (f64, f64, f64)> {
        let clearance = self.clearance_m + delta_v_m;
        // element angles by rotation from the first (one sin_cos per call instead of one
        // per element; the recurrence's rounding stays at ~1e-16 per element)
        let (s_step, c_step) = (2.0 * PI / self.n_elements as f64).sin_cos();
        let (s0, c0) = cage_angle_rad.sin_cos();
        (0..self.n_elements).scan((s0, c0), move |(s, c), e| {
            if e > 0 {
                (*s, *c) = (*s * c_step + *c * s_step, *c * c_step - *s * s_step);
            }
            Some((dx_m * *c + dy_m * *s - clearance, *c, *s))
        })
    }

    /// Force, radial load, loaded-element count and derivatives (Eqs. 3–5).
    ///
    /// * `dx_m`, `dy_m`: inner-ring minus outer-ring displacement;
    /// * `delta_v_m`: thermal clearance variation `δv` (effective clearance `δ0 + δv`);
    /// * `cage_angle_rad`: `ω_c t`.
    pub fn force(&self, dx_m: f64, dy_m: f64, delta_v_m: f64, cage_angle_rad: f64) -> BearingForce {
        let k = self.stiffness;
        let mut out = BearingForce::default();
        for (delta, c, s) in self.penetrations(dx_m, dy_m, delta_v_m, cage_angle_rad) {
            if delta <= 0.0 {
                continue;
            }
            out.n_loaded += 1;
            let (p, dp) = self.law.element_load(k, delta);
            out.fx += p * c;
            out.fy += p * s;
            out.fb += p;
            let dir = [c, s, 1.0];
            let ddelta = [c, s, -1.0];
            for (row, d_r) in out.jac.iter_mut().zip(dir) {
                for (entry, d_c) in row.iter_mut().zip(ddelta) {
                    *entry += dp * d_r * d_c;
                }
            }
        }
        out
    }
}
