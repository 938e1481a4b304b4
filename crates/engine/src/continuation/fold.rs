//! Fold curves in two parameters: continuation of the saddle-node points of the
//! harmonic-balance branch in the rotor speed ω and a second parameter `p` (a flow rate, a
//! forcing amplitude, a damping ratio, …).
//!
//! Method: the minimally augmented system (Govaerts, *Numerical Methods for Bifurcations of
//! Dynamical Equilibria*, SIAM 2000, ch. 4; the fold continuation of MatCont and
//! BifurcationKit). At a fold of the ω-branch the Jacobian `J = ∂R/∂A` of the
//! harmonic-balance residual is singular. With bordering vectors `b`, `c` the bordered
//! system
//!
//! ```text
//! [ J   b ] [ v ]   [ 0 ]            [ Jᵀ  c ] [ w ]   [ 0 ]
//! [ cᵀ  0 ] [ g ] = [ 1 ]    and     [ bᵀ  0 ] [ h ] = [ 1 ]
//! ```
//!
//! defines a scalar `g(A, ω, p)` that vanishes exactly where `J` is singular, with
//! `v` and `w` its right and left null vectors there. The fold curve is the solution set of
//! `F(A, ω, p) = [R(A, ω; p); g(A, ω, p)] = 0`, `N + 1` equations in `N + 2` unknowns,
//! followed by pseudo-arclength continuation. The derivatives of `g` are
//! `∂g/∂z = −wᵀ (∂J/∂z) v`: along `A` from the Jacobian at `A ± εv` (the symmetry of the
//! second derivative: `Σ_k wᵢ ∂J_ij/∂A_k v_j` row `k` is `(∂J/∂ε (A + εv))ᵀ w`), along ω
//! and `p` from the Jacobian at `ω ± h`, `p ± h`; `∂R/∂p` is a central difference of the
//! residual of the systems at `p ± h`. The bordering vectors are the null vectors of the
//! previous point, so the bordered matrices stay well conditioned along the curve.
//!
//! A cusp, where a pair of folds is born or dies, is where the curve's projection onto
//! (ω, p) reverses: the ω- and `p`-components of the unit tangent change sign together.
//! Its arclength is where the linear interpolation of `dp/ds` vanishes, its (ω, p) the
//! quadratics through the three points around the sign change evaluated there.
//!
//! The second parameter enters through a [`Family`]: the system at each value of `p`.

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::ContinuationError;
use crate::hb::{Basis, HarmonicBalance};
use crate::system::System;

/// A one-parameter family of systems: the system at parameter value `p`.
pub trait Family: Sync {
    /// The system at `p`; an error names why `p` is not admissible.
    fn at(&self, p: f64) -> Result<Box<dyn System + '_>, String>;
}

impl<F, S> Family for F
where
    F: Fn(f64) -> Result<S, String> + Sync,
    S: System + 'static,
{
    fn at(&self, p: f64) -> Result<Box<dyn System + '_>, String> {
        Ok(Box::new(self(p)?))
    }
}

/// Settings of a fold-curve continuation.
#[derive(Clone, Debug, PartialEq)]
pub struct FoldOptions {
    /// Range of the second parameter; the curve stops where it leaves it.
    pub p_range: (f64, f64),
    /// Range of ω; the curve stops where it leaves it.
    pub omega_range: (f64, f64),
    /// Scales of ω and `p` in the arclength (the coefficients are scaled by the start
    /// point's largest one): a step of `ds` moves about `ds` of each scale.
    pub omega_scale: f64,
    pub p_scale: f64,
    /// Initial, smallest and largest step (scaled arclength).
    pub ds: f64,
    pub ds_min: f64,
    pub ds_max: f64,
    /// Maximum number of points.
    pub max_points: usize,
    /// Newton tolerance on the scaled correction.
    pub tol: f64,
    /// Newton iterations per step.
    pub max_iterations: usize,
    /// AFT samples per period (`None`: chosen from the basis).
    pub aft_samples: Option<usize>,
}

