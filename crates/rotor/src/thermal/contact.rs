//! Hertz-contact thermal resistances of rolling elements (paper Eqs. 15–17).
//!
//! **Ball (Eq. 15).** Each ball–ring contact is an ellipse with semi-major axis `a` and
//! semi-minor axis `b`; the constriction resistance of an isothermal ellipse on a half
//! space (Yovanovich; the paper's ref. 52) is `Ψ/(4 k a)` per body with
//! `Ψ = (2/π) K(e)`, `e² = 1 − (b/a)²`, `K` the complete elliptic integral of the first kind:
//!
//! ```text
//!   R_one = Ψ/(4 k_ball a) + Ψ/(4 k_ring a)
//! ```
//!
//! `K` is computed by the arithmetic–geometric mean, `K(m) = π / (2 AGM(1, √(1−m)))`
//! (Abramowitz & Stegun 17.6), so `Ψ = 1/AGM(1, b/a)`.
//!
//! The semi-axes come from the Hamrock–Brewe approximations (B. J. Hamrock, D. Brewe,
//! "Simplified solution for stresses and deformations", J. Lubr. Technol. 105 (1983)
//! 171–177; also Hamrock, Schmid, Jacobson, *Fundamentals of Machine Elements*):
//!
//! ```text
//!   1/R_x = 2/d ± 2/d_race          (+ inner raceway, − outer raceway; rolling direction)
//!   1/R_y = 2/d − 1/r_groove        (r_groove = f·d, groove conformity f)
//!   1/R = 1/R_x + 1/R_y,  α_r = R_y/R_x,  k̄ = α_r^(2/π),  Ē = 1 + (π/2 − 1)/α_r
//!   a = (6 k̄² Ē W R/(π E'))^(1/3),  b = (6 Ē W R/(π k̄ E'))^(1/3),  E' = E/(1 − μ²)
//! ```
//!
//! with `W` the load of one contact. The paper gives no groove radii; the default
//! conformity `f = 0.52` is the usual deep-groove value (Harris: 0.515–0.53).
//!
//! **Roller (Eq. 16).** Each roller–ring contact is a rectangle of length `l` (the roller
//! length `a_roller`) and width `2b`, with `b = √(8 W R/(π l E'))` from line-contact Hertz
//! theory (`1/R = 2/d ± 2/d_race`). As printed, Eq. 16 (`2 a_roller f_rec(ε)/(π k)`) has
//! units of m²·K/W, not K/W; we use the dimensionally consistent isoflux mean-temperature
//! constriction resistance of a `l × 2b` rectangle on a half space,
//!
//! ```text
//!   R = f_rec(ε)/(2π k b),   ε = l/(2b),
//!   f_rec(ε) = asinh(1/ε) + asinh(ε)/ε + (ε/3)[1 + 1/ε³ − (1 + 1/ε²)^(3/2)]
//! ```
//!
//! which keeps the paper's `f_rec` and `ε` and is checked in the tests against a direct
//! numerical integration of the mean surface temperature under uniform flux.
//!
//! **Parallel elements (Eq. 17).** `R_bi = R_bi^one / n_b`, `R_bo = R_bo^one / n_b` with
//! `n_b` the number of loaded elements; the load per contact is `W = F_b / n_b`. We work
//! with the conductance `G = n_b / R^one(F_b/n_b)` and its derivatives with respect to
//! `F_b` and `n_b` (treated as a real number). To keep `G` finite and differentiable when a
//! bearing unloads, `n_b` is clamped below at 1 and `F_b` at a small floor load (settable;
//! derivatives are zero in the clamped ranges).

use std::f64::consts::PI;

use crate::bearing::ContactLaw;

/// Arithmetic–geometric mean of two positive numbers.
pub fn agm(mut a: f64, mut b: f64) -> f64 {
    for _ in 0..64 {
        let an = 0.5 * (a + b);
        let bn = (a * b).sqrt();
        a = an;
        b = bn;
        if (a - b).abs() <= 1e-15 * a {
            break;
        }
    }
    0.5 * (a + b)
}

