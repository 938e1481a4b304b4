//! Floquet accuracy on the Hill-type reference `A(t) = [[0, 1], [−10 cos t, −24 − 10 sin t]]`
//! (exponents 0 and −24 exactly, see `tmrotor::systems::hill`).

use tmrotor::stability::{Sip, StabilityMethod, Variational};
use tmrotor::systems::hill::{EXPONENTS, Hill, HillOrbit, PERIOD, exact_monodromy};

/// Multipliers sorted by modulus, descending.
fn sorted(mut m: Vec<num_complex::Complex64>) -> Vec<num_complex::Complex64> {
    m.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
    m
}

#[test]
fn sip_default_reaches_exponent_zero_and_minus_24() {
    let sip = Sip::default();
    let mono = sip
        .monodromy_with_log_det(&Hill::default(), &HillOrbit)
        .expect("SIP runs");
    let mult = sorted(mono.matrix.eigenvalues().expect("eigenvalues"));
    let lambda0 = mult[0].norm().ln() / PERIOD;
    let log_det = mono.log_abs_det.expect("log det requested");
    let lambda1 = (log_det - mult[0].norm().ln()) / PERIOD;
    println!(
        "SIP N_k = {} (rho bound {:.2}): mu0 = {:.3e}{:+.3e}i, exponent0 = {:.3e}, exponent1 = {:.9}, |mu1| = {:.3e}",
        mono.intervals,
        mono.rho_bound,
        mult[0].re,
        mult[0].im,
        lambda0,
        lambda1,
        mult[1].norm()
    );
    assert!(mult[0].im.abs() < 1e-12, "leading multiplier is real");
    // The multiplier on the circle is what decides stability: the default resolves it to
    // far better than UNIT_CIRCLE_TOL = 1e-6 (|μ − 1| = 2π·|exponent|).
    assert!(
        (lambda0 - EXPONENTS[0]).abs() < 1e-7,
        "exponent 0: {lambda0}"
    );
    // The fast exponent −24 is carried with Δ·24 ≈ 0.59 per factor: the order-4 series
    // misrepresents exp(−0.59) by ~1e-3 relative per interval, ~0.1 in the exponent after
    // 256 intervals (a multiplier of e^{−48π} is immaterial for stability).
    assert!(
        (lambda1 - EXPONENTS[1]).abs() < 0.15,
        "exponent -24: {lambda1}"
    );
    assert!(
        mult[1].norm() < 1e-12,
        "second multiplier is numerically zero"
    );
}

#[test]
fn sip_refined_reaches_exponent_minus_24() {
    let mono = Sip::fixed(4096, 4)
        .monodromy_with_log_det(&Hill::default(), &HillOrbit)
        .expect("SIP runs");
    let mult = sorted(mono.matrix.eigenvalues().expect("eigenvalues"));
    let lambda0 = mult[0].norm().ln() / PERIOD;
    let lambda1 = (mono.log_abs_det.expect("log det") - mult[0].norm().ln()) / PERIOD;
    println!("SIP N_k = 4096: exponent0 = {lambda0:.3e}, exponent1 = {lambda1:.9}");
    // Series truncation error per interval ∝ (Δ·24)^5: 16× shorter intervals than the
    // default divide the exponent error (~0.09) by ~16^4.
    assert!(
        (lambda0 - EXPONENTS[0]).abs() < 1e-10,
        "exponent 0: {lambda0}"
    );
    assert!(
        (lambda1 - EXPONENTS[1]).abs() < 1e-4,
        "exponent -24: {lambda1}"
    );
}

#[test]
fn sip_error_falls_as_delta_squared() {
    let mut errs = vec![];
    for n in [200, 400, 800] {
        let mono = Sip::fixed(n, 4)
            .monodromy(&Hill::default(), &HillOrbit)
            .expect("SIP runs");
        let mult = sorted(mono.matrix.eigenvalues().expect("eigenvalues"));
        errs.push((mult[0] - 1.0).norm());
    }
    println!("SIP |mu0 - 1| at N_k = 200, 400, 800: {errs:?}");
    // Interval means keep the first Magnus term exactly and drop the commutator term:
    // at least second order is guaranteed (halving Δ divides the error by ≥ 4; on this
    // problem the multiplier on the circle converges faster, ratios ≈ 17–19).
    for w in errs.windows(2) {
        let ratio = w[0] / w[1];
        assert!(ratio > 3.5, "ratio {ratio} in {errs:?}");
    }
}

