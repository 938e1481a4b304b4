//! Conduction and convection resistances with the Nusselt correlations of Table 1.
//!
//! Conduction (Table 1):
//! * cylindrical wall `R = ln(r_out/r_in)/(2π k L)` ([`cylinder_conduction`]);
//! * flat wall `R = L/(k S)` ([`flat_conduction`]).
//!
//! Convection `R = 1/(h A)` with `h = k_f Nu / L_c`. The correlations, as we read Table 1
//! (its rings/shafts cells are merged in the printed text; the reading below is the one
//! whose branches join continuously):
//!
//! | surfaces | correlation | length `L_c`, velocity |
//! |---|---|---|
//! | lubricant–balls (ref. 50, Harris) | `Nu = 0.33 Re^0.5 Pr^0.4` | ball diameter, cage pitch speed `ω_c D_m/2` |
//! | lubricant–rollers (ref. 53, cross-flow cylinder) | `Nu = (0.35 + 0.34 Re^0.5 + 0.15 Re^0.58) Pr^0.3` | roller diameter, `ω_c D_m/2` |
//! | lubricant–rings (ref. 54, rotating annulus) | `Nu = 2` (`Ta < 41`), `0.167 Ta^0.69 Pr^0.4` (`41 ≤ Ta < 100`), `0.401 Ta^0.5 Pr^0.4` (`Ta ≥ 100`) | hydraulic diameter `2δ` |
//! | shafts/disks–ambient air (ref. 55) | `Nu = 0.00308 Re + 4.432` (`Re < 7300`), `Re^0.37` (`7300 ≤ Re < 9600`), `30.5 Re^−0.0042` (`Re ≥ 9600`) | diameter, surface speed `ω D/2` |
//! | lubricant–housing (ref. 50, laminar plate) | `h = 0.332 k_f Pr^(1/3) (u_s/(ν x))^(1/2)` | `x` = housing diameter, `u_s` below |
//! | housing–ambient (ref. 18) | `h = 15 W/(m²·K)` | – |
//!
//! * Rings: `Ta = (|ω_i − ω_o| r_i δ/ν) √(δ/r_i)` with `r_i` the inner raceway radius and
//!   `δ` the radial raceway gap (the annulus the lubricant fills); the `Ta < 41` branch is
//!   missing in print and is the laminar Couette conduction limit `Nu = 2`; the two printed
//!   branches meet at `Ta = 100` (4.00 vs 4.01), which fixes their pairing.
//! * Housing: Table 1 writes `u_s = ω_c/3`, which is not a velocity; we read it as one third
//!   of the cage pitch speed, `u_s = ω_c D_m/6` (the lubricant dragged along by the cage).
//! * `Re = u L_c/ν`, `Pr = ν/α` with the lubricant's `α` (Table A.6: 7.38e-8 m²/s) or air's.
//!
//! Each lubricant correlation returns `h` and `∂h/∂ν` (ν in m²/s), so that lubricant
//! resistances can follow the viscosity `ν(T_L)` (Eq. 12) with exact derivatives.

use std::f64::consts::PI;

/// Radial conduction through a cylindrical wall `r_in..r_out` of length `L` (K/W).
pub fn cylinder_conduction(r_in_m: f64, r_out_m: f64, k: f64, length_m: f64) -> f64 {
    (r_out_m / r_in_m).ln() / (2.0 * PI * k * length_m)
}

/// Conduction through a flat wall of thickness `L` and area `S` (K/W).
pub fn flat_conduction(length_m: f64, k: f64, area_m2: f64) -> f64 {
    length_m / (k * area_m2)
}

/// A heat-transfer coefficient (W/(m²·K)) and its derivative with respect to the fluid's
/// kinematic viscosity (W/(m²·K) per m²/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coefficient {
    pub h: f64,
    pub dh_dnu: f64,
}

/// Fluid properties entering the correlations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fluid {
    /// Thermal conductivity `k_f` (W/(m·K)).
    pub conductivity: f64,
    /// Thermal diffusivity `α` (m²/s).
    pub diffusivity: f64,
}

/// Lubricant–element coefficient of a bearing whose elements follow `law`:
/// [`ball_lubricant`] or [`roller_lubricant`].
pub fn element_lubricant(
    law: crate::bearing::ContactLaw,
    fluid: &Fluid,
    speed_m_s: f64,
    diameter_m: f64,
    nu_m2_s: f64,
) -> Coefficient {
    match law {
        crate::bearing::ContactLaw::Ball => ball_lubricant(fluid, speed_m_s, diameter_m, nu_m2_s),
        crate::bearing::ContactLaw::Roller => {
            roller_lubricant(fluid, speed_m_s, diameter_m, nu_m2_s)
        }
    }
}