impl FoldOptions {
    /// Options for `p` in `p_range` and ω in `omega_range`, scales from the ranges' widths.
    pub fn new(p_range: (f64, f64), omega_range: (f64, f64)) -> Self {
        Self {
            p_range,
            omega_range,
            omega_scale: (omega_range.1 - omega_range.0).abs().max(1e-12),
            p_scale: (p_range.1 - p_range.0).abs().max(1e-12),
            ds: 0.01,
            ds_min: 1e-6,
            ds_max: 0.05,
            max_points: 2000,
            tol: 1e-10,
            max_iterations: 12,
            aft_samples: None,
        }
    }
}

/// One point of a fold curve.
#[derive(Clone, Debug, PartialEq)]
pub struct FoldPoint {
    pub omega: f64,
    pub p: f64,
    /// Harmonic-balance unknowns (mechanical, then thermal coefficients).
    pub unknowns: Vec<f64>,
    /// Scaled arclength from the start.
    pub arclength: f64,
    /// `dp/ds` and `dω/ds` of the unit tangent (scaled).
    pub dp_ds: f64,
    pub domega_ds: f64,
}

/// A cusp: where two fold curves meet and the fold pair is born or dies.
#[derive(Clone, Debug, PartialEq)]
pub struct Cusp {
    pub omega: f64,
    pub p: f64,
    /// Index of the curve point after it.
    pub after: usize,
}

/// Why a fold curve ended.
#[derive(Clone, Debug, PartialEq)]
pub enum FoldFinish {
    /// Left the parameter or speed range.
    LeftRange,
    MaxPoints,
    /// The step fell below `ds_min` (the corrector failed there).
    StepTooSmall {
        omega: f64,
        p: f64,
    },
}

/// A traced fold curve.
#[derive(Clone, Debug)]
pub struct FoldCurve {
    pub points: Vec<FoldPoint>,
    pub cusps: Vec<Cusp>,
    pub finish: FoldFinish,
}

impl FoldCurve {
    /// ω where the curve crosses the parameter value `p`, each crossing interpolated
    /// linearly between its two points, sorted.
    pub fn omegas_at(&self, p: f64) -> Vec<f64> {
        let mut out: Vec<f64> = self
            .points
            .windows(2)
            .filter(|w| (w[0].p - p) * (w[1].p - p) <= 0.0 && w[0].p != w[1].p)
            .map(|w| {
                let t = (p - w[0].p) / (w[1].p - w[0].p);
                w[0].omega + t * (w[1].omega - w[0].omega)
            })
            .collect();
        out.sort_by(f64::total_cmp);
        out.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        out
    }
}

/// The extended problem `F(A, ω, p)` on one basis.
struct Extended<'f> {
    family: &'f dyn Family,
    basis: Basis,
    aft_samples: Option<usize>,
    /// Scales of the unknowns: coefficients, ω, p.
    scale: Vec<f64>,
}

/// The parts of `F` and its Jacobian at one point.
struct Evaluation {
    /// `[R; g]`.
    f: Vec<f64>,
    /// `∂F/∂(A, ω, p)`, `(N+1) × (N+2)`, in unscaled unknowns.
    jac: Mat<f64>,
    /// Right and left null vectors (normalised, for the next bordering).
    v: Vec<f64>,
    w: Vec<f64>,
}

/// `x` divided by its 2-norm.
fn unit(x: Vec<f64>) -> Vec<f64> {
    let s = x.iter().map(|y| y * y).sum::<f64>().sqrt();
    x.into_iter().map(|y| y / s).collect()
}

fn err(what: impl Into<String>) -> ContinuationError {
    ContinuationError::Fold(what.into())
}

