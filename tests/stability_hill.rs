//! Floquet accuracy on the Hill-type reference `A(t) = [[0, 1], [−10 cos t, −24 − 10 sin t]]`
//! (exponents 0 and −24 exactly, see `tmrotor::systems::hill`).

use tmrotor::stability::{Sip, StabilityMethod, Variational};
use tmrotor::systems::hill::{EXPONENTS, Hill, HillOrbit, PERIOD};

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
