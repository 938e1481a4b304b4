//! Variational equations `Φ̇ = B(t) Φ` (paper Eq. 30 in physical time) integrated with
//! [`Dopri5`], along a given orbit or together with the state.
//!
//! The matrix ODE is integrated as one vector of `d²` entries (column-major `Φ`), so the
//! step-size control sees every column: the monodromy matrix is accurate to about `rtol`
//! relative to its largest entries. Each right-hand side is one
//! [`StateSpace::apply_linearization`] on all `d` columns at once.

use faer::{Mat, MatMut, MatRef};

use super::steady::check_start;
use super::{Dopri5, Dopri5Options, IntegrateError, StateSpace};
use crate::system::{NonlinearEval, PeriodicOrbit, System};

/// Monodromy matrix `Φ(P)` of the variational equations along `orbit` (time origin 0,
/// `P = orbit.period()`), by integrating `Φ̇ = B(t)Φ`, `Φ(0) = I`, with the
/// derivatives of the nonlinear terms evaluated on the orbit at every stage.
pub fn monodromy_along_orbit(
    space: &StateSpace<'_>,
    orbit: &dyn PeriodicOrbit,
    opts: &Dopri5Options,
) -> Result<Mat<f64>, IntegrateError> {
    let d = space.dim();
    let period = orbit.period();
    if !(period > 0.0 && period.is_finite()) {
        return Err(IntegrateError::Setting {
            field: "orbit period",
            value: period.to_string(),
            reason: "must be positive and finite",
        });
    }
    let mut ws = space.workspace();
    let mut derivs = ws.eval.clone();
    let (mut x, mut v, mut temp) = (
        vec![0.0; space.n_mech()],
        vec![0.0; space.n_mech()],
        vec![0.0; space.n_therm()],
    );
    let mut rhs = |t: f64, phi: &[f64], dphi: &mut [f64]| {
        orbit.state_at(t, &mut x, &mut v, &mut temp);
        space.eval_nonlinear_at(t, &x, &v, &temp, &mut ws);
        derivs.clone_from(&ws.eval);
        let w = MatRef::from_column_major_slice(phi, d, d);
        let out = MatMut::from_column_major_slice_mut(dphi, d, d);
        space.apply_linearization(&derivs, w, out, &mut ws);
    };
    let mut phi = identity_flat(d);
    let mut solver = Dopri5::new(d * d, *opts);
    solver.integrate(&mut rhs, 0.0, &mut phi, period)?;
    Ok(MatRef::from_column_major_slice(&phi, d, d).to_owned())
}

/// State and sensitivity after integrating over `[t0, t0 + duration]`.
#[derive(Clone, Debug)]
pub struct FlowSensitivity {
    /// `y(t0 + duration)`.
    pub y: Vec<f64>,
    /// `∂y(t0 + duration) / ∂y(t0)`.
    pub phi: Mat<f64>,
}

/// Integrates the state from `y0` at `t0` over `duration` together with its sensitivity
/// to `y0` (the variational equations along the computed trajectory).
pub fn flow_with_sensitivity(
    space: &StateSpace<'_>,
    t0: f64,
    y0: &[f64],
    duration: f64,
    opts: &Dopri5Options,
) -> Result<FlowSensitivity, IntegrateError> {
    let d = space.dim();
    check_start(d, y0, duration)?;
    let mut ws = space.workspace();
    let mut derivs: NonlinearEval = ws.eval.clone();
    let mut rhs = |t: f64, z: &[f64], dz: &mut [f64]| {
        let (y, phi) = z.split_at(d);
        let (dy, dphi) = dz.split_at_mut(d);
        space.rhs(t, y, dy, &mut ws);
        derivs.clone_from(&ws.eval);
        let w = MatRef::from_column_major_slice(phi, d, d);
        let out = MatMut::from_column_major_slice_mut(dphi, d, d);
        space.apply_linearization(&derivs, w, out, &mut ws);
    };
    let mut z = y0.to_vec();
    z.extend(identity_flat(d));
    let mut solver = Dopri5::new(d + d * d, *opts);
    solver.integrate(&mut rhs, t0, &mut z, t0 + duration)?;
    Ok(FlowSensitivity {
        y: z[..d].to_vec(),
        phi: MatRef::from_column_major_slice(&z[d..], d, d).to_owned(),
    })
}

