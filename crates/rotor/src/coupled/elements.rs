//! Nonlinear elements of the model file besides the rolling bearings (`[[nonlinear]]`):
//! rotor–stator rub, a polynomial (e.g. cubic) support, a unilateral spring. Each acts on
//! the relative displacement `u = (x_a − x_b, y_a − y_b)` of a node and ground (or of two
//! nodes) and returns its force on node `a` (left-hand-side sign: the restoring force; node
//! `b` gets its negative) with the exact 2×2 Jacobian `∂f/∂u`.
//!
//! * **Rub** (radial gap `g`, contact stiffness `k`, Coulomb coefficient `μ`): with
//!   `r = |u|`, no force while `r ≤ g`; in contact the normal force `k (r − g)` pushes back
//!   along `e_r = u/r` and friction `μ k (r − g)` acts along the tangent
//!   `e_θ = (−u_y, u_x)/r` against the rotor's surface motion, whose sense is the sign `s`
//!   of the rotor's speed (the rotor's surface speed `Ω R` dominates the whirl velocity:
//!   the classic rub model, e.g. Muszynska, *Rotordynamics*, CRC 2005, §5.8):
//!   `f = k (1 − g/r) (u + μ s J u)`, `J = [[0, −1], [1, 0]]`.
//! * **Polynomial support** (coefficients `c_1 … c_n`): the radial restoring force
//!   `F(r) = Σ c_j r^j` along `e_r`, `f = (Σ c_j r^{j−1}) u`: `[0, 0, k3]` is the cubic
//!   spring, `[k1, 0, k3]` the hardening Duffing support.
//! * **Unilateral spring** (direction `n` at angle `α` from +x towards +y, gap `g`,
//!   stiffness `k`): with `d = n·u`, no force while `d ≤ g`, else `f = k (d − g) n`: a stop
//!   on one side (the two-mass contact benchmark's).

/// One law, with its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum ElementLaw {
    Rub {
        gap_m: f64,
        stiffness_n_m: f64,
        friction: f64,
        /// Sense of the rotor's surface motion: sign of its speed ratio (0: not spinning).
        spin_sign: f64,
    },
    Polynomial {
        /// `c_j` for `j = 1 …` (N/m^j).
        coefficients: Vec<f64>,
    },
    Unilateral {
        gap_m: f64,
        stiffness_n_m: f64,
        /// Unit direction `n`.
        direction: [f64; 2],
    },
}

/// Force `f` (on node `a`, left-hand-side sign) and Jacobian `∂f/∂u` (rows f_x, f_y).
pub type ElementForce = ([f64; 2], [[f64; 2]; 2]);

impl ElementLaw {
    /// The switching function at relative displacement `u`: the penetration whose zeros
    /// are the instants where the force stops being smooth (`r − g` for rub, `n·u − g` for
    /// a unilateral spring); `None` for a smooth law.
    pub fn switching(&self, u: [f64; 2]) -> Option<f64> {
        match *self {
            Self::Rub { gap_m, .. } => Some(u[0].hypot(u[1]) - gap_m),
            Self::Polynomial { .. } => None,
            Self::Unilateral {
                gap_m,
                direction: n,
                ..
            } => Some(n[0] * u[0] + n[1] * u[1] - gap_m),
        }
    }

