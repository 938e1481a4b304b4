//! Branch switching at a period doubling: from a located period-doubling point of a
//! branch, a start on the period-doubled branch that bifurcates there.
//!
//! Method. At a period doubling of a `T`-periodic orbit a Floquet multiplier is −1: the
//! linearisation has a solution with `p(t + T) = −p(t)`, made of the odd multiples of
//! half the orbit's fundamental frequency `ν₀/2`. The `T`-periodic basis has no such
//! harmonics, so the branch does not see the bifurcation. [`doubled_basis`] adds, for
//! every harmonic `h` of the basis, `h − ν₀/2` and `h + ν₀/2`; in that basis the
//! `T`-periodic solution is the same (its new coefficients are zero), and the
//! harmonic-balance Jacobian `∂R/∂A` at the period doubling is singular, its null vector
//! the half-order mode. By the symmetry `t → t + T` the Jacobian does not couple the
//! orbit's own harmonics with the new ones, so the null vector is found by inverse
//! iteration on the new coefficients. The period-doubled branch leaves the bifurcation
//! tangent to that mode with an amplitude growing as `√|ω − ω_PD|` (Kuznetsov,
//! *Elements of Applied Bifurcation Theory*, 3rd ed., Springer 2004, §4.4; Seydel,
//! *Practical Bifurcation and Stability Analysis*, 3rd ed., Springer 2010, §7.6). The start
//! is a Newton solve on `(A, ω)` with the projection of `A` on the mode fixed at a small
//! amplitude `ε` (ω free; Seydel §5.6's parametrisation by the bifurcating direction):
//! the `T`-periodic branch has no projection on the mode, so the solve cannot fall back
//! onto it, and the side of `ω_PD` the doubled branch lies on comes out of the solve.
//! `ε` is a fraction of the orbit's largest oscillating coefficient (the constant terms,
//! static offsets or temperatures, do not measure a vibration), tried with both signs and
//! at a tenth of it.

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::ContinuationError;
use crate::hb::newton::{ArcConstraint, NewtonOptions, solve_arclength};
use crate::hb::{Basis, HarmonicBalance, HbSolution, Ratio};
use crate::system::System;

/// A start on a period-doubled branch.
#[derive(Clone, Debug)]
pub struct SwitchedStart {
    /// The doubled basis ([`doubled_basis`]).
    pub basis: Basis,
    /// Where the start was solved (rad/s).
    pub omega: f64,
    /// Harmonic-balance unknowns in the doubled basis.
    pub unknowns: Vec<f64>,
    /// Share of the half-order harmonics in the start's coefficients ([`half_order_share`]).
    pub half_order_share: f64,
}

/// Settings of [`switch_at_period_doubling`].
#[derive(Clone, Debug, PartialEq)]
pub struct SwitchOptions {
    /// Projection of the start's coefficients on the half-order mode, relative to the
    /// largest oscillating coefficient of the orbit (tried as given, then a tenth of it,
    /// with both signs).
    pub amplitude: f64,
    /// Smallest half-order share that counts as period-doubled.
    pub min_share: f64,
    /// AFT samples per period of the doubled basis (`None`: chosen from the basis).
    pub aft_samples: Option<usize>,
}

impl Default for SwitchOptions {
    fn default() -> Self {
        Self {
            amplitude: 0.05,
            min_share: 1e-4,
            aft_samples: None,
        }
    }
}

fn value(r: Ratio) -> f64 {
    f64::from(r.num) / f64::from(r.den)
}