/// The state after integrating from `y0` at `t0` over `duration`, without sensitivities.
fn flow(
    space: &StateSpace<'_>,
    t0: f64,
    y0: &[f64],
    duration: f64,
    opts: &Dopri5Options,
) -> Result<Vec<f64>, IntegrateError> {
    check_start(space.dim(), y0, duration)?;
    let mut ws = space.workspace();
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| space.rhs(t, y, dy, &mut ws);
    let mut y = y0.to_vec();
    Dopri5::new(space.dim(), *opts).integrate(&mut rhs, t0, &mut y, t0 + duration)?;
    Ok(y)
}

/// Settings of [`shoot_periodic`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShootingOptions {
    /// Integrator settings (default [`Dopri5Options::default`]).
    pub integrator: Dopri5Options,
    /// Convergence: `‖y(P) − y(0)‖_∞ ≤ tol·(1 + ‖y(0)‖_∞)`. Default 1e-10 (just above the
    /// integrator's accuracy at `rtol = 1e-10`).
    pub tol: f64,
    /// Newton iterations. Default 30.
    pub max_iterations: usize,
}

impl Default for ShootingOptions {
    fn default() -> Self {
        Self {
            integrator: Dopri5Options::default(),
            tol: 1e-10,
            max_iterations: 30,
        }
    }
}

/// The loosest integrator tolerance [`shoot_periodic`] starts with.
const LOOSE_RTOL: f64 = 1e-6;

/// A loose residual below this many times the loose tolerance is that integration's own
/// error: the start is measured again at the full tolerance before any step.
const START_CONVERGED: f64 = 10.0;

/// A `period`-periodic solution of `system` at `omega` by Newton's method on
/// `y(P; y0) − y0 = 0` (single shooting from `t = 0`), started from `y0`. Finds stable and
/// unstable orbits alike. Returns the initial state of the orbit and the monodromy matrix
/// at the converged point. Converged: a residual or a Newton correction below
/// [`ShootingOptions::tol`] (the latter spares the integration that would only confirm it).
///
/// The first Newton step is inexact: a start taken from a truncated harmonic balance lies
/// about 1e-3 from the orbit, so the first integration runs at [`LOOSE_RTOL`] (about a
/// quarter of the steps at 1e-10; the step it gives leaves an error of about `‖r‖²`, far
/// above its integration error). A start whose loose residual is already at that
/// integration's own error level is measured again at the full tolerance before any step;
/// the loose look integrates the state alone first, and the sensitivities only where the
/// start needs a step. Every later integration, the convergence test and the returned
/// monodromy use the full tolerance.
pub fn shoot_periodic(
    system: &dyn System,
    omega: f64,
    y0: &[f64],
    period: f64,
    opts: &ShootingOptions,
) -> Result<FlowSensitivity, IntegrateError> {
    shoot_periodic_segments(system, omega, &[y0.to_vec()], period, opts)
}

