//! Fold curves in two parameters on the Duffing oscillator
//! `ẍ + 0.05ẋ + x + 0.1x³ = F cos Ωt`, continued in (Ω, F) from a saddle-node of a
//! one-parameter sweep:
//! - at H = 1, every point of the curve satisfies the closed form of the one-harmonic
//!   balance: with `s = 1 − Ω²`, `q = ¾k₃` and `u = a²`, the frequency-response equation
//!   `G(u, Ω) = u[(s + qu)² + c²Ω²] = F²` and the fold condition
//!   `∂G/∂u = 3q²u² + 4qsu + s² + c²Ω² = 0`; the cusp where the fold pair is born is where
//!   that quadratic has a double root, `s² = 3c²Ω²`, i.e. `Ω_c² − 1 = √3 c Ω_c`;
//! - the curve passes through the saddle-nodes of one-parameter sweeps at forcing
//!   amplitudes other than the start's (H = 3, to 1e-3 rad/s);
//! - the curve converges with H: the H = 3 and H = 5 curves agree more closely than H = 1
//!   and H = 3.

use tmrotor::continuation::fold::{FoldCurve, FoldOptions, continue_fold};
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::BifurcationKind;
use tmrotor::systems::duffing::Duffing;

const C: f64 = 0.05;
const K3: f64 = 0.1;

fn duffing(force: f64) -> Result<Duffing, String> {
    if force > 0.0 {
        Ok(Duffing::new(1.0, C, 1.0, K3, force))
    } else {
        Err("the forcing amplitude must be positive".into())
    }
}

/// The saddle-nodes `(Ω, unknowns)` of a one-parameter sweep at forcing `force`.
fn sweep_folds(order: u32, force: f64) -> Vec<(f64, Vec<f64>)> {
    let sys = duffing(force).expect("system");
    let basis = Basis::integer(order).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.5, 1.8);
    opts.ds_max = 0.02;
    opts.max_points = 100_000;
    let mut cont = Continuation::new(hb, opts, None).expect("continuation");
    let branch = cont.run(|_| {}).expect("run");
    branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::SaddleNode))
        .map(|b| (b.solution.omega, b.solution.unknowns()))
        .collect()
}

/// The fold curve of order `order` through the first saddle-node of the sweep at F = 0.18,
/// for F in [0.02, 0.4].
fn curve(order: u32) -> FoldCurve {
    let folds = sweep_folds(order, 0.18);
    assert_eq!(folds.len(), 2, "the sweep at F = 0.18 has one fold pair");
    let (omega0, a0) = &folds[0];
    let basis = Basis::integer(order).expect("basis");
    let mut opts = FoldOptions::new((0.02, 0.4), (0.5, 2.5));
    opts.ds_max = 0.02;
    continue_fold(&duffing, &basis, a0, *omega0, 0.18, &opts).expect("fold curve")
}

/// The first-harmonic amplitude of a point's unknowns (layout `[c0, a1, b1, …]`).
fn amplitude(unknowns: &[f64]) -> f64 {
    unknowns[1].hypot(unknowns[2])
}

#[test]
fn the_h1_fold_curve_is_the_closed_form_and_has_its_cusp() {
    let c = curve(1);
    assert!(c.points.len() > 20, "{} points", c.points.len());
    let q = 0.75 * K3;
    let mut worst = (0.0f64, 0.0f64);
    for pt in &c.points {
        let (w, f) = (pt.omega, pt.p);
        let u = amplitude(&pt.unknowns).powi(2);
        let s = 1.0 - w * w;
        let g = u * ((s + q * u).powi(2) + (C * w).powi(2));
        let fold = 3.0 * q * q * u * u + 4.0 * q * s * u + s * s + (C * w).powi(2);
        // relative to the size of the terms
        let fold_scale = s * s + (C * w).powi(2) + 4.0 * (q * s * u).abs();
        worst.0 = worst.0.max((g.sqrt() - f).abs() / f);
        worst.1 = worst.1.max(fold.abs() / fold_scale);
    }
    eprintln!(
        "H = 1: {} points, F from {:.4} to {:.4}; worst |F − F(u, Ω)|/F = {:.2e}, fold condition {:.2e}",
        c.points.len(),
        c.points.iter().map(|p| p.p).fold(f64::INFINITY, f64::min),
        c.points.iter().map(|p| p.p).fold(0.0, f64::max),
        worst.0,
        worst.1
    );
    assert!(
        worst.0 < 1e-8,
        "frequency-response equation off by {:.2e}",
        worst.0
    );
    assert!(worst.1 < 1e-8, "fold condition off by {:.2e}", worst.1);

    // the cusp: Ω_c² − 1 = √3 c Ω_c
    let b = 3f64.sqrt() * C;
    let omega_c = (b + (b * b + 4.0).sqrt()) / 2.0;
    let s = 1.0 - omega_c * omega_c;
    let u_c = -2.0 * s / (3.0 * q);
    let f_c = (u_c * ((s + q * u_c).powi(2) + (C * omega_c).powi(2))).sqrt();
    assert_eq!(c.cusps.len(), 1, "{:?}", c.cusps);
    let cusp = &c.cusps[0];
    eprintln!(
        "cusp at Ω = {:.6}, F = {:.6}; closed form Ω = {omega_c:.6}, F = {f_c:.6}",
        cusp.omega, cusp.p
    );
    assert!((cusp.omega - omega_c).abs() < 1e-3, "{cusp:?}");
    assert!((cusp.p - f_c).abs() < 1e-3 * f_c, "{cusp:?}");
}

#[test]
fn the_h3_fold_curve_passes_through_the_saddle_nodes_of_other_sweeps() {
    let c = curve(3);
    for force in [0.1, 0.3] {
        let mut swept: Vec<f64> = sweep_folds(3, force).into_iter().map(|f| f.0).collect();
        swept.sort_by(f64::total_cmp);
        let on_curve = c.omegas_at(force);
        eprintln!("F = {force}: sweep folds {swept:?}, curve {on_curve:?}");
        assert_eq!(swept.len(), on_curve.len(), "F = {force}");
        for (a, b) in swept.iter().zip(&on_curve) {
            // the curve's points are interpolated linearly between steps of ≤ 0.02
            // scaled arclength: compare with the point corrected onto F exactly
            assert!((a - b).abs() < 1e-3, "F = {force}: sweep {a}, curve {b}");
        }
    }
}

#[test]
fn the_fold_curve_converges_with_the_order() {
    let curves = [curve(1), curve(3), curve(5)];
    let at = |k: usize| curves[k].omegas_at(0.3);
    let (h1, h3, h5) = (at(0), at(1), at(2));
    eprintln!("F = 0.3: H = 1 {h1:?}, H = 3 {h3:?}, H = 5 {h5:?}");
    assert!(h1.len() == 2 && h3.len() == 2 && h5.len() == 2);
    let d13 = (h1[1] - h3[1]).abs();
    let d35 = (h3[1] - h5[1]).abs();
    assert!(
        d35 < 0.1 * d13,
        "upper fold: |H1 − H3| = {d13:.2e}, |H3 − H5| = {d35:.2e}"
    );
}
