//! Bearing friction heat (paper Eqs. 9–13) and lubricant viscosity (Eq. 12).
//!
//! Palmgren's friction torque (Harris, *Rolling Bearing Analysis*, the paper's ref. 50):
//!
//! ```text
//!   M   = M_l + M_v                                                     (9)
//!   M_l = f_l F_b D_m                                                   (10)
//!   M_v = 1e-7 f_v (ν n)^(2/3) D_m³          if ν n ≥ 2000              (11)
//!       = 160e-7 f_v D_m³                    if ν n < 2000
//!   Q_gl = 1e-3 |ω_i − ω_o| M_l,  Q_gv = 1e-3 |ω_i − ω_o| M_v           (13)
//! ```
//!
//! in the classic units of the correlation: torque in N·mm, `F_b` in N, `D_m` in mm, `ν` in
//! mm²/s (cSt), `n = 60 |ω_i − ω_o| / (2π)` in rpm. Then `1e-3 · ω · M` turns N·mm · rad/s
//! into W. The inter-shaft bearing uses the relative ring speed. The two branches of Eq. 11
//! meet almost continuously (`2000^(2/3) = 158.7` against the constant 160), as in the
//! original correlation; the low branch has zero viscosity derivative.
//!
//! Viscosity–temperature law (Eq. 12, the paper's ref. 51): `ν = ν0 exp(−β (T_L − T_L0))`
//! with `β = 0.02339 1/K` (Table A.6). The paper does not give `ν0`; the default is
//! `ν0 = 39 mm²/s` at `T_L0 = 25 °C`, i.e. an aviation turbine oil of about 27.6 mm²/s at
//! 40 °C with the paper's `β` (e.g. MIL-PRF-23699 class oils: ≈ 25–28 mm²/s at 40 °C).
//!
//! Palmgren coefficient ranges (Harris, Table "f_v" and "f_l"): `f_v ≈ 2–4` for ball,
//! `≈ 2.2–4` for cylindrical roller bearings (oil-jet/oil-bath); `f_l ≈ 0.0005–0.0009` for
//! deep-groove ball and `≈ 0.0002–0.0004` for cylindrical roller bearings.

/// Palmgren data of one bearing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Palmgren {
    /// Load coefficient `f_l` (–).
    pub f_l: f64,
    /// Viscous coefficient `f_v` (–).
    pub f_v: f64,
    /// Pitch diameter `D_m` (m; converted to mm inside).
    pub pitch_diameter_m: f64,
}

/// Friction torques and heats of one bearing at one instant, with derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrictionHeat {
    /// Load torque `M_l` (N·mm).
    pub torque_load_nmm: f64,
    /// Viscous torque `M_v` (N·mm).
    pub torque_visc_nmm: f64,
    /// Load heat `Q_gl` (W).
    pub q_load_w: f64,
    /// Viscous heat `Q_gv` (W).
    pub q_visc_w: f64,
    /// `∂Q_gl/∂F_b` (W/N).
    pub dq_load_d_fb: f64,
    /// `∂Q_gv/∂ν` (W per mm²/s).
    pub dq_visc_d_nu: f64,
}

impl FrictionHeat {
    /// Total heat `Q_g = Q_gl + Q_gv` (W).
    pub fn total_w(&self) -> f64 {
        self.q_load_w + self.q_visc_w
    }
}

/// Speed in rpm from rad/s.
pub fn rpm_from_rad_s(speed_rad_s: f64) -> f64 {
    speed_rad_s * 60.0 / (2.0 * std::f64::consts::PI)
}

impl Palmgren {
    /// Torques and heats for radial load `F_b` (N), viscosity `ν` (mm²/s) and relative ring
    /// speed `ω_i − ω_o` (rad/s).
    pub fn heat(&self, fb_n: f64, nu_mm2_s: f64, rel_speed_rad_s: f64) -> FrictionHeat {
        let dm_mm = self.pitch_diameter_m * 1e3;
        let w = rel_speed_rad_s.abs();
        let n_rpm = rpm_from_rad_s(w);
        let torque_load = self.f_l * fb_n * dm_mm;
        let dm3 = dm_mm * dm_mm * dm_mm;
        let nun = nu_mm2_s * n_rpm;
        let (torque_visc, dtv_dnu) = if nun >= 2000.0 {
            let t = 1e-7 * self.f_v * nun.powf(2.0 / 3.0) * dm3;
            (t, 2.0 / 3.0 * t / nu_mm2_s)
        } else {
            (160e-7 * self.f_v * dm3, 0.0)
        };
        FrictionHeat {
            torque_load_nmm: torque_load,
            torque_visc_nmm: torque_visc,
            q_load_w: 1e-3 * w * torque_load,
            q_visc_w: 1e-3 * w * torque_visc,
            dq_load_d_fb: 1e-3 * w * self.f_l * dm_mm,
            dq_visc_d_nu: 1e-3 * w * dtv_dnu,
        }
    }
}

/// Exponential viscosity–temperature law (Eq. 12).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viscosity {
    /// `ν0` (mm²/s) at the reference temperature.
    pub nu0_mm2_s: f64,
    /// Reference temperature `T_L0` (°C).
    pub ref_temp_c: f64,
    /// Viscosity–temperature coefficient `β` (1/K).
    pub beta_per_k: f64,
}

impl Viscosity {
    /// `(ν, dν/dT)` in mm²/s and mm²/(s·K) at lubricant temperature `temp_c`.
    pub fn eval(&self, temp_c: f64) -> (f64, f64) {
        let nu = self.nu0_mm2_s * (-self.beta_per_k * (temp_c - self.ref_temp_c)).exp();
        (nu, -self.beta_per_k * nu)
    }
}

/// Heat carried away by the lubricant flow (Eq. 14), returned as the positive heat removed
/// `ρ_l c_l q_l (T_L − T_L∞)` (W) — the paper's `Q_d` is its negative. The flow rate is
/// given in L/min (converted: 1 L/min = 1/60000 m³/s).
pub fn lubricant_heat_removal_w(
    density_kg_m3: f64,
    specific_heat_j_kg_k: f64,
    flow_l_min: f64,
    temp_c: f64,
    cooling_temp_c: f64,
) -> f64 {
    lubricant_conductance_w_k(density_kg_m3, specific_heat_j_kg_k, flow_l_min)
        * (temp_c - cooling_temp_c)
}

/// The "flow conductance" `ρ_l c_l q_l` (W/K) of Eq. 14, `q_l` in L/min.
pub fn lubricant_conductance_w_k(
    density_kg_m3: f64,
    specific_heat_j_kg_k: f64,
    flow_l_min: f64,
) -> f64 {
    density_kg_m3 * specific_heat_j_kg_k * flow_l_min / 60_000.0
}