/// The basis with, for every harmonic `h`, also `h − ν₀/2` and `h + ν₀/2` (`ν₀` the
/// fundamental of `basis`, `1/base_den` of ω), sorted by frequency.
pub fn doubled_basis(basis: &Basis) -> Result<Basis, ContinuationError> {
    let den = 2 * basis.base_den();
    let mut all: Vec<Ratio> = Vec::new();
    for h in basis.harmonics() {
        // h = m/den in the finer unit
        let m = h.num * (den / h.den);
        for k in [m.saturating_sub(1), m, m + 1] {
            if k > 0 {
                let r = reduce(k, den);
                if !all.contains(&r) {
                    all.push(r);
                }
            }
        }
    }
    all.sort_by(|a, b| value(*a).total_cmp(&value(*b)));
    Basis::new(all).map_err(|e| ContinuationError::Switch(format!("doubled basis: {e}")))
}

fn reduce(num: u32, den: u32) -> Ratio {
    let mut g = (num, den);
    while g.1 != 0 {
        g = (g.1, g.0 % g.1);
    }
    Ratio {
        num: num / g.0,
        den: den / g.0,
    }
}

/// Coefficients of `from` (layout `[a0, a_1..a_H, b_1..b_H]` per DoF) in the basis `to`,
/// which holds every harmonic of `from`; harmonics `to` adds are zero.
pub fn embed(coeffs: &[f64], from: &Basis, to: &Basis) -> Vec<f64> {
    let (nf, nt) = (from.n_coeffs(), to.n_coeffs());
    let (hf, ht) = (from.n_harmonics(), to.n_harmonics());
    let index: Vec<Option<usize>> = from
        .harmonics()
        .iter()
        .map(|h| to.harmonics().iter().position(|g| g == h))
        .collect();
    let n_dof = coeffs.len() / nf;
    let mut out = vec![0.0; n_dof * nt];
    for d in 0..n_dof {
        let (src, dst) = (
            &coeffs[d * nf..(d + 1) * nf],
            &mut out[d * nt..(d + 1) * nt],
        );
        dst[0] = src[0];
        for (k, j) in index.iter().enumerate() {
            if let Some(j) = *j {
                dst[1 + j] = src[1 + k];
                dst[1 + ht + j] = src[1 + hf + k];
            }
        }
    }
    out
}

/// The indices of the coefficients of the harmonics of `to` that `from` lacks.
fn new_coefficients(from: &Basis, to: &Basis, n_dof: usize) -> Vec<usize> {
    let (nt, ht) = (to.n_coeffs(), to.n_harmonics());
    let new: Vec<usize> = (0..ht)
        .filter(|&j| !from.harmonics().contains(&to.harmonics()[j]))
        .collect();
    (0..n_dof)
        .flat_map(|d| {
            new.iter()
                .flat_map(move |&j| [d * nt + 1 + j, d * nt + 1 + ht + j])
        })
        .collect()
}

/// 2-norm of the coefficients `half` over the 2-norm of all oscillating coefficients of
/// `a` (blocks of `nc`): the constant terms (static offsets, temperatures) are left out of
/// both, as they do not measure a vibration.
fn share_of(a: &[f64], half: &[usize], nc: usize) -> f64 {
    let h: f64 = half.iter().map(|&i| a[i] * a[i]).sum::<f64>().sqrt();
    let all: f64 = a
        .iter()
        .enumerate()
        .filter(|(i, _)| i % nc != 0)
        .map(|(_, x)| x * x)
        .sum::<f64>()
        .sqrt();
    h / all.max(1e-300)
}