/// [`shoot_periodic`] by multiple shooting: the period split into `starts.len()` equal
/// segments, segment `k` from `t_k = kP/S` started from `starts[k]` (e.g. the states of a
/// harmonic-balance orbit there), integrated in parallel. Newton solves
/// `y_k(t_{k+1}; y_k) − y_{k+1} = 0` (indices mod S) for all the segments' starts at once;
/// the monodromy is the product of the segments' sensitivities, `Φ_{S−1} ⋯ Φ_0`, and the
/// returned state the orbit's at `t = 0`. With one segment this is single shooting.
pub fn shoot_periodic_segments(
    system: &dyn System,
    omega: f64,
    starts: &[Vec<f64>],
    period: f64,
    opts: &ShootingOptions,
) -> Result<FlowSensitivity, IntegrateError> {
    use faer::linalg::solvers::Solve;
    use rayon::prelude::*;
    let space = StateSpace::new(system, omega)?;
    let d = space.dim();
    let n_seg = starts.len();
    if let Some(found) = starts
        .iter()
        .map(Vec::len)
        .find(|&l| l != d)
        .or((n_seg == 0).then_some(0))
    {
        return Err(IntegrateError::Dimension {
            what: "shooting segment start",
            expected: d,
            found,
        });
    }
    let h = period / n_seg as f64;
    let full = opts.integrator;
    let mut ys: Vec<Vec<f64>> = starts.to_vec();
    let mut residual = f64::INFINITY;
    // the next integration's relative tolerance
    let mut rtol = LOOSE_RTOL.max(full.rtol);
    let monodromy = |flows: &[FlowSensitivity]| {
        let mut phi = flows[0].phi.clone();
        for f in &flows[1..] {
            phi = &f.phi * &phi;
        }
        phi
    };
    for _ in 0..opts.max_iterations {
        let integrator = Dopri5Options {
            rtol,
            atol: full.atol * rtol / full.rtol,
            ..full
        };
        let exact = rtol <= full.rtol;
        let scale = 1.0 + ys.iter().map(|y| max_abs(y)).fold(0.0, f64::max);
        if !exact {
            // the loose look first without the sensitivities (a fifth of the equations of
            // a small system): a start already at that integration's own error (a well
            // resolved balance) needs none of them, only the measurement below
            let ends: Vec<Vec<f64>> = ys
                .par_iter()
                .enumerate()
                .map(|(k, y)| flow(&space, k as f64 * h, y, h, &integrator))
                .collect::<Result<_, _>>()?;
            residual = max_abs(&gaps(&ys, |k| &ends[k]));
            if residual <= START_CONVERGED * integrator.rtol * scale {
                rtol = full.rtol;
                continue;
            }
        }
        let flows: Vec<FlowSensitivity> = ys
            .par_iter()
            .enumerate()
            .map(|(k, y)| flow_with_sensitivity(&space, k as f64 * h, y, h, &integrator))
            .collect::<Result<_, _>>()?;
        let r = gaps(&ys, |k| &flows[k].y);
        residual = max_abs(&r);
        if exact && residual <= opts.tol * scale {
            return Ok(FlowSensitivity {
                phi: monodromy(&flows),
                y: ys.swap_remove(0),
            });
        }
        // every later integration at the full tolerance (the next residual is about the
        // square of this one, and the step it gives is only as good as its measurement)
        rtol = full.rtol;
        if !exact && residual <= START_CONVERGED * integrator.rtol * scale {
            // the residual is the loose integration's own error: measure it properly
            continue;
        }
        // ∂r_k/∂y_k = Φ_k, ∂r_k/∂y_{k+1} = −I
        let n = n_seg * d;
        let mut jac = Mat::<f64>::zeros(n, n);
        for k in 0..n_seg {
            let next = (k + 1) % n_seg;
            for i in 0..d {
                for j in 0..d {
                    jac[(k * d + i, k * d + j)] += flows[k].phi[(i, j)];
                }
                jac[(k * d + i, next * d + i)] -= 1.0;
            }
        }
        let rhs = Mat::from_fn(n, 1, |i, _| -r[i]);
        let delta = jac.partial_piv_lu().solve(rhs);
        let mut step = 0.0f64;
        for k in 0..n_seg {
            for i in 0..d {
                ys[k][i] += delta[(k * d + i, 0)];
                step = step.max(delta[(k * d + i, 0)].abs());
            }
        }
        if ys.iter().flatten().any(|v| !v.is_finite()) {
            break;
        }
        // a Newton correction below the tolerance: the corrected states are converged (the
        // next residual would be of the order of its square), and the monodromy at the
        // states before it differs from the one after by O(correction) ≤ tol
        if exact && step <= opts.tol * scale {
            let phi = monodromy(&flows);
            return Ok(FlowSensitivity {
                y: ys.swap_remove(0),
                phi,
            });
        }
    }
    Err(IntegrateError::Shooting {
        iterations: opts.max_iterations,
        residual,
    })
}

/// The multiple-shooting residual `r_k = y_k(t_{k+1}) − y_{k+1}` (indices mod the number
/// of segments) of segment starts `ys` whose ends are `end(k)`.
fn gaps<'e>(ys: &[Vec<f64>], end: impl Fn(usize) -> &'e [f64]) -> Vec<f64> {
    let n = ys.len();
    (0..n)
        .flat_map(|k| {
            let next = &ys[(k + 1) % n];
            end(k)
                .iter()
                .zip(next)
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>()
        })
        .collect()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn identity_flat(d: usize) -> Vec<f64> {
    let mut phi = vec![0.0; d * d];
    for i in 0..d {
        phi[i * d + i] = 1.0;
    }
    phi
}
