//! Linearised rolling-bearing stiffness for modal analysis.
//!
//! The nonlinear bearing force of paper Eq. 4 with ring displacement `u = r (cos α, sin α)`
//! (inner minus outer ring) is
//!
//! ```text
//!   f(u, t) = k_b Σ_k (r cos(θ_k − α) − δ0)^n H(·) (cos θ_k, sin θ_k),   θ_k = 2π(k−1)/N + ω_c t.
//! ```
//!
//! It pulses with the cage angle. For a linear (modal) model it is averaged over one
//! element pitch of cage rotation (64 midpoint samples); the average is axisymmetric, so it
//! is `F(r) ê` with `ê = u/r` and the scalar law
//!
//! ```text
//!   F(r) = k_b ⟨ Σ_k (r cos θ_k − δ0)^n H(·) cos θ_k ⟩_cage .
//! ```
//!
//! Its Jacobian at `u` is exact for the averaged law:
//! `K = F'(r) ê êᵀ + (F(r)/r) (I − ê êᵀ)` — the tangent stiffness along the load and the
//! secant stiffness across it. The operating point is the radial load the bearing carries
//! (given in the model file, or the static gravity equilibrium computed by
//! the model's assembly).

use std::f64::consts::PI;

use super::ContactLaw;

/// Cage positions sampled per element pitch when averaging Eq. 4.
pub const CAGE_SAMPLES: usize = 64;

/// The cage-averaged radial Hertz law of one bearing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HertzLaw {
    /// `k_b` (N/m^n).
    pub stiffness: f64,
    /// Element law (exponent `n`: 3/2 ball, 10/9 roller).
    pub law: ContactLaw,
    /// Number of rolling elements `N`.
    pub count: u32,
    /// Initial radial clearance `δ0` (m).
    pub clearance_m: f64,
}

impl HertzLaw {
    /// Averaged radial force `F(r)` (N) and its derivative `F'(r)` (N/m) at ring
    /// displacement `r ≥ 0` (m).
    pub fn force_and_slope(&self, r: f64) -> (f64, f64) {
        let n = self.count as usize;
        let pitch = 2.0 * PI / self.count as f64;
        let (mut f, mut df) = (0.0, 0.0);
        for s in 0..CAGE_SAMPLES {
            let phase = (s as f64 + 0.5) / CAGE_SAMPLES as f64 * pitch;
            for k in 0..n {
                let c = (phase + k as f64 * pitch).cos();
                let (p, dp) = self.law.element_load(1.0, r * c - self.clearance_m);
                f += p * c;
                df += dp * c * c;
            }
        }
        let scale = self.stiffness / CAGE_SAMPLES as f64;
        (f * scale, df * scale)
    }

    /// Ring displacement `r` (m) at which the averaged force equals `load_n` (N): the law
    /// is monotone for `r > δ0`, so a bracket is grown and then shrunk by Newton steps,
    /// falling back to bisection whenever a step leaves the bracket.
    pub fn displacement_for_load(&self, load_n: f64) -> f64 {
        if load_n <= 0.0 {
            return self.clearance_m;
        }
        let mut lo = self.clearance_m;
        let mut hi = self.clearance_m.max(1e-9) * 2.0;
        let mut guard = 0;
        while self.force_and_slope(hi).0 < load_n && guard < 200 {
            lo = hi;
            hi *= 2.0;
            guard += 1;
        }
        let mut r = 0.5 * (lo + hi);
        for _ in 0..200 {
            let (f, df) = self.force_and_slope(r);
            if f < load_n {
                lo = r;
            } else {
                hi = r;
            }
            let newton = if df > 0.0 {
                r - (f - load_n) / df
            } else {
                f64::NAN
            };
            let next = if newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if (next - r).abs() <= 1e-14 * r || hi - lo <= 1e-15 * hi {
                return next;
            }
            r = next;
        }
        r
    }

    /// Secant stiffness `F(r)/r` at load `load_n`.
    pub fn secant_stiffness(&self, load_n: f64) -> f64 {
        let r = self.displacement_for_load(load_n);
        if r > 0.0 { load_n / r } else { 0.0 }
    }

    /// 2×2 stiffness `[[kxx, kxy], [kyx, kyy]]` of the averaged law at load vector
    /// `load_n` = (Fx, Fy) (N), see the module docs.
    pub fn tangent_matrix(&self, load_n: [f64; 2]) -> [[f64; 2]; 2] {
        let mag = load_n[0].hypot(load_n[1]);
        let (ex, ey) = if mag > 0.0 {
            (load_n[0] / mag, load_n[1] / mag)
        } else {
            (1.0, 0.0)
        };
        let r = self.displacement_for_load(mag);
        let (f, kr) = self.force_and_slope(r);
        let kt = if r > 0.0 { f / r } else { 0.0 };
        [
            [kr * ex * ex + kt * (1.0 - ex * ex), (kr - kt) * ex * ey],
            [(kr - kt) * ex * ey, kr * ey * ey + kt * (1.0 - ey * ey)],
        ]
    }
}