/// Lubricant–ball coefficient: `Nu = 0.33 Re^0.5 Pr^0.4` (so `h ∝ ν^−0.1`).
pub fn ball_lubricant(fluid: &Fluid, speed_m_s: f64, diameter_m: f64, nu_m2_s: f64) -> Coefficient {
    if speed_m_s <= 0.0 {
        return Coefficient::default();
    }
    let re = speed_m_s * diameter_m / nu_m2_s;
    let pr = nu_m2_s / fluid.diffusivity;
    let h = 0.33 * re.sqrt() * pr.powf(0.4) * fluid.conductivity / diameter_m;
    Coefficient {
        h,
        dh_dnu: -0.1 * h / nu_m2_s,
    }
}

/// Lubricant–roller coefficient: `Nu = (0.35 + 0.34 Re^0.5 + 0.15 Re^0.58) Pr^0.3`.
pub fn roller_lubricant(
    fluid: &Fluid,
    speed_m_s: f64,
    diameter_m: f64,
    nu_m2_s: f64,
) -> Coefficient {
    let re = (speed_m_s * diameter_m / nu_m2_s).max(0.0);
    let pr = nu_m2_s / fluid.diffusivity;
    let prf = pr.powf(0.3);
    let poly = 0.35 + 0.34 * re.sqrt() + 0.15 * re.powf(0.58);
    // dRe/dν = −Re/ν.
    let dpoly_dnu = -(0.5 * 0.34 * re.sqrt() + 0.58 * 0.15 * re.powf(0.58)) / nu_m2_s;
    let c = fluid.conductivity / diameter_m;
    Coefficient {
        h: c * poly * prf,
        dh_dnu: c * (dpoly_dnu * prf + poly * 0.3 * prf / nu_m2_s),
    }
}

/// Lubricant–ring coefficient in the rotating annulus (Taylor-number correlation).
pub fn ring_lubricant(
    fluid: &Fluid,
    rel_speed_rad_s: f64,
    inner_radius_m: f64,
    gap_m: f64,
    nu_m2_s: f64,
) -> Coefficient {
    let lc = 2.0 * gap_m;
    let c = fluid.conductivity / lc;
    let ta =
        rel_speed_rad_s.abs() * inner_radius_m * gap_m / nu_m2_s * (gap_m / inner_radius_m).sqrt();
    let pr = nu_m2_s / fluid.diffusivity;
    let prf = pr.powf(0.4);
    // Ta ∝ 1/ν, Pr ∝ ν.
    if ta < 41.0 {
        Coefficient {
            h: 2.0 * c,
            dh_dnu: 0.0,
        }
    } else if ta < 100.0 {
        let h = c * 0.167 * ta.powf(0.69) * prf;
        Coefficient {
            h,
            dh_dnu: (0.4 - 0.69) * h / nu_m2_s,
        }
    } else {
        let h = c * 0.401 * ta.sqrt() * prf;
        Coefficient {
            h,
            dh_dnu: (0.4 - 0.5) * h / nu_m2_s,
        }
    }
}

/// Lubricant–housing coefficient `h = 0.332 k_f Pr^(1/3) (u_s/(ν x))^(1/2)` (`∝ ν^−1/6`).
pub fn housing_lubricant(
    fluid: &Fluid,
    speed_m_s: f64,
    length_m: f64,
    nu_m2_s: f64,
) -> Coefficient {
    if speed_m_s <= 0.0 {
        return Coefficient::default();
    }
    let pr = nu_m2_s / fluid.diffusivity;
    let h = 0.332 * fluid.conductivity * pr.cbrt() * (speed_m_s / (nu_m2_s * length_m)).sqrt();
    Coefficient {
        h,
        dh_dnu: (1.0 / 3.0 - 0.5) * h / nu_m2_s,
    }
}

/// Shaft (or disk) to ambient-air Nusselt number of Table 1 at Reynolds number `re`.
pub fn shaft_ambient_nusselt(re: f64) -> f64 {
    if re < 7300.0 {
        0.00308 * re + 4.432
    } else if re < 9600.0 {
        re.powf(0.37)
    } else {
        30.5 * re.powf(-0.0042)
    }
}

/// Shaft (or disk) to ambient coefficient (W/(m²·K)) for a body of diameter `D` turning at
/// `ω`: `Re = (ω D/2) D/ν_air`, `h = Nu k_air/D`.
pub fn shaft_ambient(speed_rad_s: f64, diameter_m: f64, air_nu_m2_s: f64, air_k: f64) -> f64 {
    let re = speed_rad_s.abs() * 0.5 * diameter_m * diameter_m / air_nu_m2_s;
    shaft_ambient_nusselt(re) * air_k / diameter_m
}
