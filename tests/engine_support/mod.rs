//! Independent references for the engine tests: a fixed-step RK4 integrator of the full
//! equations of motion and a Floquet method that integrates the variational equations
//! over one period (RK4, monodromy matrix, eigenvalues by nalgebra's Schur form).
//! Mechanical systems only (`n_therm = 0`).
#![allow(dead_code, clippy::needless_range_loop)]

use nalgebra::DMatrix;
use tmrotor::stability::{FloquetResult, StabilityError, StabilityMethod};
use tmrotor::system::{LinearPart, NonlinearEval, PeriodicOrbit, System};

/// `M⁻¹` of the system at `omega`.
fn inverse_mass(system: &dyn System, omega: f64) -> DMatrix<f64> {
    let lin = system.linear(omega);
    let n = lin.mass.n;
    let m = DMatrix::from_row_slice(n, n, &lin.mass.data);
    m.try_inverse().expect("invertible mass matrix")
}

/// Right-hand side of the first-order form `y = [x, v]`.
fn rhs(
    system: &dyn System,
    lin: &LinearPart,
    omega: f64,
    t: f64,
    y: &[f64],
    minv: &DMatrix<f64>,
    out: &mut [f64],
) {
    let n = system.n_mech();
    let nl = system.nonlinear_dofs();
    let (x, v) = y.split_at(n);
    let mut force = vec![0.0; n];
    system.forcing(omega, t, &mut force);
    for i in 0..n {
        for j in 0..n {
            force[i] -= lin.damping.get(i, j) * v[j] + lin.stiffness.get(i, j) * x[j];
        }
    }
    let xn: Vec<f64> = nl.mech.iter().map(|&d| x[d]).collect();
    let vn: Vec<f64> = nl.mech.iter().map(|&d| v[d]).collect();
    let mut e = NonlinearEval::new(nl.mech.len(), 0);
    system.eval_nonlinear(omega, t, &xn, &vn, &[], &mut e);
    for (k, &d) in nl.mech.iter().enumerate() {
        force[d] -= e.f[k];
    }
    out[..n].copy_from_slice(v);
    for i in 0..n {
        out[n + i] = (0..n).map(|j| minv[(i, j)] * force[j]).sum();
    }
}

/// Integrates from `y0` at `t0` over `n_steps` RK4 steps of `dt`, calling `sample(t, y)`
/// after every step; returns the final state.
pub fn rk4(
    system: &dyn System,
    omega: f64,
    t0: f64,
    y0: &[f64],
    dt: f64,
    n_steps: usize,
    mut sample: impl FnMut(f64, &[f64]),
) -> Vec<f64> {
    let minv = inverse_mass(system, omega);
    let lin = system.linear(omega);
    let m = y0.len();
    let mut y = y0.to_vec();
    let mut t = t0;
    let (mut k1, mut k2, mut k3, mut k4, mut tmp) = (
        vec![0.0; m],
        vec![0.0; m],
        vec![0.0; m],
        vec![0.0; m],
        vec![0.0; m],
    );
    for _ in 0..n_steps {
        rhs(system, &lin, omega, t, &y, &minv, &mut k1);
        for i in 0..m {
            tmp[i] = y[i] + 0.5 * dt * k1[i];
        }
        rhs(system, &lin, omega, t + 0.5 * dt, &tmp, &minv, &mut k2);
        for i in 0..m {
            tmp[i] = y[i] + 0.5 * dt * k2[i];
        }
        rhs(system, &lin, omega, t + 0.5 * dt, &tmp, &minv, &mut k3);
        for i in 0..m {
            tmp[i] = y[i] + dt * k3[i];
        }
        rhs(system, &lin, omega, t + dt, &tmp, &minv, &mut k4);
        for i in 0..m {
            y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        t += dt;
        sample(t, &y);
    }
    y
}

/// Runs `n_transient` periods from `y0`, then returns `max |x_dof|` over one more period
/// (largest step sample refined by the parabola through it and its neighbours) and the
/// state at its end. `steps` RK4 steps per period.
pub fn steady_max_abs(
    system: &dyn System,
    omega: f64,
    period: f64,
    y0: &[f64],
    n_transient: usize,
    steps: usize,
    dof: usize,
) -> (f64, Vec<f64>) {
    let dt = period / steps as f64;
    let y = rk4(system, omega, 0.0, y0, dt, n_transient * steps, |_, _| {});
    let t0 = n_transient as f64 * period;
    let mut samples = Vec::with_capacity(steps);
    let y = rk4(system, omega, t0, &y, dt, steps, |_, y| {
        samples.push(y[dof].abs())
    });
    let (j, &m) = samples
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .expect("samples");
    let n = samples.len();
    let (y0, y2) = (samples[(j + n - 1) % n], samples[(j + 1) % n]);
    let den = y0 - 2.0 * m + y2;
    let refined = if den < 0.0 {
        m - (y0 - y2).powi(2) / (8.0 * den)
    } else {
        m
    };
    (refined, y)
}

/// Floquet multipliers from the variational equations `δẏ = A(t) δy` integrated with RK4
/// (`steps` per period) along the orbit.
pub struct VariationalFloquet {
    pub steps: usize,
}

impl VariationalFloquet {
    fn jac(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        t: f64,
        minv: &DMatrix<f64>,
    ) -> DMatrix<f64> {
        let n = system.n_mech();
        let omega = orbit.omega();
        let lin = system.linear(omega);
        let nl = system.nonlinear_dofs();
        let (mut x, mut v) = (vec![0.0; n], vec![0.0; n]);
        orbit.state_at(t, &mut x, &mut v, &mut []);
        let mut kx = DMatrix::from_row_slice(n, n, &lin.stiffness.data);
        let mut cv = DMatrix::from_row_slice(n, n, &lin.damping.data);
        let p = nl.mech.len();
        let xn: Vec<f64> = nl.mech.iter().map(|&d| x[d]).collect();
        let vn: Vec<f64> = nl.mech.iter().map(|&d| v[d]).collect();
        let mut e = NonlinearEval::new(p, 0);
        system.eval_nonlinear(omega, t, &xn, &vn, &[], &mut e);
        for (a, &da) in nl.mech.iter().enumerate() {
            for (b, &db) in nl.mech.iter().enumerate() {
                kx[(da, db)] += e.df_dx[a * p + b];
                cv[(da, db)] += e.df_dv[a * p + b];
            }
        }
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
        }
        let lower_k = -(minv * kx);
        let lower_c = -(minv * cv);
        a.view_mut((n, 0), (n, n)).copy_from(&lower_k);
        a.view_mut((n, n), (n, n)).copy_from(&lower_c);
        a
    }
}