/// Complete elliptic integral of the first kind `K(m)`, parameter `m = e²` in `[0, 1)`.
pub fn elliptic_k(m: f64) -> f64 {
    PI / (2.0 * agm(1.0, (1.0 - m).sqrt()))
}

/// The function `f_rec(ε)` of Eq. 16 and its derivative.
pub fn f_rec(eps: f64) -> (f64, f64) {
    let ie = 1.0 / eps;
    let s = (1.0 + ie * ie).sqrt();
    let f = ie.asinh() + eps.asinh() * ie + eps / 3.0 * (1.0 + ie * ie * ie - s * s * s);
    // The derivatives of the first two terms partly cancel (see module docs).
    let d =
        -eps.asinh() * ie * ie + (1.0 - 2.0 * ie * ie * ie - s * s * s + 3.0 * ie * ie * s) / 3.0;
    (f, d)
}

/// Which raceway a contact is on (sign of the raceway curvature).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Raceway {
    /// Convex inner raceway.
    Inner,
    /// Concave outer raceway.
    Outer,
}

/// Elastic and thermal data of one element–raceway contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactGeometry {
    /// Rolling-element diameter `d` (m).
    pub element_diameter_m: f64,
    /// Raceway diameter at the contact (m).
    pub raceway_diameter_m: f64,
    /// Inner or outer raceway.
    pub raceway: Raceway,
    /// Groove conformity `f = r_groove/d` (balls only; ignored for rollers).
    pub conformity: f64,
    /// Roller length `l` (m; rollers only).
    pub roller_length_m: f64,
    /// Effective modulus `E' = E/(1 − μ²)` (Pa), same material for element and ring.
    pub modulus_pa: f64,
    /// Conductivity of the rolling element (W/(m·K)).
    pub k_element: f64,
    /// Conductivity of the ring (W/(m·K)).
    pub k_ring: f64,
}

/// Semi-axes of a Hertz point contact (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EllipseAxes {
    /// Semi-major axis `a` (transverse to rolling).
    pub a: f64,
    /// Semi-minor axis `b` (rolling direction).
    pub b: f64,
}

impl ContactGeometry {
    fn rx_inverse(&self) -> f64 {
        let d = self.element_diameter_m;
        match self.raceway {
            Raceway::Inner => 2.0 / d + 2.0 / self.raceway_diameter_m,
            Raceway::Outer => 2.0 / d - 2.0 / self.raceway_diameter_m,
        }
    }

    /// Hamrock–Brewe semi-axes of a ball contact under load `w_n` (N).
    pub fn ball_axes(&self, w_n: f64) -> EllipseAxes {
        let d = self.element_diameter_m;
        let inv_rx = self.rx_inverse();
        let inv_ry = 2.0 / d - 1.0 / (self.conformity * d);
        let r = 1.0 / (inv_rx + inv_ry);
        let alpha = inv_rx / inv_ry;
        let kbar = alpha.powf(2.0 / PI);
        let ebar = 1.0 + (PI / 2.0 - 1.0) / alpha;
        let base = 6.0 * ebar * w_n * r / (PI * self.modulus_pa);
        EllipseAxes {
            a: (base * kbar * kbar).cbrt(),
            b: (base / kbar).cbrt(),
        }
    }

    /// Semi-width `b` (m) of a roller line contact under load `w_n` (N).
    pub fn roller_half_width(&self, w_n: f64) -> f64 {
        let r = 1.0 / self.rx_inverse();
        (8.0 * w_n * r / (PI * self.roller_length_m * self.modulus_pa)).sqrt()
    }

    /// Resistance of one ball contact (Eq. 15) and `dR/dW`, for load `w_n` (N).
    pub fn ball_resistance(&self, w_n: f64) -> (f64, f64) {
        let ax = self.ball_axes(w_n);
        let psi = 1.0 / agm(1.0, ax.b / ax.a);
        let r = psi / (4.0 * ax.a) * (1.0 / self.k_element + 1.0 / self.k_ring);
        // a ∝ W^(1/3) at fixed ellipticity: R ∝ W^(−1/3).
        (r, -r / (3.0 * w_n))
    }