/// Share of the harmonics `to` adds to `from` in the coefficients `unknowns` (basis `to`,
/// blocks of `to.n_coeffs()` per DoF): the 2-norm of those coefficients over the 2-norm
/// of all oscillating ones. On the doubled basis of a branch it is the period-doubled
/// part of a solution: zero on the branch it bifurcated from, growing as `√|ω − ω_PD|` on
/// the doubled one.
pub fn half_order_share(unknowns: &[f64], from: &Basis, to: &Basis) -> f64 {
    let nc = to.n_coeffs();
    share_of(
        unknowns,
        &new_coefficients(from, to, unknowns.len() / nc),
        nc,
    )
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// A start on the period-doubled branch at the located period doubling `pd` of a branch
/// of `system` on `basis` (see the module docs). Errors when no start with a half-order
/// part is found on either side.
pub fn switch_at_period_doubling(
    system: &dyn System,
    basis: &Basis,
    pd: &HbSolution,
    opts: &SwitchOptions,
) -> Result<SwitchedStart, ContinuationError> {
    let doubled = doubled_basis(basis)?;
    let hb = HarmonicBalance::new(system, &doubled, opts.aft_samples)?;
    let a0 = embed(&pd.unknowns(), basis, &doubled);
    let n = a0.len();
    let n_dof = n / doubled.n_coeffs();
    let half = new_coefficients(basis, &doubled, n_dof);

    // the half-order mode: inverse iteration on the new coefficients' block of the
    // Jacobian (the symmetry leaves it uncoupled from the orbit's own harmonics, so the
    // block alone has the mode; on the dual rotor's doubled basis that block is 2/3 of
    // the unknowns, about a quarter of the whole matrix's LU work)
    let mut r = vec![0.0; n];
    let parts = hb.residual_jacobian(&a0, pd.omega, &mut r)?;
    let dense = hb.dense_jacobian(&parts);
    let nh = half.len();
    let lu = Mat::from_fn(nh, nh, |i, j| dense[half[i] * n + half[j]]).partial_piv_lu();
    drop(dense);
    let mut w: Vec<f64> = (0..nh).map(|k| 1.0 + 0.37 * k as f64).collect();
    for _ in 0..4 {
        let x = lu.solve(Mat::from_fn(nh, 1, |i, _| w[i]));
        let next: Vec<f64> = (0..nh).map(|i| x[(i, 0)]).collect();
        let s = norm(&next);
        if !(s.is_finite() && s > 0.0) {
            return Err(ContinuationError::Switch(
                "no half-order mode (singular Jacobian)".into(),
            ));
        }
        w = next.into_iter().map(|y| y / s).collect();
    }
    let mut v = vec![0.0; n];
    for (k, &i) in half.iter().enumerate() {
        v[i] = w[k];
    }

    // the orbit's largest oscillating coefficient: the constant terms (a static offset,
    // or a temperature in kelvin beside displacements in metres) do not set the size of
    // a vibration
    let nc = doubled.n_coeffs();
    let scale = a0
        .iter()
        .enumerate()
        .filter(|(i, _)| i % nc != 0)
        .fold(0.0f64, |m, (_, x)| m.max(x.abs()))
        .max(1e-300);
    let share = |a: &[f64]| share_of(a, &half, nc);
    let newton = NewtonOptions::default();
    let mut tried = Vec::new();
    for fraction in [1.0, 0.1] {
        for sign in [1.0, -1.0] {
            // the half-order part's projection on the mode fixed, ω free: the branch it
            // bifurcated from has none, so Newton cannot fall back onto it
            let eps = sign * fraction * opts.amplitude * scale;
            let arc = ArcConstraint {
                anchor: &a0,
                anchor_omega: pd.omega,
                row: &v,
                corner: 0.0,
                ds: eps,
            };
            let guess: Vec<f64> = a0.iter().zip(&v).map(|(a, m)| a + eps * m).collect();
            match solve_arclength(&hb, &guess, pd.omega, &arc, &newton) {
                Ok((a, omega, _)) => {
                    let s = share(&a);
                    if s >= opts.min_share {
                        return Ok(SwitchedStart {
                            basis: doubled,
                            omega,
                            unknowns: a,
                            half_order_share: s,
                        });
                    }
                    tried.push(format!(
                        "mode amplitude {eps:.3e}: ω = {omega:.6}, half-order share {s:.2e}"
                    ));
                }
                Err(e) => tried.push(format!("mode amplitude {eps:.3e}: {e}")),
            }
        }
    }
    Err(ContinuationError::Switch(format!(
        "period doubling at ω = {:.6}: no period-doubled solution beside it ({})",
        pd.omega,
        tried.join("; ")
    )))
}
