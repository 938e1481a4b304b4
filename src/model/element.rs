//! Hollow Timoshenko shaft element (paper Appendix B, Eqs. B.1–B.3) and its section data.
//!
//! Local coordinates of one bending plane: `[w1, θ1, w2, θ2]` with `θ = dw/dz` (the
//! paper's `q_s1 = [x1 θx1 x2 θx2]`, and the same matrices for `q_s2 = [y1 θy1 y2 θy2]`).
//! With `φs = 12EI/(GκAl²)`, `G = E/(2(1+μ))` and Cowper's shear coefficient of a hollow
//! circular section as written in Appendix B
//!
//! ```text
//!   κ = 1 / ( (7+6μ)/(6(1+μ)) · [1 + (20+12μ)/(7+6μ) · (Dd/(D²+d²))²] )
//! ```
//!
//! (Cowper, J. Appl. Mech. 33 (1966) 335–340, Table 1, hollow circle), the element has the
//! translational mass `M_sT`, the rotary mass `M_sR`, the gyroscopic matrix `J_s = 2 M_sR`
//! (per unit spin speed) and the stiffness `K_s`. With `φs = 0` they reduce to the
//! Euler–Bernoulli consistent matrices (Przemieniecki, *Theory of Matrix Structural
//! Analysis*, 1968, §11).

#![allow(clippy::needless_range_loop)] // index loops read like the matrix algebra

use std::f64::consts::PI;

/// A 4×4 element matrix, row-major.
pub type Mat4 = [[f64; 4]; 4];

/// Geometry and material of a uniform hollow circular shaft element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShaftSection {
    pub length_m: f64,
    pub inner_diameter_m: f64,
    pub outer_diameter_m: f64,
    pub youngs_modulus_pa: f64,
    pub poisson_ratio: f64,
    pub density_kg_m3: f64,
}

impl ShaftSection {
    /// Cross-section area `A = π (D² − d²)/4`.
    pub fn area_m2(&self) -> f64 {
        PI / 4.0 * (self.outer_diameter_m.powi(2) - self.inner_diameter_m.powi(2))
    }

    /// Area moment of inertia `I = π (D⁴ − d⁴)/64`.
    pub fn second_moment_m4(&self) -> f64 {
        PI / 64.0 * (self.outer_diameter_m.powi(4) - self.inner_diameter_m.powi(4))
    }

    /// Shear modulus `G = E / (2 (1 + μ))`.
    pub fn shear_modulus_pa(&self) -> f64 {
        self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))
    }

    /// Cowper's shear coefficient κ for a hollow circle (Appendix B).
    pub fn shear_coefficient(&self) -> f64 {
        cowper_kappa(
            self.poisson_ratio,
            self.outer_diameter_m,
            self.inner_diameter_m,
        )
    }

    /// Shear parameter `φs = 12 E I / (G κ A l²)`.
    pub fn phi_s(&self) -> f64 {
        12.0 * self.youngs_modulus_pa * self.second_moment_m4()
            / (self.shear_modulus_pa()
                * self.shear_coefficient()
                * self.area_m2()
                * self.length_m.powi(2))
    }

    /// Element mass `ρ A l`.
    pub fn mass_kg(&self) -> f64 {
        self.density_kg_m3 * self.area_m2() * self.length_m
    }

    /// Element polar moment of inertia `2 ρ I l`.
    pub fn polar_inertia_kg_m2(&self) -> f64 {
        2.0 * self.density_kg_m3 * self.second_moment_m4() * self.length_m
    }

    /// The element matrices of Appendix B with this section's `φs`.
    pub fn matrices(&self) -> ElementMatrices {
        element_matrices(self, self.phi_s())
    }
}

/// Cowper's shear coefficient of a hollow circular section, outer diameter `d_out`,
/// inner diameter `d_in`, Poisson ratio `mu` (Appendix B).
pub fn cowper_kappa(mu: f64, d_out: f64, d_in: f64) -> f64 {
    let r = d_out * d_in / (d_out * d_out + d_in * d_in);
    1.0 / ((7.0 + 6.0 * mu) / (6.0 * (1.0 + mu))
        * (1.0 + (20.0 + 12.0 * mu) / (7.0 + 6.0 * mu) * r * r))
}

