//! The harmonic balance of a force with a kink, integrated between its switching instants
//! (`hb::events`), against two independent references: the uniformly sampled AFT, which
//! converges to the exact coefficients like `1/N²` as its sample count grows, and central
//! differences of the residual for the Jacobian.

use tmrotor_engine::hb::{Basis, HarmonicBalance};
use tmrotor_engine::systems::contact::UnilateralContact;

/// A two-DoF orbit whose first DoF enters the contact (gap 1) during part of the period.
fn orbit(nc: usize) -> Vec<f64> {
    let mut c = vec![0.0; 2 * nc];
    let nh = (nc - 1) / 2;
    c[0] = 0.1; // a_0
    c[1] = 1.2; // a_1
    c[1 + nh + 1] = 0.3; // b_2
    c[3] = -0.05; // a_3
    c[nc] = 0.02;
    c[nc + 1] = 0.4;
    c
}

fn residual(hb: &HarmonicBalance<'_>, c: &[f64], omega: f64) -> Vec<f64> {
    let mut r = vec![0.0; c.len()];
    hb.residual(c, omega, &mut r).expect("residual");
    r
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

#[test]
fn exact_coefficients_are_the_limit_of_sampling() {
    let system = UnilateralContact::default();
    let basis = Basis::integer(7).expect("basis");
    let omega = 0.7;
    let exact = HarmonicBalance::new(&system, &basis, None).expect("hb");
    assert!(exact.event_refinement());
    let c = orbit(basis.n_coeffs());
    let nodes = exact.event_nodes(&c, omega).expect("nodes");
    assert_eq!(nodes.events.len(), 2, "contact closes and opens once");
    let r_exact = residual(&exact, &c, omega);
    let sampled = |n: usize| {
        let hb = HarmonicBalance::new(&system, &basis, Some(n))
            .expect("hb")
            .with_event_refinement(false);
        residual(&hb, &c, omega)
    };
    let e12 = max_diff(&sampled(1 << 12), &r_exact);
    let e16 = max_diff(&sampled(1 << 16), &r_exact);
    eprintln!("sampled with 4096: {e12:.3e}, with 65536: {e16:.3e}");
    // second order: 16 times the samples, about 256 times smaller
    assert!(e16 < 1e-7, "{e16:e}");
    assert!(e16 < e12 / 100.0, "{e12:e} → {e16:e}");
}

#[test]
fn exact_jacobian_is_the_derivative_of_the_exact_residual() {
    let system = UnilateralContact::default();
    let basis = Basis::integer(7).expect("basis");
    let omega = 0.7;
    let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
    let c = orbit(basis.n_coeffs());
    let mut r = vec![0.0; c.len()];
    let parts = hb.residual_jacobian(&c, omega, &mut r).expect("jacobian");
    let jac = hb.dense_jacobian(&parts);
    let n = c.len();
    let h = 1e-6;
    let mut worst = 0.0f64;
    for j in 0..n {
        let (mut cp, mut cm) = (c.clone(), c.clone());
        cp[j] += h;
        cm[j] -= h;
        let (rp, rm) = (residual(&hb, &cp, omega), residual(&hb, &cm, omega));
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            worst = worst.max((fd - jac[i * n + j]).abs());
        }
    }
    eprintln!("largest difference to central differences: {worst:.3e}");
    assert!(worst < 1e-7, "{worst:e}");
}
