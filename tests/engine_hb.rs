//! Harmonic-balance residual, exact Jacobian and condensed solves (one factorization for
//! several right-hand sides), checked against finite differences and against the
//! uncondensed dense solve.

use tmrotor::hb::{Basis, Border, HarmonicBalance, LinearSolver, Ratio};
use tmrotor::system::System;
use tmrotor::systems::chain::Chain;
use tmrotor::systems::duffing::Duffing;

/// Deterministic pseudo-random numbers in [-1, 1) (LCG), so tests are reproducible.
fn pseudo_random(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

fn check_jacobian(system: &dyn System, basis: &Basis, omega: f64, scale: f64) {
    let hb = HarmonicBalance::new(system, basis, None).expect("hb");
    let nu = hb.n_unknowns();
    let a: Vec<f64> = pseudo_random(nu, 7).iter().map(|v| v * scale).collect();
    let mut r = vec![0.0; nu];
    let parts = hb.residual_jacobian(&a, omega, &mut r).expect("jacobian");
    let jac = hb.dense_jacobian(&parts);
    let h = 1e-6;
    let mut rp = vec![0.0; nu];
    let mut rm = vec![0.0; nu];
    let mut max_err: f64 = 0.0;
    let mut max_entry: f64 = 0.0;
    for c in 0..nu {
        let mut ap = a.clone();
        ap[c] += h;
        let mut am = a.clone();
        am[c] -= h;
        hb.residual(&ap, omega, &mut rp).expect("residual");
        hb.residual(&am, omega, &mut rm).expect("residual");
        for i in 0..nu {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            max_err = max_err.max((fd - jac[i * nu + c]).abs());
            max_entry = max_entry.max(fd.abs());
        }
    }
    assert!(
        max_err < 1e-7 * max_entry.max(1.0),
        "max |J - FD| = {max_err:e} (max entry {max_entry:e})"
    );
    // the Jacobian applied without assembling it: against a central difference along a
    // direction in which every unknown moves
    let v = pseudo_random(nu, 11);
    let mut jv = vec![0.0; nu];
    hb.apply_jacobian(&parts, &v, &mut jv);
    let ap: Vec<f64> = a.iter().zip(&v).map(|(x, d)| x + h * d).collect();
    let am: Vec<f64> = a.iter().zip(&v).map(|(x, d)| x - h * d).collect();
    hb.residual(&ap, omega, &mut rp).expect("residual");
    hb.residual(&am, omega, &mut rm).expect("residual");
    let (mut err, mut size) = (0.0_f64, 0.0_f64);
    for i in 0..nu {
        let fd = (rp[i] - rm[i]) / (2.0 * h);
        err = err.max((fd - jv[i]).abs());
        size = size.max(fd.abs());
    }
    assert!(
        err < 1e-7 * size.max(1.0),
        "max |J v - FD| = {err:e} (max {size:e})"
    );
}

#[test]
fn jacobian_matches_finite_differences_duffing() {
    check_jacobian(
        &Duffing::default(),
        &Basis::integer(5).expect("basis"),
        1.3,
        1.0,
    );
}

#[test]
fn jacobian_matches_finite_differences_thermo_mechanical_chain_multifrequency_basis() {
    // every derivative type (x, ẋ, T on f and g) is non-zero, basis with 1/2 and 6/5 multiples
    let basis = Basis::paper(2, Ratio::new(6, 5).expect("ratio")).expect("basis");
    check_jacobian(&Chain::new(5, 3), &basis, 0.9, 0.5);
}

#[test]
fn residual_of_linear_response_matches_closed_form() {
    // without the cubic term the 1-harmonic solution of m ẍ + c ẋ + k x = F cos ωt is
    // a = F (k − mω²)/D, b = F c ω / D, D = (k − mω²)² + (cω)²: the residual must vanish.
    let sys = Duffing::new(1.0, 0.05, 1.0, 0.0, 0.18);
    let basis = Basis::integer(3).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let w: f64 = 0.8;
    let (kd, cw) = (1.0 - w * w, 0.05 * w);
    let d = kd * kd + cw * cw;
    let mut a = vec![0.0; 7];
    a[1] = 0.18 * kd / d;
    a[4] = 0.18 * cw / d;
    let mut r = vec![0.0; 7];
    hb.residual(&a, w, &mut r).expect("residual");
    assert!(r.iter().all(|v| v.abs() < 1e-14), "{r:?}");
}

fn solve_both(system: &dyn System, basis: &Basis, omega: f64, bordered: bool) {
    let hb = HarmonicBalance::new(system, basis, None).expect("hb");
    let nu = hb.n_unknowns();
    let a: Vec<f64> = pseudo_random(nu, 11).iter().map(|v| 0.3 * v).collect();
    let mut r = vec![0.0; nu];
    let parts = hb.residual_jacobian(&a, omega, &mut r).expect("jacobian");
    let b = pseudo_random(nu, 3);
    let col = pseudo_random(nu, 5);
    let row = pseudo_random(nu, 9);
    let border = bordered.then_some(Border {
        column: &col,
        row: &row,
        corner: 0.7,
    });
    let (x1, mu1) = LinearSolver { condense: true }
        .solve(&hb, &parts, border, &b, 0.4)
        .expect("condensed");
    let (x2, mu2) = LinearSolver { condense: false }
        .solve(&hb, &parts, border, &b, 0.4)
        .expect("full");
    let scale = x2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (u, v) in x1.iter().zip(&x2) {
        assert!((u - v).abs() < 1e-10 * scale, "{u} vs {v}");
    }
    assert!((mu1 - mu2).abs() < 1e-10 * mu2.abs().max(1.0));
    // and the full solution really solves the system: J x + c μ = b
    let jac = hb.dense_jacobian(&parts);
    for i in 0..nu {
        let mut s: f64 = (0..nu).map(|j| jac[i * nu + j] * x1[j]).sum();
        if bordered {
            s += col[i] * mu1;
        }
        assert!((s - b[i]).abs() < 1e-9 * scale.max(1.0));
    }
    // one factorization, several right-hand sides: each equals a fresh full solve
    let b2 = pseudo_random(nu, 13);
    for condense in [true, false] {
        let fact = LinearSolver { condense }
            .factor(&hb, &parts, border)
            .expect("factor");
        assert_eq!(fact.bordered(), bordered);
        for (rhs, e) in [(&b, 0.4), (&b2, -1.3)] {
            let (x, mu) = fact.solve(rhs, e).expect("solve");
            let (xf, muf) = LinearSolver { condense: false }
                .solve(&hb, &parts, border, rhs, e)
                .expect("full");
            let scale = xf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (u, v) in x.iter().zip(&xf) {
                assert!((u - v).abs() < 1e-10 * scale, "{u} vs {v}");
            }
            assert!((mu - muf).abs() < 1e-10 * muf.abs().max(1.0));
        }
    }
    // blocks of right-hand sides, with the factors kept for one column at a time and for
    // blocks: every column equals a fresh full solve
    let rhs = faer::Mat::from_fn(nu, 3, |i, j| [&b, &b2, &col][j][i]);
    let es = [0.4, -1.3, 2.1];
    let solver = LinearSolver { condense: true };
    for fact in [
        solver.factor(&hb, &parts, border).expect("factor"),
        solver
            .factor_for_blocks(&hb, &parts, border)
            .expect("factor for blocks"),
    ] {
        let (x, mu) = fact.solve_many(rhs.as_ref(), &es).expect("solve many");
        for j in 0..3 {
            let bj: Vec<f64> = (0..nu).map(|i| rhs[(i, j)]).collect();
            let (xf, muf) = LinearSolver { condense: false }
                .solve(&hb, &parts, border, &bj, es[j])
                .expect("full");
            let scale = xf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (i, v) in xf.iter().enumerate() {
                assert!(
                    (x[(i, j)] - v).abs() < 1e-10 * scale,
                    "{} vs {v}",
                    x[(i, j)]
                );
            }
            let mu_j = if bordered { mu[j] } else { 0.0 };
            assert!((mu_j - muf).abs() < 1e-10 * muf.abs().max(1.0));
        }
    }
}

#[test]
fn condensed_solve_equals_full_solve_mechanical_chain() {
    solve_both(
        &Chain::new(12, 0),
        &Basis::integer(3).expect("basis"),
        1.1,
        false,
    );
    solve_both(
        &Chain::new(12, 0),
        &Basis::integer(3).expect("basis"),
        1.1,
        true,
    );
}

#[test]
fn condensed_solve_equals_full_solve_with_thermal_linear_dofs() {
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    solve_both(&Chain::new(9, 6), &basis, 0.7, false);
    solve_both(&Chain::new(9, 6), &basis, 0.7, true);
}

#[test]
fn jacobian_matches_finite_differences_several_contacts_and_hot_nodes() {
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    check_jacobian(&Chain::with_contacts(7, 5, 3, 2), &basis, 1.3, 0.4);
}

/// A factored bordered matrix whose border row is replaced (Sherman–Morrison) solves like
/// a fresh factorization with the new row, condensed or not, with or without the
/// replacement's `A⁻¹ e` handed in, and a second replacement starts from the factored row.
#[test]
fn replaced_border_row_solves_like_a_fresh_factorization() {
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let sys = Chain::with_contacts(7, 5, 3, 2);
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let nu = hb.n_unknowns();
    let a: Vec<f64> = pseudo_random(nu, 21).iter().map(|v| 0.3 * v).collect();
    let mut r = vec![0.0; nu];
    let parts = hb.residual_jacobian(&a, 1.1, &mut r).expect("jacobian");
    let col = pseudo_random(nu, 5);
    let (row, row2, row3) = (
        pseudo_random(nu, 9),
        pseudo_random(nu, 17),
        pseudo_random(nu, 19),
    );
    let b = pseudo_random(nu, 3);
    let border = |row| Border {
        column: &col,
        row,
        corner: 0.7,
    };
    for condense in [true, false] {
        let solver = LinearSolver { condense };
        let mut fact = solver
            .factor(&hb, &parts, Some(border(&row)))
            .expect("factor");
        let u = fact.solve(&vec![0.0; nu], 1.0).expect("u");
        for (k, (new_row, corner)) in [(&row2, -0.4), (&row3, 1.9)].into_iter().enumerate() {
            let given = (k == 0).then_some((u.0.as_slice(), u.1));
            fact.replace_border_row(new_row, corner, given)
                .expect("replaced");
            let fresh = Border {
                column: &col,
                row: new_row,
                corner,
            };
            let (xf, muf) = LinearSolver { condense: false }
                .solve(&hb, &parts, Some(fresh), &b, 0.4)
                .expect("fresh");
            let (x, mu) = fact.solve(&b, 0.4).expect("solve");
            let scale = xf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (p, q) in x.iter().zip(&xf) {
                assert!((p - q).abs() < 1e-10 * scale, "{p} vs {q}");
            }
            assert!(
                (mu - muf).abs() < 1e-10 * muf.abs().max(1.0),
                "{mu} vs {muf}"
            );
        }
    }
    // without a border there is no row to replace
    let mut plain = LinearSolver::default()
        .factor(&hb, &parts, None)
        .expect("factor");
    assert!(plain.replace_border_row(&row2, 0.1, None).is_err());
}

/// `∂R/∂ω` by the forward difference from the residual at the point agrees with the
/// central difference to the forward difference's own error (about 1e-8 relative).
#[test]
fn forward_omega_derivative_matches_the_central_one() {
    let basis = Basis::paper(2, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let sys = Chain::with_contacts(7, 5, 3, 2);
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let nu = hb.n_unknowns();
    let a: Vec<f64> = pseudo_random(nu, 23).iter().map(|v| 0.4 * v).collect();
    let omega = 1.3;
    let mut r = vec![0.0; nu];
    hb.residual(&a, omega, &mut r).expect("residual");
    let (mut fwd, mut central) = (vec![0.0; nu], vec![0.0; nu]);
    hb.d_residual_d_omega_from(&a, omega, &r, &mut fwd)
        .expect("forward");
    hb.d_residual_d_omega(&a, omega, &mut central)
        .expect("central");
    let scale = central.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(scale > 0.0);
    let err = fwd
        .iter()
        .zip(&central)
        .fold(0.0f64, |m, (f, c)| m.max((f - c).abs()));
    assert!(err < 1e-6 * scale, "max deviation {err:e} of {scale:e}");
    // a residual of the wrong length is refused
    assert!(
        hb.d_residual_d_omega_from(&a, omega, &r[1..], &mut fwd)
            .is_err()
    );
}

/// Hill's pencil takes the Jacobian and the velocity sensitivity from one evaluation of
/// the samples: the same matrices as the two separate calls, and no sensitivity (rather
/// than a matrix of zeros) where no force or heat depends on a velocity.
#[test]
fn jacobian_and_velocity_sensitivity_from_one_evaluation_equal_the_separate_ones() {
    let basis = Basis::paper(2, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let mut without = Chain::new(5, 3);
    without.cubic_damping = 0.0;
    without.heat_friction = 0.0;
    for (system, velocity_dependent) in [(Chain::new(5, 3), true), (without, false)] {
        let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
        let nu = hb.n_unknowns();
        let a: Vec<f64> = pseudo_random(nu, 5).iter().map(|v| 0.5 * v).collect();
        let (mut r1, mut r2) = (vec![0.0; nu], vec![0.0; nu]);
        let parts = hb.residual_jacobian(&a, 0.9, &mut r1).expect("jacobian");
        let separate = hb.velocity_sensitivity(&a, 0.9).expect("velocity");
        let (joint, velocity) = hb
            .residual_jacobian_velocity(&a, 0.9, &mut r2)
            .expect("jacobian and velocity");
        assert_eq!(r1, r2);
        assert_eq!(parts.nonlinear, joint.nonlinear);
        assert_eq!(hb.dense_jacobian(&parts), hb.dense_jacobian(&joint));
        assert_eq!(
            hb.velocity_sensitivity_if_any(&a, 0.9).expect("velocity"),
            velocity
        );
        match velocity {
            Some(v) => {
                assert!(velocity_dependent);
                assert!(v.iter().any(|x| *x != 0.0));
                assert_eq!(v, separate);
            }
            None => {
                assert!(!velocity_dependent);
                assert!(separate.iter().all(|x| *x == 0.0));
            }
        }
    }
}

/// A point's Hill exponents are the same whether the pencil evaluates the Jacobian itself
/// or is handed the continuation's (whose flag tells it whether a velocity sensitivity
/// must be evaluated): with and without velocity-dependent forces and heat.
#[test]
fn hill_exponents_equal_with_a_handed_jacobian() {
    use tmrotor::hb::HbSolution;
    use tmrotor::stability::{HillOptions, HillPencil};
    let basis = Basis::integer(3).expect("basis");
    let mut without = Chain::new(4, 3);
    without.cubic_damping = 0.0;
    without.heat_friction = 0.0;
    for (system, velocity_dependent) in [(Chain::new(4, 3), true), (without, false)] {
        let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
        let omega = 0.9;
        let (a, stats) = tmrotor::hb::newton::solve_fixed(
            &hb,
            omega,
            &vec![0.0; hb.n_unknowns()],
            &Default::default(),
        )
        .expect("a converged point");
        let s = HbSolution::from_unknowns(omega, hb.basis(), hb.n_mech(), &a, &stats);
        let mut r = vec![0.0; hb.n_unknowns()];
        let parts = hb.residual_jacobian(&a, omega, &mut r).expect("jacobian");
        assert_eq!(parts.velocity_dependent, velocity_dependent);
        let want = hb.n_therm() + 4;
        let options = HillOptions::default();
        let own = HillPencil::new(&hb, &s, None)
            .and_then(|p| p.near_zero(want, &options))
            .expect("exponents");
        let handed = HillPencil::new(&hb, &s, Some(&parts))
            .and_then(|p| p.near_zero(want, &options))
            .expect("exponents");
        assert!(!own.exponents.is_empty());
        assert_eq!(own, handed);
    }
}
