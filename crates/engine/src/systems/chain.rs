//! A linear spring–mass chain with one nonlinear contact, optionally coupled to a linear
//! thermal chain through one nonlinear thermal node: the "many linear, few nonlinear DoFs"
//! structure of a rotor on nonlinear bearings, small enough to check every derivative.
//!
//! ```text
//!   mechanical: m ẍ_i + c (2ẋ_i − ẋ_{i−1} − ẋ_{i+1}) + k (2x_i − x_{i−1} − x_{i+1}) = δ_{i0} F cos ω t
//!               + at contact a (DoF i_a): f_a = k₃ x³ (1 + β T_{j(a)}) + d₃ ẋ³
//!   thermal:    C Ṫ_j + κ (2T_j − T_{j−1} − T_{j+1}) = δ_{j0} Q
//!               + at hot node b (node j_b): g_b = η T² − γ ẋ_{i(b)}² − ρ x_{i(b)}² T
//! ```
//!
//! with `p` contacts and `q` hot nodes spread evenly along the chains, contact `a` coupled
//! to hot node `a mod q` and hot node `b` to contact `b mod p`.
//!
//! (fixed ends, `x_{−1} = x_n = 0`, `T_{−1} = T_m = 0`). All parameters are
//! nondimensional test values; the terms are chosen so that every partial derivative of
//! the [`System`] seam (`∂f/∂x`, `∂f/∂ẋ`, `∂f/∂T`, `∂g/∂x`, `∂g/∂ẋ`, `∂g/∂T`) is non-zero.

use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Chain with `p` nonlinear mechanical DoFs and `q` nonlinear thermal DoFs.
#[derive(Clone, Debug)]
pub struct Chain {
    pub n_mech: usize,
    pub n_therm: usize,
    pub mass: f64,
    pub stiffness: f64,
    pub damping: f64,
    pub cubic: f64,
    pub cubic_damping: f64,
    pub thermal_softening: f64,
    pub capacity: f64,
    pub conductance: f64,
    pub heat_quadratic: f64,
    pub heat_friction: f64,
    pub heat_coupling: f64,
    pub force: f64,
    pub heat_load: f64,
    nl: NonlinearDofs,
}

impl Chain {
    /// Chain of `n_mech` masses (contact at the middle DoF) and `n_therm` thermal nodes (hot
    /// node in the middle). Default values: `m = 1, k = 1, c = 0.02, k₃ = 0.5, d₃ = 0.01,
    /// β = 0.1, C = 1, κ = 0.5, η = 0.05, γ = 0.2, ρ = 0.1, F = 0.1, Q = 1`.
    pub fn new(n_mech: usize, n_therm: usize) -> Self {
        Self::with_contacts(n_mech, n_therm, 1, usize::from(n_therm > 0))
    }

    /// Chain with `p` contacts and `q` hot nodes (`1 ≤ p ≤ n_mech`, `q ≤ n_therm`, `q = 0`
    /// when `n_therm = 0`), placed at `(2a + 1)·n/(2p)`.
    pub fn with_contacts(n_mech: usize, n_therm: usize, p: usize, q: usize) -> Self {
        let spread = |n: usize, k: usize| -> Vec<usize> {
            (0..k).map(|a| ((2 * a + 1) * n) / (2 * k)).collect()
        };
        Self {
            n_mech,
            n_therm,
            mass: 1.0,
            stiffness: 1.0,
            damping: 0.02,
            cubic: 0.5,
            cubic_damping: 0.01,
            thermal_softening: 0.1,
            capacity: 1.0,
            conductance: 0.5,
            heat_quadratic: 0.05,
            heat_friction: 0.2,
            heat_coupling: 0.1,
            force: 0.1,
            heat_load: 1.0,
            nl: NonlinearDofs {
                mech: spread(n_mech, p),
                therm: spread(n_therm, q),
            },
        }
    }
}

fn tridiagonal(n: usize, diag: f64, off: f64) -> DenseMatrix {
    let mut m = DenseMatrix::zeros(n);
    for i in 0..n {
        *m.get_mut(i, i) = diag;
        if i + 1 < n {
            *m.get_mut(i, i + 1) = off;
            *m.get_mut(i + 1, i) = off;
        }
    }
    m
}

impl System for Chain {
    fn n_mech(&self) -> usize {
        self.n_mech
    }

    fn n_therm(&self) -> usize {
        self.n_therm
    }

    fn linear(&self, _omega: f64) -> LinearPart {
        LinearPart {
            mass: tridiagonal(self.n_mech, self.mass, 0.0),
            damping: tridiagonal(self.n_mech, 2.0 * self.damping, -self.damping),
            stiffness: tridiagonal(self.n_mech, 2.0 * self.stiffness, -self.stiffness),
            thermal_capacity: tridiagonal(self.n_therm, self.capacity, 0.0),
            thermal_conductance: tridiagonal(
                self.n_therm,
                2.0 * self.conductance,
                -self.conductance,
            ),
        }
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.nl
    }

    fn eval_nonlinear(
        &self,
        _omega: f64,
        _t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        out.clear();
        let (p, q) = (x.len(), temp.len());
        for a in 0..p {
            let tc = if q > 0 { temp[a % q] } else { 0.0 };
            let soft = 1.0 + self.thermal_softening * tc;
            out.f[a] = self.cubic * x[a].powi(3) * soft + self.cubic_damping * v[a].powi(3);
            out.df_dx[a * p + a] = 3.0 * self.cubic * x[a] * x[a] * soft;
            out.df_dv[a * p + a] = 3.0 * self.cubic_damping * v[a] * v[a];
            if q > 0 {
                out.df_dt[a * q + a % q] = self.cubic * x[a].powi(3) * self.thermal_softening;
            }
        }
        for (b, &tc) in temp.iter().enumerate() {
            let i = b % p;
            out.g[b] = self.heat_quadratic * tc * tc
                - self.heat_friction * v[i] * v[i]
                - self.heat_coupling * x[i] * x[i] * tc;
            out.dg_dx[b * p + i] = -2.0 * self.heat_coupling * x[i] * tc;
            out.dg_dv[b * p + i] = -2.0 * self.heat_friction * v[i];
            out.dg_dt[b * q + b] =
                2.0 * self.heat_quadratic * tc - self.heat_coupling * x[i] * x[i];
        }
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        out[0] = self.force * (omega * t).cos();
    }

    fn thermal_load(&self, _omega: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        if let Some(q) = out.first_mut() {
            *q = self.heat_load;
        }
    }
}