impl Extended<'_> {
    fn n(&self) -> usize {
        self.scale.len() - 2
    }

    fn hb<'s>(&self, system: &'s dyn System) -> Result<HarmonicBalance<'s>, ContinuationError> {
        Ok(HarmonicBalance::new(system, &self.basis, self.aft_samples)?)
    }

    fn system(&self, p: f64) -> Result<Box<dyn System + '_>, ContinuationError> {
        self.family
            .at(p)
            .map_err(|e| err(format!("parameter {p}: {e}")))
    }

    /// Dense `∂R/∂A` and `R` at `(a, ω)`.
    fn jacobian(
        &self,
        hb: &HarmonicBalance,
        a: &[f64],
        omega: f64,
    ) -> Result<(Mat<f64>, Vec<f64>), ContinuationError> {
        let n = self.n();
        let mut r = vec![0.0; n];
        let parts = hb.residual_jacobian(a, omega, &mut r)?;
        let dense = hb.dense_jacobian(&parts);
        Ok((Mat::from_fn(n, n, |i, j| dense[i * n + j]), r))
    }

    /// The bordered solves: `(v, g)` and `w`.
    fn bordered(
        j: &Mat<f64>,
        b: &[f64],
        c: &[f64],
    ) -> Result<(Vec<f64>, f64, Vec<f64>), ContinuationError> {
        let n = j.nrows();
        let m = Mat::from_fn(n + 1, n + 1, |r, k| match (r < n, k < n) {
            (true, true) => j[(r, k)],
            (true, false) => b[r],
            (false, true) => c[k],
            (false, false) => 0.0,
        });
        let lu = m.partial_piv_lu();
        let e = Mat::from_fn(n + 1, 1, |r, _| if r == n { 1.0 } else { 0.0 });
        let x = lu.solve(&e);
        let y = lu.solve_transpose(&e);
        let v: Vec<f64> = (0..n).map(|r| x[(r, 0)]).collect();
        let w: Vec<f64> = (0..n).map(|r| y[(r, 0)]).collect();
        let g = x[(n, 0)];
        if !g.is_finite() || v.iter().chain(&w).any(|x| !x.is_finite()) {
            return Err(err("singular bordered matrix"));
        }
        Ok((v, g, w))
    }

    /// `wᵀ J v` for the Jacobian at `(a, ω)`, applied without assembling it.
    fn wjv(
        &self,
        hb: &HarmonicBalance,
        a: &[f64],
        omega: f64,
        v: &[f64],
        w: &[f64],
    ) -> Result<f64, ContinuationError> {
        let n = self.n();
        let mut r = vec![0.0; n];
        let parts = hb.residual_jacobian(a, omega, &mut r)?;
        let mut jv = vec![0.0; n];
        hb.apply_jacobian(&parts, v, &mut jv);
        Ok(w.iter().zip(&jv).map(|(x, y)| x * y).sum())
    }

    /// `F` and its Jacobian at `z = (A, ω, p)`, bordered by `(b, c)`.
    fn evaluate(&self, z: &[f64], b: &[f64], c: &[f64]) -> Result<Evaluation, ContinuationError> {
        let n = self.n();
        let (a, omega, p) = (&z[..n], z[n], z[n + 1]);
        let system = self.system(p)?;
        let hb = self.hb(&*system)?;
        let (j, r) = self.jacobian(&hb, a, omega)?;
        let (v, g, w) = Self::bordered(&j, b, c)?;
        let mut r_omega = vec![0.0; n];
        hb.d_residual_d_omega(a, omega, &mut r_omega)?;

        // ∂R/∂p and ∂g/∂p: central differences over the family.
        let hp = 1e-6 * self.scale[n + 1];
        let (sp, sm) = (self.system(p + hp)?, self.system(p - hp)?);
        let (hbp, hbm) = (self.hb(&*sp)?, self.hb(&*sm)?);
        let mut rp = vec![0.0; n];
        let mut rm = vec![0.0; n];
        hbp.residual(a, omega, &mut rp)?;
        hbm.residual(a, omega, &mut rm)?;
        let r_p: Vec<f64> = rp
            .iter()
            .zip(&rm)
            .map(|(x, y)| (x - y) / (2.0 * hp))
            .collect();
        let g_p =
            -(self.wjv(&hbp, a, omega, &v, &w)? - self.wjv(&hbm, a, omega, &v, &w)?) / (2.0 * hp);
        // ∂g/∂ω
        let ho = 1e-6 * omega.abs().max(1e-6);
        let g_omega = -(self.wjv(&hb, a, omega + ho, &v, &w)?
            - self.wjv(&hb, a, omega - ho, &v, &w)?)
            / (2.0 * ho);
        // ∂g/∂A = −(∂/∂ε J(A + εv))ᵀ w
        let vnorm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let anorm = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
        let eps = 1e-6 * anorm / vnorm.max(1e-300);
        let shifted = |s: f64| -> Vec<f64> { a.iter().zip(&v).map(|(x, y)| x + s * y).collect() };
        let (jp, _) = self.jacobian(&hb, &shifted(eps), omega)?;
        let (jm, _) = self.jacobian(&hb, &shifted(-eps), omega)?;
        let g_a: Vec<f64> = (0..n)
            .map(|k| {
                -(0..n)
                    .map(|r| w[r] * (jp[(r, k)] - jm[(r, k)]))
                    .sum::<f64>()
                    / (2.0 * eps)
            })
            .collect();

        let jac = Mat::from_fn(n + 1, n + 2, |row, col| {
            if row < n {
                match col {
                    k if k < n => j[(row, k)],
                    k if k == n => r_omega[row],
                    _ => r_p[row],
                }
            } else {
                match col {
                    k if k < n => g_a[k],
                    k if k == n => g_omega,
                    _ => g_p,
                }
            }
        });
        let mut f = r;
        f.push(g);
        Ok(Evaluation {
            f,
            jac,
            v: unit(v),
            w: unit(w),
        })
    }

    /// Unit tangent (scaled unknowns) of the curve: the null vector of the scaled
    /// Jacobian, oriented along `prev`.
    fn tangent(&self, jac: &Mat<f64>, prev: &[f64]) -> Result<Vec<f64>, ContinuationError> {
        let n1 = jac.nrows();
        let m = Mat::from_fn(n1 + 1, n1 + 1, |r, k| {
            if r < n1 {
                jac[(r, k)] * self.scale[k]
            } else {
                prev[k]
            }
        });
        let e = Mat::from_fn(n1 + 1, 1, |r, _| if r == n1 { 1.0 } else { 0.0 });
        let t = m.partial_piv_lu().solve(&e);
        let t: Vec<f64> = (0..=n1).map(|r| t[(r, 0)]).collect();
        let s = t.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(s.is_finite() && s > 0.0) {
            return Err(err("no tangent (the curve is singular here)"));
        }
        Ok(t.into_iter().map(|x| x / s).collect())
    }

    /// Newton on `F(z) = 0` with `tᵀ (z − z_pred)/scale = 0`; returns the point, its
    /// evaluation and the iterations.
    fn correct(
        &self,
        mut z: Vec<f64>,
        t: &[f64],
        b: &[f64],
        c: &[f64],
        opts: &FoldOptions,
    ) -> Result<(Vec<f64>, Evaluation), ContinuationError> {
        let n2 = z.len();
        let pred = z.clone();
        for _ in 0..opts.max_iterations {
            let ev = self.evaluate(&z, b, c)?;
            let n1 = n2 - 1;
            let m = Mat::from_fn(n2, n2, |r, k| {
                if r < n1 {
                    ev.jac[(r, k)] * self.scale[k]
                } else {
                    t[k]
                }
            });
            let rhs = Mat::from_fn(n2, 1, |r, _| {
                if r < n1 {
                    -ev.f[r]
                } else {
                    -(0..n2)
                        .map(|k| t[k] * (z[k] - pred[k]) / self.scale[k])
                        .sum::<f64>()
                }
            });
            let dx = m.partial_piv_lu().solve(&rhs);
            let mut size = 0.0f64;
            for k in 0..n2 {
                let d = dx[(k, 0)];
                if !d.is_finite() {
                    return Err(err("corrector diverged"));
                }
                z[k] += d * self.scale[k];
                size = size.max(d.abs());
            }
            if size < opts.tol {
                let ev = self.evaluate(&z, b, c)?;
                return Ok((z, ev));
            }
        }
        Err(err("corrector did not converge"))
    }
}

