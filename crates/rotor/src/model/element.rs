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

impl ElementMatrices {
    /// The set from the translational and rotary mass and the stiffness: `M_s = M_sT +
    /// M_sR`, `J_s = 2 M_sR`.
    fn from_parts(mt: Mat4, mr: Mat4, k: Mat4) -> Self {
        let mut mass = mt;
        let mut gyro = mr;
        for r in 0..4 {
            for c in 0..4 {
                mass[r][c] += mr[r][c];
                gyro[r][c] = 2.0 * mr[r][c];
            }
        }
        Self {
            mass_translational: mt,
            mass_rotary: mr,
            mass,
            gyro,
            stiffness: k,
        }
    }
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
    ElementMatrices::from_parts(mt, mr, k)
}

/// A conical (tapered) element: diameters varying linearly from `left` (the first node) to
/// `right_outer_m`, `right_inner_m` at the second node, same length and material.
///
/// The matrices are the consistent ones of the Timoshenko element's interdependent
/// interpolation (Friswell, Penny, Garvey & Lees, *Dynamics of Rotating Machines*,
/// Cambridge 2010, §5.4.3: the shape functions that solve the uniform element's static
/// equations exactly) integrated over the varying section by 6-point Gauss–Legendre
/// quadrature, exact for the polynomial integrands (`A` quadratic and `I` quartic in the
/// axial coordinate, shape-function products up to degree 6):
///
/// ```text
///   M_T = ∫ ρ A N_wᵀ N_w dz,   M_R = ∫ ρ I N_ψᵀ N_ψ dz,   J = 2 M_R,
///   K   = ∫ E I N_ψ'ᵀ N_ψ' dz + ∫ κ G A (N_w' − N_ψ)ᵀ (N_w' − N_ψ) dz,
/// ```
///
/// with the shear parameter `φ` of the interpolation taken from the element's mean
/// section (`A`, `I`, `κ` at mid-length). For equal ends the integrals are the closed
/// forms of [`element_matrices`] (tested to rounding). For a taper the interpolation is
/// no longer the exact static solution, so the element converges with the mesh; the
/// damped eigenvalues of a rotor with conical elements agree with ROSS's conical element
/// (Genta & Gugliotta, J. Sound Vib. 1988) to 3e-10 (`tests/ross_linear.rs`).
pub fn tapered_matrices(
    left: &ShaftSection,
    right_outer_m: f64,
    right_inner_m: f64,
) -> ElementMatrices {
    let l = left.length_m;
    let (e, rho, mu) = (
        left.youngs_modulus_pa,
        left.density_kg_m3,
        left.poisson_ratio,
    );
    let g = left.shear_modulus_pa();
    let section = |xi: f64| {
        let d_out = left.outer_diameter_m + xi * (right_outer_m - left.outer_diameter_m);
        let d_in = left.inner_diameter_m + xi * (right_inner_m - left.inner_diameter_m);
        let a = PI / 4.0 * (d_out * d_out - d_in * d_in);
        let i = PI / 64.0 * (d_out.powi(4) - d_in.powi(4));
        (a, i, cowper_kappa(mu, d_out, d_in))
    };
    let (am, im, km) = section(0.5);
    let p = 12.0 * e * im / (g * km * am * l * l);
    let c = 1.0 / (1.0 + p);
    // shape functions at ξ: displacement N_w, rotation N_ψ, and their z-derivatives
    let shapes = |xi: f64| {
        let (x2, x3) = (xi * xi, xi * xi * xi);
        let nw = [
            c * (1.0 - 3.0 * x2 + 2.0 * x3 + p * (1.0 - xi)),
            c * l * (xi - 2.0 * x2 + x3 + 0.5 * p * (xi - x2)),
            c * (3.0 * x2 - 2.0 * x3 + p * xi),
            c * l * (-x2 + x3 - 0.5 * p * (xi - x2)),
        ];
        let dnw = [
            c * (-6.0 * xi + 6.0 * x2 - p) / l,
            c * (1.0 - 4.0 * xi + 3.0 * x2 + 0.5 * p * (1.0 - 2.0 * xi)),
            c * (6.0 * xi - 6.0 * x2 + p) / l,
            c * (-2.0 * xi + 3.0 * x2 - 0.5 * p * (1.0 - 2.0 * xi)),
        ];
        let npsi = [
            c * 6.0 * (-xi + x2) / l,
            c * (1.0 - 4.0 * xi + 3.0 * x2 + p * (1.0 - xi)),
            c * 6.0 * (xi - x2) / l,
            c * (-2.0 * xi + 3.0 * x2 + p * xi),
        ];
        let dnpsi = [
            c * 6.0 * (-1.0 + 2.0 * xi) / (l * l),
            c * (-4.0 + 6.0 * xi - p) / l,
            c * 6.0 * (1.0 - 2.0 * xi) / (l * l),
            c * (-2.0 + 6.0 * xi + p) / l,
        ];
        (nw, dnw, npsi, dnpsi)
    };
    // 6-point Gauss–Legendre on [0, 1]
    const X: [f64; 3] = [
        0.238_619_186_083_196_9,
        0.661_209_386_466_264_5,
        0.932_469_514_203_152,
    ];
    const W: [f64; 3] = [
        0.467_913_934_572_691,
        0.360_761_573_048_138_6,
        0.171_324_492_379_170_3,
    ];
    let mut mt = [[0.0; 4]; 4];
    let mut mr = [[0.0; 4]; 4];
    let mut k = [[0.0; 4]; 4];
    for (x, w) in X.iter().zip(W) {
        for xi in [0.5 * (1.0 - x), 0.5 * (1.0 + x)] {
            let wt = 0.5 * w * l;
            let (a, i, kappa) = section(xi);
            let (nw, dnw, npsi, dnpsi) = shapes(xi);
            let gamma: [f64; 4] = std::array::from_fn(|j| dnw[j] - npsi[j]);
            for r in 0..4 {
                for s in 0..4 {
                    mt[r][s] += wt * rho * a * nw[r] * nw[s];
                    mr[r][s] += wt * rho * i * npsi[r] * npsi[s];
                    k[r][s] +=
                        wt * (e * i * dnpsi[r] * dnpsi[s] + kappa * g * a * gamma[r] * gamma[s]);
                }
            }
        }
    }
    ElementMatrices::from_parts(mt, mr, k)
}