    /// Force and exact Jacobian at relative displacement `u` (m).
    pub fn force(&self, u: [f64; 2]) -> ElementForce {
        let zero = ([0.0; 2], [[0.0; 2]; 2]);
        match *self {
            Self::Rub {
                gap_m,
                stiffness_n_m: k,
                friction,
                spin_sign,
            } => {
                let r = u[0].hypot(u[1]);
                if r <= gap_m || r == 0.0 {
                    return zero;
                }
                let ms = friction * spin_sign;
                let phi = k * (1.0 - gap_m / r);
                // v = u + μ s J u
                let v = [u[0] - ms * u[1], u[1] + ms * u[0]];
                // ∂φ/∂u_j = k g u_j / r³
                let dphi = [k * gap_m * u[0] / r.powi(3), k * gap_m * u[1] / r.powi(3)];
                let dv = [[1.0, -ms], [ms, 1.0]];
                let mut jac = [[0.0; 2]; 2];
                for i in 0..2 {
                    for j in 0..2 {
                        jac[i][j] = phi * dv[i][j] + v[i] * dphi[j];
                    }
                }
                ([phi * v[0], phi * v[1]], jac)
            }
            Self::Polynomial { ref coefficients } => {
                let r = u[0].hypot(u[1]);
                // s(r) = Σ c_j r^{j−1}; s'(r) = Σ (j−1) c_j r^{j−2}
                let (mut s, mut ds) = (0.0, 0.0);
                for (i, &c) in coefficients.iter().enumerate() {
                    let j = i as i32 + 1;
                    s += c * r.powi(j - 1);
                    if j >= 2 {
                        ds += f64::from(j - 1) * c * r.powi(j - 2);
                    }
                }
                let mut jac = [[s, 0.0], [0.0, s]];
                if r > 0.0 {
                    for i in 0..2 {
                        for j in 0..2 {
                            // ∂(s u_i)/∂u_j = s δ_ij + u_i s'(r) u_j / r
                            jac[i][j] += u[i] * ds * u[j] / r;
                        }
                    }
                }
                ([s * u[0], s * u[1]], jac)
            }
            Self::Unilateral {
                gap_m,
                stiffness_n_m: k,
                direction: n,
            } => {
                let d = n[0] * u[0] + n[1] * u[1];
                if d <= gap_m {
                    return zero;
                }
                let f = k * (d - gap_m);
                (
                    [f * n[0], f * n[1]],
                    [
                        [k * n[0] * n[0], k * n[0] * n[1]],
                        [k * n[1] * n[0], k * n[1] * n[1]],
                    ],
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact Jacobian against central differences (step 1e-9 of the scale), at points
    /// in contact, out of contact and on both sides of the axes.
    fn check(law: &ElementLaw, points: &[[f64; 2]]) {
        for &u in points {
            let (_, jac) = law.force(u);
            let h = 1e-9 * u[0].hypot(u[1]).max(1e-6);
            for j in 0..2 {
                let (mut up, mut dn) = (u, u);
                up[j] += h;
                dn[j] -= h;
                let (fp, _) = law.force(up);
                let (fm, _) = law.force(dn);
                for i in 0..2 {
                    let fd = (fp[i] - fm[i]) / (2.0 * h);
                    let scale = jac.iter().flatten().fold(1.0f64, |m, v| m.max(v.abs()));
                    assert!(
                        (fd - jac[i][j]).abs() <= 1e-6 * scale,
                        "{law:?} at {u:?}: ∂f{i}/∂u{j} = {} against {fd}",
                        jac[i][j]
                    );
                }
            }
        }
    }

    const POINTS: [[f64; 2]; 6] = [
        [1.3e-4, 0.4e-4],
        [-0.9e-4, 1.1e-4],
        [0.2e-4, -1.6e-4],
        [-1.2e-4, -1.0e-4],
        [0.3e-4, 0.2e-4],
        [0.0, 2.0e-4],
    ];

    #[test]
    fn rub_jacobian_is_exact() {
        for spin_sign in [1.0, -1.0, 0.0] {
            check(
                &ElementLaw::Rub {
                    gap_m: 1e-4,
                    stiffness_n_m: 3e6,
                    friction: 0.2,
                    spin_sign,
                },
                &POINTS,
            );
        }
    }

    #[test]
    fn polynomial_jacobian_is_exact() {
        check(
            &ElementLaw::Polynomial {
                coefficients: vec![2e5, -3e8, 5e13],
            },
            &POINTS,
        );
    }

    #[test]
    fn unilateral_jacobian_is_exact() {
        let a = 0.7_f64;
        check(
            &ElementLaw::Unilateral {
                gap_m: 2e-5,
                stiffness_n_m: 4e6,
                direction: [a.cos(), a.sin()],
            },
            &POINTS,
        );
    }

    /// Rub: no force inside the gap; in contact the normal part is `k (r − g)` and the
    /// friction part `μ k (r − g)` against the spin, at right angles.
    #[test]
    fn rub_force_closed_form() {
        let law = ElementLaw::Rub {
            gap_m: 1e-4,
            stiffness_n_m: 2e6,
            friction: 0.3,
            spin_sign: 1.0,
        };
        assert_eq!(law.force([0.5e-4, 0.5e-4]).0, [0.0, 0.0]);
        let (f, _) = law.force([1.5e-4, 0.0]);
        assert!((f[0] - 2e6 * 0.5e-4).abs() < 1e-9);
        assert!((f[1] - 0.3 * 2e6 * 0.5e-4).abs() < 1e-9);
    }

    /// The cubic support's force is `k3 r³` along `e_r`.
    #[test]
    fn cubic_support_closed_form() {
        let law = ElementLaw::Polynomial {
            coefficients: vec![0.0, 0.0, 1e12],
        };
        let (f, _) = law.force([3e-4, 4e-4]);
        let r: f64 = 5e-4;
        assert!((f[0] - 1e12 * r.powi(3) * 0.6).abs() < 1e-9);
        assert!((f[1] - 1e12 * r.powi(3) * 0.8).abs() < 1e-9);
    }
}