/// Continues the fold curve through the saddle-node `(a0, ω0)` of the branch at `p0`
/// (from a one-parameter sweep, e.g. a located bifurcation point's unknowns), in both
/// directions, until it leaves the ranges of `opts`. The points run from one end to the
/// other through the start.
pub fn continue_fold(
    family: &dyn Family,
    basis: &Basis,
    a0: &[f64],
    omega0: f64,
    p0: f64,
    opts: &FoldOptions,
) -> Result<FoldCurve, ContinuationError> {
    let n = a0.len();
    let a_scale = a0.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
    let mut scale = vec![a_scale; n];
    scale.push(opts.omega_scale);
    scale.push(opts.p_scale);
    let ext = Extended {
        family,
        basis: basis.clone(),
        aft_samples: opts.aft_samples,
        scale,
    };
    // Bordering from the start point's Jacobian: its smallest singular direction
    // approximated by one inverse iteration from a generic vector.
    let system = ext.system(p0)?;
    let (j0, _) = ext.jacobian(&ext.hb(&*system)?, a0, omega0)?;
    drop(system);
    let generic: Vec<f64> = (0..n).map(|k| 1.0 + 0.1 * k as f64).collect();
    let (v, _, w) = Extended::bordered(&j0, &generic, &generic)?;
    let (b, c) = (unit(w), unit(v));
    // Correct onto the curve at fixed p (the tangent constraint along p only).
    let mut z: Vec<f64> = a0.to_vec();
    z.push(omega0);
    z.push(p0);
    let mut along_p = vec![0.0; n + 2];
    along_p[n + 1] = 1.0;
    let (z0, ev0) = ext.correct(z, &along_p, &b, &c, opts)?;
    let t0 = {
        let mut guess = vec![0.0; n + 2];
        guess[n + 1] = 1.0;
        ext.tangent(&ev0.jac, &guess)?
    };

    let forward = trace(&ext, &z0, &ev0, t0.clone(), opts)?;
    let backward = trace(&ext, &z0, &ev0, t0.iter().map(|x| -x).collect(), opts)?;
    // One curve from the far end of the backward half through the start.
    let mut points: Vec<FoldPoint> = backward
        .0
        .into_iter()
        .skip(1)
        .rev()
        .map(|mut q| {
            q.arclength = -q.arclength;
            q.dp_ds = -q.dp_ds;
            q.domega_ds = -q.domega_ds;
            q
        })
        .collect();
    points.extend(forward.0);
    let finish = match backward.1 {
        f @ FoldFinish::StepTooSmall { .. } => f,
        _ => forward.1,
    };
    let cusps = cusps(&points);
    Ok(FoldCurve {
        points,
        cusps,
        finish,
    })
}

