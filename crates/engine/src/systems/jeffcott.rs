//! Jeffcott rotor on a deep-groove ball bearing with radial clearance (paper Eq. 3–4 form).
//!
//! A symmetric rotor (disk at mid-span, massless elastic shaft, two identical bearings) is
//! modelled by symmetry as half the disk on one bearing. DoFs (SI, `x` vertical *downward*,
//! `y` horizontal): `[x_d, y_d, x_b, y_b]`, disk then journal (bearing inner ring):
//!
//! ```text
//!   m_d ẍ_d + c_d ẋ_d + k_s (x_d − x_b) = m_d g + m_d e ω² cos ωt
//!   m_d ÿ_d + c_d ẏ_d + k_s (y_d − y_b) =         m_d e ω² sin ωt
//!   m_b ẍ_b + c_b ẋ_b + k_s (x_b − x_d) + F_x(x_b, y_b, t) = m_b g
//!   m_b ÿ_b + c_b ẏ_b + k_s (y_b − y_d) + F_y(x_b, y_b, t) = 0
//!   [F_x, F_y] = k_h Σ_k δ_k^{3/2} H(δ_k) [cos θ_k, sin θ_k],
//!   δ_k = x_b cos θ_k + y_b sin θ_k − δ_0,   θ_k = 2π(k−1)/N_b + ω_c t
//! ```
//!
//! with the cage speed `ω_c = ω d_i / (d_i + d_o)` (outer ring fixed, paper Section 2.1).
//! The journal DoFs are the nonlinear DoFs; the disk DoFs are linear (condensed).
//!
//! ## Parameters (defaults) and sources
//! * Hertz constant `k_h = 7.055e9 N/m^{3/2}`, `N_b = 8` balls, bearing damping
//!   `c_b = 200 N s/m`, journal mass `m_b = 0.6 kg`: the ball bearing of Tiwari, Gupta &
//!   Prakash, "Effect of radial internal clearance of a ball bearing on the dynamics of a
//!   balanced horizontal rotor", JSV 238 (2000), also used by Harsha (2005).
//! * Radial clearance `δ_0 = 10 µm`: within the 5–20 µm range studied there.
//! * Raceway diameters `d_i = 30 mm`, `d_o = 45 mm` (a 6205-size bearing rounded so that
//!   `ω_c / ω = 2/5` exactly; the ball-passage frequency `N_b ω_c = 16/5 ω` is then
//!   commensurate with ω and the response is periodic with period `5 · 2π/ω`).
//! * Half disk `m_d = 4 kg`, shaft stiffness (per bearing side) `k_s = 1e6 N/m`: rotor
//!   critical speed `√(k_s/m_d) = 500 rad/s` on rigid bearings; disk damping
//!   `c_d = 80 N s/m` (2 % of critical); unbalance eccentricity `e = 20 µm`;
//!   `g = 9.81 m/s²`. Sweep range 300–700 rad/s. These are illustrative choices, not a
//!   particular machine.
//!
//! The basis must contain multiples of `ω/5`: [`Jeffcott::basis`].
//!
//! ## What the response needs (measured, `examples/jeffcott.rs`, `tests/engine_jeffcott.rs`)
//! The journal rides on the contact stiffness of the loaded balls, a lightly damped mode
//! near 8–9·10³ rad/s (`ζ` ≈ 0.02), i.e. near the 75th multiple of `ω/5` at 600 rad/s.
//! Up to about 555 rad/s at least one ball is always in contact; above, the journal leaves
//! all balls for part of each period (up to ~18 % of it near 600 rad/s) and the contact
//! force becomes a sequence of impacts whose spectrum reaches that mode. Then:
//! * the basis must reach well past the mode: with multiples up to 4ω (20 harmonics) the
//!   journal maxima are 9–11 % below time integration at 550–600 rad/s and the branch
//!   misses all the structure below; with 160 harmonics (up to 32ω) they agree to 5e-4,
//!   and the folds between 570 and 580 rad/s sit at the same speeds (to ~0.01 rad/s)
//!   with 240 harmonics and with 4× the AFT samples;
//! * each time a multiple of `ω/5` crosses the mode (every ~7 rad/s) the branch has a
//!   narrow super-harmonic resonance, bent into fold pairs (~35 between 560 and 640
//!   rad/s), with period doublings and Neimark–Sacker points: between them time
//!   integration settles on period-2, -4, -5 and non-periodic responses (e.g. 610–640
//!   rad/s), and isolated branches of periodic orbits exist beside the continued one (one
//!   spans 646–652 rad/s and is where time integration from rest settles at 650 rad/s);
//! * these folds are a fraction of a rad/s wide and live in the journal's high harmonics,
//!   ~1e-7 m against the disk's static sag of ~5e-5 m: continuation needs each DoF scaled
//!   by its own size (`ContinuationOptions::scale_per_dof`) to resolve them.