    /// Resistance of one roller contact (Eq. 16, read as in the module docs) and `dR/dW`.
    pub fn roller_resistance(&self, w_n: f64) -> (f64, f64) {
        let b = self.roller_half_width(w_n);
        let eps = self.roller_length_m / (2.0 * b);
        let (f, df) = f_rec(eps);
        let c = (1.0 / self.k_element + 1.0 / self.k_ring) / (2.0 * PI);
        let r = c * f / b;
        // dR/db = c (−ε f'(ε) − f)/b², db/dW = b/(2W).
        let dr_db = c * (-eps * df - f) / (b * b);
        (r, dr_db * b / (2.0 * w_n))
    }

    /// Resistance of one contact of a bearing whose elements follow `law`.
    pub fn resistance(&self, law: ContactLaw, w_n: f64) -> (f64, f64) {
        match law {
            ContactLaw::Ball => self.ball_resistance(w_n),
            ContactLaw::Roller => self.roller_resistance(w_n),
        }
    }
}

/// One contact's resistance law `W ↦ (R, dR/dW)`, with what does not depend on the load
/// worked out once.
///
/// A ball contact's ellipticity is fixed by the geometry, so both semi-axes scale as
/// `W^{1/3}` and `R(W) = R(1 N) · W^{−1/3}` exactly: one cube root per evaluation instead
/// of the Hamrock–Brewe power, two cube roots and the elliptic integral's AGM iteration
/// ([`ContactGeometry::ball_resistance`] at 1 N, evaluated at construction). A roller's
/// `f_rec(ε)` depends on the load through `ε = l/(2b)`; it is evaluated in full.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactResistance {
    geom: ContactGeometry,
    law: ContactLaw,
    /// `R` of a ball contact at 1 N.
    ball_unit: f64,
}

impl ContactResistance {
    /// The resistance law of a contact of `geom` in a bearing whose elements follow `law`.
    pub fn new(geom: ContactGeometry, law: ContactLaw) -> Self {
        let ball_unit = match law {
            ContactLaw::Ball => geom.ball_resistance(1.0).0,
            ContactLaw::Roller => 0.0,
        };
        Self {
            geom,
            law,
            ball_unit,
        }
    }

    /// `(R, dR/dW)` of one contact under load `w_n` (N), as
    /// [`ContactGeometry::resistance`].
    pub fn eval(&self, w_n: f64) -> (f64, f64) {
        match self.law {
            ContactLaw::Ball => {
                let r = self.ball_unit / w_n.cbrt();
                (r, -r / (3.0 * w_n))
            }
            ContactLaw::Roller => self.geom.roller_resistance(w_n),
        }
    }
}

/// Conductance of `n_b` loaded elements in parallel (Eq. 17) sharing load `F_b`, with
/// `(G, ∂G/∂F_b, ∂G/∂n_b)`. `n_b` is clamped below at 1 and `F_b` at `min_load_n`.
pub fn parallel_conductance(
    geom: &ContactGeometry,
    law: ContactLaw,
    fb_n: f64,
    n_loaded: f64,
    min_load_n: f64,
) -> (f64, f64, f64) {
    parallel_conductance_of(|w| geom.resistance(law, w), fb_n, n_loaded, min_load_n)
}

/// [`parallel_conductance`] for any one-contact resistance law `W ↦ (R, dR/dW)`.
pub fn parallel_conductance_of(
    resistance: impl Fn(f64) -> (f64, f64),
    fb_n: f64,
    n_loaded: f64,
    min_load_n: f64,
) -> (f64, f64, f64) {
    let (n, dn_on) = if n_loaded >= 1.0 {
        (n_loaded, true)
    } else {
        (1.0, false)
    };
    let (f, df_on) = if fb_n >= min_load_n {
        (fb_n, true)
    } else {
        (min_load_n, false)
    };
    let w = f / n;
    let (r, dr_dw) = resistance(w);
    let g = n / r;
    // G = n/R(F/n): ∂G/∂F = −R'/R², ∂G/∂n = 1/R + R' W/R².
    let dg_df = if df_on { -dr_dw / (r * r) } else { 0.0 };
    let dg_dn = if dn_on {
        1.0 / r + dr_dw * w / (r * r)
    } else {
        0.0
    };
    (g, dg_df, dg_dn)
}