#[test]
fn variational_reaches_exponent_zero_and_annihilates_the_decaying_solution() {
    let var = Variational::default();
    let phi = var
        .monodromy(&Hill::default(), &HillOrbit)
        .expect("variational runs");
    let mult = sorted(phi.eigenvalues().expect("eigenvalues"));
    let lambda0 = mult[0].norm().ln() / PERIOD;
    // The decaying solution x = exp(−24t + 10 cos t) starts along (1, −24): Φ maps it to
    // e^{−48π}·(1, −24) ≈ 0.
    let image = [
        phi[(0, 0)] - 24.0 * phi[(0, 1)],
        phi[(1, 0)] - 24.0 * phi[(1, 1)],
    ];
    println!(
        "variational: mu0 = {:.12}{:+.3e}i, exponent0 = {:.3e}, |mu1| = {:.3e}, |Phi v1| = {:.3e}",
        mult[0].re,
        mult[0].im,
        lambda0,
        mult[1].norm(),
        image[0].hypot(image[1])
    );
    assert!(
        (lambda0 - EXPONENTS[0]).abs() < 1e-9,
        "exponent 0: {lambda0}"
    );
    assert!(mult[1].norm() < 1e-9);
    assert!(image[0].hypot(image[1]) < 1e-8);
    let r = var
        .multipliers(&Hill::default(), &HillOrbit)
        .expect("multipliers");
    assert!(r.stable, "exponent 0 sits on the circle within tolerance");
}

#[test]
fn exact_monodromy_is_the_closed_form_and_matches_the_variational_one() {
    let exact = exact_monodromy();
    // trace = sum of the multipliers, det = their product (e^{−48π} below round-off)
    let trace = exact[0][0] + exact[1][1];
    let det = exact[0][0] * exact[1][1] - exact[0][1] * exact[1][0];
    assert!((trace - 1.0).abs() < 1e-14, "trace {trace}");
    assert!(det.abs() < 1e-14, "det {det}");
    // the decaying solution starts along (1, −24) and is annihilated
    for row in exact {
        assert!((row[0] - 24.0 * row[1]).abs() < 1e-12);
    }
    let phi = Variational::default()
        .monodromy(&Hill::default(), &HillOrbit)
        .expect("variational runs");
    let err = (0..2)
        .flat_map(|i| (0..2).map(move |j| (i, j)))
        .map(|(i, j)| (phi[(i, j)] - exact[i][j]).abs())
        .fold(0.0, f64::max);
    println!("exact monodromy {exact:?}, variational differs by {err:.3e}");
    assert!(err < 1e-9, "variational vs exact monodromy: {err:e}");
}

// The table of `examples/hill.rs`, exactly as `cargo run --example hill` prints it.
#[path = "../examples/hill.rs"]
#[allow(dead_code)]
mod example;

#[test]
fn example_table_shows_second_order_sip_and_accurate_variational() {
    let rows = example::rows().expect("example runs");
    let csv = example::table_csv(&rows);
    print!("{csv}");
    let sip: Vec<_> = rows.iter().filter(|r| r.method == "sip").collect();
    assert_eq!(sip.len(), example::INTERVALS.len());
    for w in sip.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = b.intervals.expect("intervals");
        // the monodromy matrix: second order once the series is accurate (N ≥ 512)
        let order = (a.monodromy_error / b.monodromy_error).log2();
        if n >= 512 {
            assert!((order - 2.0).abs() < 0.1, "N = {n}: matrix order {order}");
        }
        // the multiplier on the circle: at least second order, until round-off (1e-13)
        if a.mu1_error > 1e-12 {
            let order = (a.mu1_error / b.mu1_error).log2();
            assert!(order > 1.9, "N = {n}: multiplier order {order}");
        }
        // the fast exponent: error falls with N
        let (ea, eb) = (
            a.exponent2_error.expect("SIP gives exponent 2"),
            b.exponent2_error.expect("SIP gives exponent 2"),
        );
        assert!(eb < ea, "N = {n}: exponent −24 error {eb} after {ea}");
    }
    let finest = sip.last().expect("rows");
    assert!(finest.mu1_error < 1e-12 && finest.exponent2_error.expect("exp 2") < 1e-6);
    let var = rows
        .iter()
        .find(|r| r.method == "variational")
        .expect("variational row");
    assert!(var.mu1_error < 1e-9 && var.monodromy_error < 1e-9);
    // the CSV lists the exact row and one row per method run
    assert_eq!(csv.lines().count(), 2 + rows.len());
    assert!(csv.contains("\nexact,,1e0,0e0,"));
}