use thiserror::Error;

use crate::hb::{Basis, BasisError, Ratio};
use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Errors building the Jeffcott model's basis.
#[derive(Debug, Error, PartialEq)]
pub enum JeffcottError {
    #[error(
        "cage speed ratio {ratio} is not a rational with denominator ≤ 100: the response would not be periodic"
    )]
    IrrationalCageRatio { ratio: f64 },
    #[error(transparent)]
    Basis(#[from] BasisError),
}

/// Jeffcott rotor on a Hertzian ball bearing with clearance (SI units).
#[derive(Clone, Debug)]
pub struct Jeffcott {
    pub disk_mass_kg: f64,
    pub journal_mass_kg: f64,
    pub shaft_stiffness_n_m: f64,
    pub disk_damping_n_s_m: f64,
    pub bearing_damping_n_s_m: f64,
    pub hertz_n_m15: f64,
    pub n_balls: usize,
    pub clearance_m: f64,
    pub inner_race_diameter_m: f64,
    pub outer_race_diameter_m: f64,
    pub eccentricity_m: f64,
    pub gravity_m_s2: f64,
    nl: NonlinearDofs,
}

impl Default for Jeffcott {
    fn default() -> Self {
        Self {
            disk_mass_kg: 4.0,
            journal_mass_kg: 0.6,
            shaft_stiffness_n_m: 1e6,
            disk_damping_n_s_m: 80.0,
            bearing_damping_n_s_m: 200.0,
            hertz_n_m15: 7.055e9,
            n_balls: 8,
            clearance_m: 10e-6,
            inner_race_diameter_m: 30e-3,
            outer_race_diameter_m: 45e-3,
            eccentricity_m: 20e-6,
            gravity_m_s2: 9.81,
            nl: NonlinearDofs {
                mech: vec![2, 3],
                therm: vec![],
            },
        }
    }
}

impl Jeffcott {
    /// Default sweep range (rad/s): the primary resonance (~488 rad/s) and the range above
    /// it where the journal loses contact (from ~555 rad/s; see the module docs for the
    /// basis and continuation settings this needs).
    pub const OMEGA_RANGE: (f64, f64) = (300.0, 700.0);

    /// Cage speed ratio `ω_c / ω = d_i / (d_i + d_o)`.
    pub fn cage_ratio(&self) -> f64 {
        self.inner_race_diameter_m / (self.inner_race_diameter_m + self.outer_race_diameter_m)
    }

    /// Basis of all multiples `k/q · ω`, `k = 1..=max_multiple`, where `q` is the
    /// denominator of the cage ratio (5 for the defaults: `max_multiple = 20` reaches 4ω).
    /// Errors when the cage ratio is not a rational with denominator ≤ 100.
    pub fn basis(&self, max_multiple: u32) -> Result<Basis, JeffcottError> {
        let ratio = self.cage_ratio();
        let r =
            Ratio::approximate(ratio, 100).ok_or(JeffcottError::IrrationalCageRatio { ratio })?;
        let q = r.den;
        Ok(Basis::new(
            (1..=max_multiple)
                .map(|k| Ratio::new(k, q))
                .collect::<Result<Vec<_>, _>>()?,
        )?)
    }