/// One direction of the curve from the corrected start `z0`.
fn trace(
    ext: &Extended,
    z0: &[f64],
    ev0: &Evaluation,
    t0: Vec<f64>,
    opts: &FoldOptions,
) -> Result<(Vec<FoldPoint>, FoldFinish), ContinuationError> {
    let n = ext.n();
    let point = |z: &[f64], s: f64, t: &[f64]| FoldPoint {
        omega: z[n],
        p: z[n + 1],
        unknowns: z[..n].to_vec(),
        arclength: s,
        dp_ds: t[n + 1],
        domega_ds: t[n],
    };
    let inside = |z: &[f64]| {
        let (lo, hi) = (
            opts.p_range.0.min(opts.p_range.1),
            opts.p_range.0.max(opts.p_range.1),
        );
        let (wlo, whi) = (
            opts.omega_range.0.min(opts.omega_range.1),
            opts.omega_range.0.max(opts.omega_range.1),
        );
        (lo..=hi).contains(&z[n + 1]) && (wlo..=whi).contains(&z[n])
    };
    let mut points = vec![point(z0, 0.0, &t0)];
    let mut z = z0.to_vec();
    let mut t = t0;
    let (mut b, mut c) = (ev0.w.clone(), ev0.v.clone());
    let mut ds = opts.ds;
    let mut s = 0.0;
    while points.len() < opts.max_points {
        let pred: Vec<f64> = (0..n + 2)
            .map(|k| z[k] + ds * t[k] * ext.scale[k])
            .collect();
        match ext.correct(pred, &t, &b, &c, opts) {
            Ok((zn, ev)) => {
                let tn = ext.tangent(&ev.jac, &t)?;
                s += ds;
                let left = !inside(&zn);
                points.push(point(&zn, s, &tn));
                if left {
                    return Ok((points, FoldFinish::LeftRange));
                }
                z = zn;
                t = tn;
                b = ev.w;
                c = ev.v;
                ds = (ds * 1.5).min(opts.ds_max);
            }
            Err(_) if ds > opts.ds_min => ds *= 0.5,
            Err(_) => {
                return Ok((
                    points,
                    FoldFinish::StepTooSmall {
                        omega: z[n],
                        p: z[n + 1],
                    },
                ));
            }
        }
    }
    Ok((points, FoldFinish::MaxPoints))
}