/// Element matrices of one bending plane (Appendix B).
#[derive(Clone, Debug, PartialEq)]
pub struct ElementMatrices {
    /// Translational mass `M_sT` (B.1).
    pub mass_translational: Mat4,
    /// Rotary mass `M_sR` (B.1).
    pub mass_rotary: Mat4,
    /// `M_s = M_sT + M_sR`.
    pub mass: Mat4,
    /// Gyroscopic matrix per unit spin speed, `J_s = 2 M_sR` (B.2).
    pub gyro: Mat4,
    /// Stiffness `K_s` (B.3).
    pub stiffness: Mat4,
}

fn sym(lower: [[f64; 4]; 4]) -> Mat4 {
    let mut m = lower;
    for i in 0..4 {
        for j in (i + 1)..4 {
            m[i][j] = lower[j][i];
        }
    }
    m
}

/// Appendix B matrices for section `s` with shear parameter `phi` (pass `0.0` for the
/// Euler–Bernoulli limit).
pub fn element_matrices(s: &ShaftSection, phi: f64) -> ElementMatrices {
    let l = s.length_m;
    let (a, i) = (s.area_m2(), s.second_moment_m4());
    let rho = s.density_kg_m3;
    let e = s.youngs_modulus_pa;
    let p = phi;
    let p2 = phi * phi;
    let m1 = 13.0 / 35.0 + 7.0 / 10.0 * p + p2 / 3.0;
    let m2 = l * (11.0 / 210.0 + 11.0 / 120.0 * p + p2 / 24.0);
    let m3 = 9.0 / 70.0 + 3.0 / 10.0 * p + p2 / 6.0;
    let m4 = -l * (13.0 / 420.0 + 3.0 / 40.0 * p + p2 / 24.0);
    let m5 = l * l * (1.0 / 105.0 + p / 60.0 + p2 / 120.0);
    let m6 = -l * l * (1.0 / 140.0 + p / 60.0 + p2 / 120.0);
    let m7 = 6.0 / 5.0;
    let m8 = l * (1.0 / 10.0 - p / 2.0);
    let m9 = l * l * (2.0 / 15.0 + p / 6.0 + p2 / 3.0);
    let m10 = l * l * (-1.0 / 30.0 - p / 6.0 + p2 / 6.0);

    let ct = rho * a * l / (1.0 + p).powi(2);
    let mt = sym([
        [m1, 0.0, 0.0, 0.0],
        [m2, m5, 0.0, 0.0],
        [m3, -m4, m1, 0.0],
        [m4, m6, -m2, m5],
    ])
    .map(|r| r.map(|v| v * ct));
    let cr = rho * i / (l * (1.0 + p).powi(2));
    let mr = sym([
        [m7, 0.0, 0.0, 0.0],
        [m8, m9, 0.0, 0.0],
        [-m7, -m8, m7, 0.0],
        [m8, m10, -m8, m9],
    ])
    .map(|r| r.map(|v| v * cr));
    let ck = e * i / ((1.0 + p) * l.powi(3));
    let k = sym([
        [12.0, 0.0, 0.0, 0.0],
        [6.0 * l, (4.0 + p) * l * l, 0.0, 0.0],
        [-12.0, -6.0 * l, 12.0, 0.0],
        [6.0 * l, (2.0 - p) * l * l, -6.0 * l, (4.0 + p) * l * l],
    ])
    .map(|r| r.map(|v| v * ck));
    let mut mass = mt;
    let mut gyro = mr;
    for r in 0..4 {
        for c in 0..4 {
            mass[r][c] += mr[r][c];
            gyro[r][c] = 2.0 * mr[r][c];
        }
    }
    ElementMatrices {
        mass_translational: mt,
        mass_rotary: mr,
        mass,
        gyro,
        stiffness: k,
    }
}
