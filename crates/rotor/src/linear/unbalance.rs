//! The unbalance response of the linearised rotor (Bode and polar data).
//!
//! Each rotor's disk unbalances drive it at the rotor's own speed `Ω_r = s_r ω`:
//! `F_x = m e Ω_r² cos(Ω_r t + φ)`, `F_y = m e Ω_r² sin(Ω_r t + φ)` (the nonlinear engine's
//! forcing, [`crate::model::Assembly::add_unbalance_force`]). With complex amplitudes
//! `x(t) = Re(X e^{iΩ_r t})` that is `F_x = m e Ω_r² e^{iφ}`, `F_y = −i F_x`, and the
//! steady response of the linearised rotor (bearings replaced by their linearised stiffness,
//! as in [`super::modes`]) solves
//!
//! ```text
//!   (K(ω) + K_b − Ω_r² M + i Ω_r (C(ω) + Σ_q s_q ω G_q)) X = F
//! ```
//!
//! once per rotor and speed (a dense complex LU). Rotors that spin at different speeds give
//! responses at different frequencies, reported separately; the motion is their sum.

use faer::Mat;
use faer::linalg::solvers::Solve;
use num_complex::Complex;

use super::LinearError;
use crate::model::Assembly;
use crate::model::validate::Dir;

/// The response to one rotor's unbalance at one reference speed.
#[derive(Clone, Debug)]
pub struct UnbalanceResponse {
    /// Reference speed ω (rad/s).
    pub speed_rad_s: f64,
    /// The exciting rotor's id.
    pub rotor_id: String,
    /// The excitation's frequency `|s_r| ω` (rad/s).
    pub frequency_rad_s: f64,
    /// Complex amplitudes of every DoF (node-major `[x, y, θx, θy]`; m and rad).
    pub amplitudes: Vec<Complex<f64>>,
}

/// The orbit of a node at one excitation: amplitudes and phases of x and y, and the
/// ellipse's semi-axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeOrbit {
    pub x: Complex<f64>,
    pub y: Complex<f64>,
}

impl NodeOrbit {
    /// Semi-major axis of the ellipse `(Re(X e^{iθ}), Re(Y e^{iθ}))` (m).
    pub fn major_axis(&self) -> f64 {
        let (f, b) = self.whirl_parts();
        f + b
    }

    /// Semi-minor axis (m).
    pub fn minor_axis(&self) -> f64 {
        let (f, b) = self.whirl_parts();
        (f - b).abs()
    }

    /// Forward and backward circle radii: `X = f e^{iα} + b e^{iβ}`, `Y = −i f e^{iα} + i b e^{iβ}`.
    fn whirl_parts(&self) -> (f64, f64) {
        let i = Complex::new(0.0, 1.0);
        let fwd = 0.5 * (self.x + i * self.y);
        let bwd = 0.5 * (self.x - i * self.y);
        (fwd.norm(), bwd.norm())
    }

    /// `true` when the node orbits in the sense of rotation (+x towards +y).
    pub fn forward(&self) -> bool {
        let (f, b) = self.whirl_parts();
        f >= b
    }
}

impl UnbalanceResponse {
    /// The orbit of the node at position `node_index` (DoF order).
    pub fn node(&self, node_index: usize) -> NodeOrbit {
        NodeOrbit {
            x: self.amplitudes[crate::model::validate::dof(node_index, Dir::X)],
            y: self.amplitudes[crate::model::validate::dof(node_index, Dir::Y)],
        }
    }
}

/// The unbalance responses of every rotor with an unbalance at each reference speed of
/// `speeds` (rad/s). Errors on a rotor without unbalance anywhere (nothing to compute) or
/// a singular dynamic stiffness (an undamped resonance hit exactly).
pub fn unbalance_response(
    asm: &Assembly,
    speeds: &[f64],
) -> Result<Vec<UnbalanceResponse>, LinearError> {
    if asm.unbalances.is_empty() {
        return Err(LinearError::NoUnbalance);
    }
    let n = asm.n_dof;
    let mut out = Vec::new();
    for &w in speeds {
        if !w.is_finite() || w < 0.0 {
            return Err(LinearError::BadSpeeds(format!(
                "speed {w} rad/s: need finite and ≥ 0"
            )));
        }
        let lp = asm.linear_part_with_bearings(w);
        for g in &asm.gyro {
            let ours: Vec<_> = asm
                .unbalances
                .iter()
                .filter(|u| u.rotor_id == g.rotor_id)
                .collect();
            if ours.is_empty() || g.speed_ratio.value() == 0.0 {
                continue;
            }
            let om = g.speed_ratio.value() * w;
            let a = Mat::<Complex<f64>>::from_fn(n, n, |i, j| {
                Complex::new(
                    lp.stiffness.get(i, j) - om * om * lp.mass.get(i, j),
                    om * lp.damping.get(i, j),
                )
            });
            let mut f = Mat::<Complex<f64>>::zeros(n, 1);
            for u in &ours {
                let fx = Complex::from_polar(u.mass_eccentricity_kg_m * om * om, u.phase_rad);
                f[(u.dof_x, 0)] += fx;
                f[(u.dof_y, 0)] += Complex::new(0.0, -1.0) * fx;
            }
            let x = a.partial_piv_lu().solve(&f);
            // x(t) = Re(X e^{iΩt}); for a counter-rotating rotor (Ω < 0) reported as
            // Re(conj(X) e^{i|Ω|t}), at the positive frequency |Ω|
            let amplitudes: Vec<Complex<f64>> = (0..n)
                .map(|i| {
                    if om < 0.0 {
                        x[(i, 0)].conj()
                    } else {
                        x[(i, 0)]
                    }
                })
                .collect();
            if amplitudes
                .iter()
                .any(|v| !(v.re.is_finite() && v.im.is_finite()))
            {
                return Err(LinearError::Eigen(format!(
                    "unbalance response of rotor {} at {w} rad/s: singular dynamic stiffness",
                    g.rotor_id
                )));
            }
            out.push(UnbalanceResponse {
                speed_rad_s: w,
                rotor_id: g.rotor_id.clone(),
                frequency_rad_s: om.abs(),
                amplitudes,
            });
        }
    }
    Ok(out)
}