/// The cusps of a curve: where `dp/ds` and `dω/ds` change sign together, located on the quadratic `p(s)`
/// through the three points around the change (its vertex), ω from the quadratic `ω(s)`.
fn cusps(points: &[FoldPoint]) -> Vec<Cusp> {
    let mut out = Vec::new();
    for i in 1..points.len() {
        let (a, b) = (&points[i - 1], &points[i]);
        // the projection onto (ω, p) reverses: both components of the tangent change sign
        // (a turn in p alone is a fold of the fold curve, not a cusp)
        if a.dp_ds * b.dp_ds >= 0.0 || a.domega_ds * b.domega_ds >= 0.0 {
            continue;
        }
        // the three points: i-1, i and the neighbour on the side of the larger |dp/ds|
        let k = if i + 1 < points.len() {
            i + 1
        } else {
            i.saturating_sub(2)
        };
        let tri = [&points[i - 1], &points[i], &points[k]];
        let fit = |y: &dyn Fn(&FoldPoint) -> f64, s: f64| {
            let (s0, s1, s2) = (tri[0].arclength, tri[1].arclength, tri[2].arclength);
            let (y0, y1, y2) = (y(tri[0]), y(tri[1]), y(tri[2]));
            let l0 = (s - s1) * (s - s2) / ((s0 - s1) * (s0 - s2));
            let l1 = (s - s0) * (s - s2) / ((s1 - s0) * (s1 - s2));
            let l2 = (s - s0) * (s - s1) / ((s2 - s0) * (s2 - s1));
            y0 * l0 + y1 * l1 + y2 * l2
        };
        // dp/ds is linear between the two points: its zero
        let theta = a.dp_ds / (a.dp_ds - b.dp_ds);
        let s = a.arclength + theta * (b.arclength - a.arclength);
        let p = fit(&|q: &FoldPoint| q.p, s);
        let omega = fit(&|q: &FoldPoint| q.omega, s);
        out.push(Cusp { omega, p, after: i });
    }
    out
}