#[cfg(test)]
mod tapered_tests {
    use super::*;

    fn section(d_out: f64, d_in: f64, l: f64) -> ShaftSection {
        ShaftSection {
            length_m: l,
            inner_diameter_m: d_in,
            outer_diameter_m: d_out,
            youngs_modulus_pa: 211e9,
            poisson_ratio: 0.3,
            density_kg_m3: 7810.0,
        }
    }

    fn close(a: &Mat4, b: &Mat4, tol: f64) -> f64 {
        let scale = b.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = a
            .iter()
            .flatten()
            .zip(b.iter().flatten())
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(d <= tol * scale, "difference {d:e} of {scale:e}");
        d / scale
    }

    /// With equal ends the integrated matrices are Appendix B's closed forms, for a thick
    /// hollow element (φ ≈ 0.3) and a slender one.
    #[test]
    fn uniform_taper_is_the_closed_form() {
        for (d_out, d_in, l) in [(0.1, 0.04, 0.05), (0.03, 0.0, 0.4)] {
            let s = section(d_out, d_in, l);
            let t = tapered_matrices(&s, d_out, d_in);
            let u = s.matrices();
            close(&t.mass_translational, &u.mass_translational, 1e-13);
            close(&t.mass_rotary, &u.mass_rotary, 1e-13);
            close(&t.stiffness, &u.stiffness, 1e-12);
        }
    }

    /// The translational mass matrix holds the element's mass (the rigid translation
    /// `[1, 0, 1, 0]` gives `uᵀ M u` = the frustum's mass) and the stiffness has the two
    /// rigid-body modes in its null space.
    #[test]
    fn tapered_mass_and_rigid_modes() {
        let s = section(0.08, 0.02, 0.3);
        let t = tapered_matrices(&s, 0.05, 0.01);
        let u = [1.0, 0.0, 1.0, 0.0];
        let m: f64 = (0..4)
            .flat_map(|r| (0..4).map(move |c| (r, c)))
            .map(|(r, c)| u[r] * t.mass_translational[r][c] * u[c])
            .sum();
        // frustum: ρ π/4 ∫ (D(z)² − d(z)²) dz
        let frustum = |a: f64, b: f64| (a * a + a * b + b * b) / 3.0;
        let want = 7810.0 * PI / 4.0 * 0.3 * (frustum(0.08, 0.05) - frustum(0.02, 0.01));
        assert!((m - want).abs() < 1e-12 * want, "{m} vs {want}");
        let scale = t
            .stiffness
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for rigid in [[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.3, 1.0]] {
            for r in 0..4 {
                let f: f64 = (0..4).map(|c| t.stiffness[r][c] * rigid[c]).sum();
                assert!(f.abs() < 1e-12 * scale, "rigid mode {rigid:?}: {f}");
            }
        }
    }
}
