//! Thermal expansion of bearing components and the clearance variation (paper Eqs. 1–2).
//!
//! With `T_∞` the ambient (assembly) temperature and `Γ` the linear expansion coefficients
//! (Table A.5: 12.03e-6 1/K for bearing steel):
//!
//! ```text
//!   u_b = Γ_b d_e (T_b − T_∞)                                            (1a)
//!   u_i = Γ_i d_i (T_i − T_∞)                                            (1b)
//!   u_o = Γ_o (1 + μ) d_o / (3 (d_o + d_h))
//!         · [(T_o − T_∞)(2 d_o + d_h) + (T_h − T_∞)(2 d_h + d_o)]        (2)
//!   δv  = −(u_b + (u_i − u_o)/2)
//! ```
//!
//! `d_e` is the rolling-element diameter, `d_i`, `d_o` the inner and outer raceway
//! diameters, and `d_h`, `T_h` the diameter and temperature of the part the outer ring is
//! fitted into: the bearing housing (`d_h = 2 r_h`) or, for the inter-shaft bearing 3#, the
//! high-pressure shaft element (`d_HP = 2 r_HP`). Eq. 2 follows the paper's ref. 49
//! for an outer ring constrained by its seat. All four results are linear in the
//! temperatures, so the derivatives returned are exact constants.

use super::{BearingError, check_positive};

/// What the outer ring is fitted into (the `h` of Eq. 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OuterSeat {
    /// A bearing housing (bearings 1#, 2#, 4#).
    Housing,
    /// A rotating shaft (the inter-shaft bearing 3#, seated in the HP shaft).
    Shaft,
}

/// Geometry and material data of Eqs. 1–2 for one bearing.
#[derive(Clone, Debug, PartialEq)]
pub struct ExpansionGeometry {
    /// Rolling-element diameter `d_e` (m).
    pub element_diameter_m: f64,
    /// Inner raceway diameter `d_i` (m).
    pub inner_raceway_m: f64,
    /// Outer raceway diameter `d_o` (m).
    pub outer_raceway_m: f64,
    /// Seat diameter `d_h` (m): `2 r_h` (housing) or `2 r_HP` (HP shaft).
    pub seat_diameter_m: f64,
    /// Expansion coefficient of the rolling elements `Γ_b` (1/K).
    pub expansion_element_per_k: f64,
    /// Expansion coefficient of the inner ring `Γ_i` (1/K).
    pub expansion_inner_per_k: f64,
    /// Expansion coefficient of the outer ring `Γ_o` (1/K).
    pub expansion_outer_per_k: f64,
    /// Poisson's ratio `μ` of the outer ring (Table A.5: 0.3).
    pub poisson: f64,
}

/// Radial expansions, clearance variation and its temperature derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClearanceVariation {
    /// Rolling-element expansion `u_b` (m).
    pub u_b: f64,
    /// Inner-ring expansion `u_i` (m).
    pub u_i: f64,
    /// Outer-ring expansion `u_o` (m).
    pub u_o: f64,
    /// Clearance variation `δv` (m).
    pub delta_v: f64,
    /// `∂δv/∂(T_b, T_i, T_o, T_h)` (m/K).
    pub d_delta_v_d_temp: [f64; 4],
}

impl ExpansionGeometry {
    /// Checks that diameters and coefficients are positive.
    pub fn validate(&self) -> Result<(), BearingError> {
        check_positive("element_diameter_m", self.element_diameter_m)?;
        check_positive("inner_raceway_m", self.inner_raceway_m)?;
        check_positive("outer_raceway_m", self.outer_raceway_m)?;
        check_positive("seat_diameter_m", self.seat_diameter_m)?;
        check_positive("expansion_element_per_k", self.expansion_element_per_k)?;
        check_positive("expansion_inner_per_k", self.expansion_inner_per_k)?;
        check_positive("expansion_outer_per_k", self.expansion_outer_per_k)?;
        Ok(())
    }

    /// Coefficients `(c_o, c_h)` with `u_o = c_o (T_o − T_∞) + c_h (T_h − T_∞)` (Eq. 2).
    pub fn outer_coefficients(&self) -> (f64, f64) {
        let d_o = self.outer_raceway_m;
        let d_h = self.seat_diameter_m;
        let f = self.expansion_outer_per_k * (1.0 + self.poisson) * d_o / (3.0 * (d_o + d_h));
        (f * (2.0 * d_o + d_h), f * (2.0 * d_h + d_o))
    }

    /// Expansions and clearance variation at temperatures `T_b`, `T_i`, `T_o`, `T_h` and
    /// ambient `T_∞` (any consistent unit, °C or K: only differences enter).
    pub fn evaluate(
        &self,
        t_element: f64,
        t_inner: f64,
        t_outer: f64,
        t_seat: f64,
        t_ambient: f64,
    ) -> ClearanceVariation {
        let cb = self.expansion_element_per_k * self.element_diameter_m;
        let ci = self.expansion_inner_per_k * self.inner_raceway_m;
        let (co, ch) = self.outer_coefficients();
        let u_b = cb * (t_element - t_ambient);
        let u_i = ci * (t_inner - t_ambient);
        let u_o = co * (t_outer - t_ambient) + ch * (t_seat - t_ambient);
        ClearanceVariation {
            u_b,
            u_i,
            u_o,
            delta_v: -(u_b + 0.5 * (u_i - u_o)),
            d_delta_v_d_temp: [-cb, -0.5 * ci, 0.5 * co, 0.5 * ch],
        }
    }
}