    /// Contact force and stiffness of the bearing at journal position `(x, y)`, time `t`.
    fn bearing(&self, omega: f64, t: f64, x: f64, y: f64) -> ([f64; 2], [f64; 4]) {
        let wc = omega * self.cage_ratio();
        let mut f = [0.0; 2];
        let mut k = [0.0; 4];
        for b in 0..self.n_balls {
            let th = 2.0 * std::f64::consts::PI * b as f64 / self.n_balls as f64 + wc * t;
            let (s, c) = th.sin_cos();
            let d = x * c + y * s - self.clearance_m;
            if d > 0.0 {
                let sq = d.sqrt();
                let fk = self.hertz_n_m15 * d * sq;
                let kk = 1.5 * self.hertz_n_m15 * sq;
                f[0] += fk * c;
                f[1] += fk * s;
                k[0] += kk * c * c;
                k[1] += kk * c * s;
                k[2] += kk * s * c;
                k[3] += kk * s * s;
            }
        }
        (f, k)
    }

    /// Start guess for Newton at `omega` (all DoFs, `basis` layout): the static
    /// equilibrium under gravity with the cage at its `t = 0` position plus the disk's
    /// unbalance response on rigid bearings (when ω is in the basis). The system has no
    /// support without contact, so zero coefficients give a singular Jacobian.
    pub fn start_guess(&self, basis: &Basis, omega: f64) -> Vec<f64> {
        let w = (self.disk_mass_kg + self.journal_mass_kg) * self.gravity_m_s2;
        // bisection on the vertical journal position: bearing force = total weight
        let (mut lo, mut hi) = (self.clearance_m, self.clearance_m + 1e-3);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.bearing(0.0, 0.0, mid, 0.0).0[0] > w {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let xb = 0.5 * (lo + hi);
        let xd = xb + self.disk_mass_kg * self.gravity_m_s2 / self.shaft_stiffness_n_m;
        let nc = basis.n_coeffs();
        let mut a = vec![0.0; 4 * nc];
        a[0] = xd;
        a[2 * nc] = xb;
        let nh = basis.n_harmonics();
        if let Some(h) = basis
            .harmonics()
            .iter()
            .position(|r| r.num == 1 && r.den == 1)
        {
            let (m, k, c) = (
                self.disk_mass_kg,
                self.shaft_stiffness_n_m,
                self.disk_damping_n_s_m,
            );
            let u0 = m * self.eccentricity_m * omega * omega;
            let (re, im) = (k - m * omega * omega, c * omega);
            let d = re * re + im * im;
            let (hr, hi) = (re / d, -im / d);
            a[1 + h] = u0 * hr;
            a[1 + nh + h] = -u0 * hi;
            a[nc + 1 + h] = u0 * hi;
            a[nc + 1 + nh + h] = u0 * hr;
        }
        a
    }
}

impl System for Jeffcott {
    fn n_mech(&self) -> usize {
        4
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        let mut m = DenseMatrix::zeros(4);
        let mut c = DenseMatrix::zeros(4);
        let mut k = DenseMatrix::zeros(4);
        for (i, (mi, ci)) in [
            (self.disk_mass_kg, self.disk_damping_n_s_m),
            (self.disk_mass_kg, self.disk_damping_n_s_m),
            (self.journal_mass_kg, self.bearing_damping_n_s_m),
            (self.journal_mass_kg, self.bearing_damping_n_s_m),
        ]
        .into_iter()
        .enumerate()
        {
            *m.get_mut(i, i) = mi;
            *c.get_mut(i, i) = ci;
        }
        let ks = self.shaft_stiffness_n_m;
        for (d, b) in [(0, 2), (1, 3)] {
            k.add(d, d, ks);
            k.add(b, b, ks);
            k.add(d, b, -ks);
            k.add(b, d, -ks);
        }
        LinearPart::mechanical(m, c, k)
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.nl
    }

    fn eval_nonlinear(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        _v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        let (f, k) = self.bearing(omega, t, x[0], x[1]);
        out.f.copy_from_slice(&f);
        out.df_dx.copy_from_slice(&k);
        out.df_dv.iter_mut().for_each(|v| *v = 0.0);
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        let u = self.disk_mass_kg * self.eccentricity_m * omega * omega;
        let (s, c) = (omega * t).sin_cos();
        out[0] = self.disk_mass_kg * self.gravity_m_s2 + u * c;
        out[1] = u * s;
        out[2] = self.journal_mass_kg * self.gravity_m_s2;
        out[3] = 0.0;
    }
}