impl StabilityMethod for VariationalFloquet {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        let n = system.n_mech();
        let minv = inverse_mass(system, orbit.omega());
        let period = orbit.period();
        let dt = period / self.steps as f64;
        let mut phi = DMatrix::<f64>::identity(2 * n, 2 * n);
        let mut t = 0.0;
        for _ in 0..self.steps {
            let a1 = self.jac(system, orbit, t, &minv);
            let a2 = self.jac(system, orbit, t + 0.5 * dt, &minv);
            let a4 = self.jac(system, orbit, t + dt, &minv);
            let k1 = &a1 * &phi;
            let k2 = &a2 * (&phi + &k1 * (0.5 * dt));
            let k3 = &a2 * (&phi + &k2 * (0.5 * dt));
            let k4 = &a4 * (&phi + &k3 * dt);
            phi += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
            t += dt;
        }
        if phi.iter().any(|v| !v.is_finite()) {
            return Err(StabilityError::NonFinite {
                omega: orbit.omega(),
            });
        }
        Ok(FloquetResult::new(
            phi.complex_eigenvalues().iter().copied().collect(),
        ))
    }
}

/// NLvib's two-mass contact benchmark (`systems::contact`, or the same equations from a
/// model file) continued as published: H = 21, Ω from 0.8 down to 0.5, stability by
/// shooting, the contact force integrated exactly between its switching instants
/// (`hb::events`, the default for a system with switching functions). Asserts: no
/// saddle-node but the two folds (no sampling artefacts), at most 200 points, the folds at
/// the published 0.6534401 and 0.755664 and the Neimark–Sacker point at 0.618354. Returns
/// the branch and the indices of the two folds' points.
///
/// The upper fold's tolerance is 5e-5: the published value comes from a sampled AFT and
/// carries its sampling error. Sampled with 1024 points the fold lies at 0.7556594, with
/// 4096 at 0.7556281, and with 16384 the artefact folds climb to 0.7556310; integrated
/// exactly it is 0.7556310 (docs/validation.md).
pub fn contact_benchmark(system: &dyn System) -> (tmrotor::continuation::Branch, [usize; 2]) {
    use tmrotor::continuation::{Continuation, ContinuationOptions};
    use tmrotor::hb::{Basis, HarmonicBalance};
    use tmrotor::stability::{BifurcationKind, Shooting};
    use tmrotor::systems::contact::UnilateralContact;

    let basis = Basis::integer(21).expect("basis");
    let hb = HarmonicBalance::new(system, &basis, Some(1024)).expect("hb");
    assert!(hb.event_refinement(), "the contact is integrated exactly");
    let (w0, w1) = UnilateralContact::OMEGA_RANGE;
    let mut opts = ContinuationOptions::new(w0, w1);
    opts.ds_max = 0.3;
    let method = Shooting::default();
    let mut cont = Continuation::new(hb, opts, Some(&method)).expect("continuation");
    let branch = cont.run(|_| {}).expect("run");
    assert!(branch.points.len() <= 200, "{} points", branch.points.len());
    let mut confirmed: Vec<(f64, usize)> = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::SaddleNode))
        .map(|b| (b.solution.omega, b.index))
        .collect();
    confirmed.sort_by_key(|c| c.1);
    let mut folds: Vec<f64> = confirmed.iter().map(|c| c.0).collect();
    folds.sort_by(f64::total_cmp);
    assert_eq!(folds.len(), 2, "folds {folds:?}");
    assert!((folds[0] - 0.6534401).abs() < 1e-6, "{folds:?}");
    assert!((folds[1] - 0.755664).abs() < 5e-5, "{folds:?}");
    let ns: Vec<f64> = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::NeimarkSacker))
        .map(|b| b.solution.omega)
        .collect();
    assert!(
        ns.iter().any(|w| (w - 0.618354).abs() < 5e-4),
        "Neimark–Sacker points {ns:?}"
    );
    let indices = [confirmed[0].1, confirmed[1].1];
    (branch, indices)
}
