//! The exponential-split SIP product and the Craig–Bampton reduction, checked against the
//! variational equations (Dormand–Prince) and against the unreduced model:
//!
//! * Duffing resonant orbit: `ExpSip` = variational multipliers, error falling as `Δ²`;
//! * built-in dual rotor (order 3, ω = 400 rad/s, coupled thermal network): the reduced
//!   model's multipliers = the full model's, converging with the cut-off; `ExpSip` on the
//!   reduced model = the variational equations integrated on the same reduced model; the
//!   explicit SIP product refuses the stiff full model with a clear setting error.

use num_complex::Complex64;
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use tmrotor::hb::{Basis, HarmonicBalance, HbSolution, NewtonOptions, Ratio, newton};
use tmrotor::model::Model;
use tmrotor::stability::{
    CraigBampton, ExpSip, IntervalMap, MeanSplit, Reduced, ReducedOrbit, ReductionSettings, Sip,
    StabilityError, StabilityMethod, Variational, split_thermal, thermal_multiplier_estimates,
};
use tmrotor::system::{PeriodicOrbit, System};
use tmrotor::systems::chain::Chain;
use tmrotor::systems::duffing::Duffing;

/// For each of the `k` largest (by modulus) multipliers of `a`, the distance to the
/// nearest multiplier of `b`; the maximum over them.
fn matched_distance(a: &[Complex64], b: &[Complex64], k: usize) -> f64 {
    let mut sorted = a.to_vec();
    sorted.sort_by(|x, y| y.norm().total_cmp(&x.norm()));
    sorted
        .iter()
        .take(k)
        .map(|m| b.iter().map(|n| (m - n).norm()).fold(f64::MAX, f64::min))
        .fold(0.0, f64::max)
}

fn duffing_resonant_orbit() -> (Duffing, HbSolution) {
    let sys = Duffing::default();
    let basis = Basis::integer(7).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.5, 1.2);
    opts.ds_max = 0.05;
    opts.max_points = 10_000;
    let mut cont = Continuation::new(hb, opts, None).expect("continuation");
    let branch = cont.run(|_| {}).expect("run");
    // The upper (resonant) branch point of largest amplitude below Ω = 1.2.
    let best = branch
        .points
        .iter()
        .max_by(|a, b| {
            a.solution
                .rms_amplitude(0, None)
                .total_cmp(&b.solution.rms_amplitude(0, None))
        })
        .expect("points");
    (sys, best.solution.clone())
}

#[test]
fn exp_sip_matches_the_variational_equations_on_the_duffing_resonance() {
    let (sys, orbit) = duffing_resonant_orbit();
    assert!(orbit.rms_amplitude(0, None) > 1.0, "on the resonant branch");
    let reference = Variational::default()
        .multipliers(&sys, &orbit)
        .expect("variational")
        .multipliers;
    let err_with = |n: usize, extrapolate: bool| {
        let m = ExpSip {
            intervals: n,
            extrapolate,
            max_intervals: 0,
            ..ExpSip::default()
        }
        .multipliers(&sys, &orbit)
        .expect("exp sip")
        .multipliers;
        matched_distance(&m, &reference, 2)
    };
    // The plain product is second order: halving Δ divides the error by about 4…
    let err = |n: usize| err_with(n, false);
    let (e256, e512, e1024) = (err(256), err(512), err(1024));
    assert!(e1024 < 1e-4, "error at 1024 intervals {e1024:e}");
    for (coarse, fine) in [(e256, e512), (e512, e1024)] {
        let ratio = coarse / fine;
        assert!(
            (3.0..5.5).contains(&ratio),
            "error ratio {ratio} ({coarse:e} → {fine:e})"
        );
    }
    // …so the extrapolation from 1024 and 512 removes most of it.
    let ex = err_with(1024, true);
    assert!(ex < e1024 / 4.0, "extrapolated {ex:e} vs plain {e1024:e}");
}

struct DualRotorPoint {
    sys: CoupledRotor,
    orbit: HbSolution,
}

/// A point of the dual rotor with the literature values of its open parameters (lighter
/// damping, a stronger nonlinearity: the case these checks were built on;
/// docs/calibration.md).
fn dual_rotor_point(omega: f64, thermal: bool) -> DualRotorPoint {
    let model = Model::literature().expect("literature model");
    let sys = CoupledRotor::new(
        &model,
        &StudyOverrides::default(),
        CouplingOptions {
            thermal,
            frozen_clearance: false,
            ..Default::default()
        },
    )
    .expect("coupled rotor");
    let basis = Basis::paper(3, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let a0 = sys.initial_guess(basis.n_coeffs());
    let (a, stats) =
        newton::solve_fixed(&hb, omega, &a0, &NewtonOptions::default()).expect("converges");
    let orbit = HbSolution::from_unknowns(omega, &basis, sys.n_mech(), &a, &stats);
    DualRotorPoint { sys, orbit }
}

fn mechanical(sys: &dyn System, orbit: &dyn PeriodicOrbit, all: &[Complex64]) -> Vec<Complex64> {
    let predicted = thermal_multiplier_estimates(sys, orbit).expect("thermal estimates");
    let split = split_thermal(all, &predicted);
    assert!(
        split.max_mismatch < 1e-2,
        "thermal multipliers far from their predictions: {:e}",
        split.max_mismatch
    );
    for t in &split.thermal {
        assert!(
            t.norm() < 1.0,
            "thermal multiplier {t} outside the unit circle"
        );
    }
    split.mechanical
}

#[test]
fn dual_rotor_reduced_stability_agrees_with_the_full_model_and_a_second_method() {
    let p = dual_rotor_point(400.0, true);
    let (sys, orbit) = (&p.sys, &p.orbit);

    // The explicit product cannot take the full finite-element model.
    match Sip::default().multipliers(sys, orbit) {
        Err(StabilityError::Setting { field, .. }) => assert_eq!(field, "sip.intervals"),
        other => panic!("expected a stiffness refusal, got {other:?}"),
    }

    // Full model, exponential split (210 states). Both products on 4096 intervals: the
    // full model's stiffer boundary modes give it a different discretisation error, and
    // the reduced–full distance at the default cut-off falls with the intervals (measured
    // 3.3e-4, 2.6e-4, 1.3e-4 at 1024, 2048, 4096) towards the reduction error itself.
    let product = ExpSip {
        intervals: 4096,
        max_intervals: 0,
        ..ExpSip::default()
    };
    let full_all = product.multipliers(sys, orbit).expect("full").multipliers;
    assert_eq!(full_all.len(), 2 * sys.n_mech() + sys.n_therm());
    let full = mechanical(sys, orbit, &full_all);

    // Reduced models converge to it with the cut-off.
    let reduced_at = |cutoff: f64| {
        let cb = CraigBampton::new(
            sys,
            400.0,
            ReductionSettings {
                cutoff_rad_s: cutoff,
                max_modes: 200,
            },
        )
        .expect("reduction");
        let rs = cb.system(sys).expect("reduced system");
        let view = ReducedOrbit::new(orbit, &cb);
        let all = product
            .multipliers(&rs, &view)
            .expect("reduced")
            .multipliers;
        mechanical(&rs, &view, &all)
    };
    let coarse = reduced_at(5_000.0);
    let fine = reduced_at(ReductionSettings::default().cutoff_rad_s);
    let d_coarse = matched_distance(&full, &coarse, 6);
    let d_fine = matched_distance(&full, &fine, 6);
    assert!(d_fine < 2e-4, "default cut-off vs full model: {d_fine:e}");
    assert!(
        d_fine < d_coarse,
        "cut-off convergence: {d_coarse:e} → {d_fine:e}"
    );
}

/// The variational equations as an independent second method on the reduced dual rotor.
/// Mechanical part only: the explicit integrator's step is bounded by the stiff boundary
/// modes (≈ 2.9·10⁴ 1/s), and with the 66-node network each step costs ten times more; the
/// thermal blocks are cross-checked on the thermal chain below.
#[test]
fn dual_rotor_reduced_exp_sip_matches_the_variational_equations() {
    let p = dual_rotor_point(400.0, false);
    let (sys, orbit) = (&p.sys, &p.orbit);
    let cb = CraigBampton::new(
        sys,
        400.0,
        ReductionSettings {
            cutoff_rad_s: 5_000.0,
            max_modes: 200,
        },
    )
    .expect("reduction");
    let by_var = Reduced {
        reduction: cb.clone(),
        method: Variational {
            rtol: 1e-8,
            atol: 1e-10,
        },
    }
    .multipliers(sys, orbit)
    .expect("variational");
    let at = |n: usize| {
        Reduced {
            reduction: cb.clone(),
            method: ExpSip {
                intervals: n,
                max_intervals: 0,
                ..ExpSip::default()
            },
        }
        .multipliers(sys, orbit)
        .expect("exp sip")
    };
    let moduli = |m: &[Complex64]| {
        let mut v: Vec<f64> = m.iter().map(|c| c.norm()).collect();
        v.sort_by(|a, b| b.total_cmp(a));
        v
    };
    // Moduli (what the stable flag reads) are accurate already with the default product
    // (refined from 512 intervals where needed)…
    let by_exp = Reduced {
        reduction: cb.clone(),
        method: ExpSip::default(),
    }
    .multipliers(sys, orbit)
    .expect("exp sip");
    let (me, mv) = (moduli(&by_exp.multipliers), moduli(&by_var.multipliers));
    let dm = me
        .iter()
        .zip(&mv)
        .take(8)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dm < 3e-4, "multiplier moduli differ by {dm:e}");
    // …and the multipliers themselves (their phases converge more slowly, and not cleanly
    // at second order: the bearing stiffness has kinks where balls lose contact) approach
    // the variational ones as the intervals are refined (measured 3.7e-3, 1.9e-4, 1.7e-4
    // extrapolated).
    let errs: Vec<f64> = [1024, 2048, 4096]
        .iter()
        .map(|&n| matched_distance(&at(n).multipliers, &by_var.multipliers, 8))
        .collect();
    assert!(
        errs[0] > errs[1] && errs[1] > errs[2] && errs[2] < 5e-4,
        "ExpSip vs variational as intervals are refined: {errs:?}"
    );
    assert_eq!(by_exp.stable, by_var.stable);
}

/// Thermal and coupling blocks: a 30-mass chain with two contacts coupled to a 12-node
/// thermal chain with two hot nodes, on its harmonic-balance orbit.
#[test]
fn exp_sip_matches_the_variational_equations_with_thermal_coupling() {
    let sys = Chain::with_contacts(30, 12, 2, 2);
    let basis = Basis::integer(5).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let a0 = vec![0.0; hb.n_unknowns()];
    let (a, stats) =
        newton::solve_fixed(&hb, 0.9, &a0, &NewtonOptions::default()).expect("converges");
    let orbit = HbSolution::from_unknowns(0.9, &basis, sys.n_mech(), &a, &stats);
    let reference = Variational::default()
        .multipliers(&sys, &orbit)
        .expect("variational")
        .multipliers;
    let got = ExpSip {
        intervals: 1024,
        max_intervals: 0,
        ..ExpSip::default()
    }
    .multipliers(&sys, &orbit)
    .expect("exp sip")
    .multipliers;
    assert_eq!(got.len(), 2 * 30 + 12);
    let d = matched_distance(&got, &reference, 12);
    assert!(
        d < 1e-4,
        "ExpSip vs variational with thermal coupling: {d:e}"
    );
}

/// The sweep's default stability method on a strongly parametric orbit: the coupled dual
/// rotor (2 L/min, 25 °C) at ω = 500 rad/s on the branch reached from 440 rad/s. The
/// bearing stiffness changes with every rolling-element pass while the bearing-local modes
/// are stiff, so the product needs fine intervals here: the reference (the variational
/// equations on the same reduced model, Dormand–Prince, rtol 1e-6) has one real
/// multiplier of modulus 1.320 (measured 1.31994; 1.31999 at rtol 1e-9), which a plain
/// Strang product on 256 intervals misses entirely; the exponential interval map (the
/// default) is checked against it for its order and against Strang's at 512 intervals.
#[test]
fn sweep_default_stability_matches_the_variational_equations_on_an_unstable_orbit() {
    use tmrotor::sweep::{StudySettings, SweepProblem, stability_method};
    // the literature values (docs/calibration.md): the orbit this check was built on
    let settings = StudySettings {
        model: Some(
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/models/dual_rotor_literature.toml"
            )
            .into(),
        ),
        ..StudySettings::default()
    };
    let problem = SweepProblem::new(&settings).expect("problem");
    let (sys, basis) = (&problem.system, &problem.basis);
    let hb = HarmonicBalance::new(sys, basis, None).expect("hb");
    let a0 = sys.initial_guess(basis.n_coeffs());
    let opts = NewtonOptions::default();
    let (a440, _) = newton::solve_fixed(&hb, 440.0, &a0, &opts).expect("440 rad/s");
    let (a, stats) = newton::solve_fixed(&hb, 500.0, &a440, &opts).expect("500 rad/s");
    let orbit = HbSolution::from_unknowns(500.0, basis, sys.n_mech(), &a, &stats);

    let method = stability_method(&settings, sys, 500.0).expect("sweep default method");
    let got = method.multipliers(sys, &orbit).expect("default method");
    let cb = CraigBampton::new(sys, 500.0, ReductionSettings::default()).expect("reduction");
    let reference = Reduced {
        reduction: cb,
        method: Variational {
            rtol: 1e-6,
            atol: 1e-9,
        },
    }
    .multipliers(sys, &orbit)
    .expect("variational");
    let top = |m: &[Complex64]| m.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let (g, r) = (top(&got.multipliers), top(&reference.multipliers));
    assert!(r > 1.3, "reference: unstable multiplier expected, got {r}");
    assert!(
        (g - r).abs() < 5e-3,
        "default method {g} vs variational {r}"
    );
    assert!(!got.stable && !reference.stable);
    // the largest 40 (the 66 thermal ones lie between 0.84 and 1)
    let d = matched_distance(&got.multipliers, &reference.multipliers, 40);
    assert!(d < 5e-3, "largest 40 multipliers: distance {d:e}");

    // The two interval maps against the reference, without refinement. Measured (plain
    // products on 256 / 512 / 1024 intervals): exponential 1.2361 / 1.2986 / 1.3150,
    // Strang 1.0000 / 1.0712 / 1.2559; extrapolated from 512: 1.3165 against 1.2013.
    let cb = || CraigBampton::new(sys, 500.0, ReductionSettings::default()).expect("reduction");
    let top_with = |interval_map: IntervalMap, intervals: usize, extrapolate: bool| {
        let m = Reduced {
            reduction: cb(),
            method: ExpSip {
                intervals,
                max_intervals: 0,
                extrapolate,
                interval_map,
                ..ExpSip::default()
            },
        };
        top(&m.multipliers(sys, &orbit).expect("product").multipliers)
    };
    let errors: Vec<f64> = [256, 512, 1024]
        .iter()
        .map(|&n| (top_with(IntervalMap::Exponential, n, false) - r).abs())
        .collect();
    for pair in errors.windows(2) {
        assert!(
            pair[1] < pair[0] / 3.0,
            "exponential map: errors {errors:?} do not fall at second order"
        );
    }
    let strang = (top_with(IntervalMap::Strang, 512, false) - r).abs();
    assert!(
        errors[1] < strang / 5.0,
        "512 intervals: exponential error {:e} against Strang's {strang:e}",
        errors[1]
    );
    let ext_exp = (top_with(IntervalMap::Exponential, 512, true) - r).abs();
    let ext_strang = (top_with(IntervalMap::Strang, 512, true) - r).abs();
    assert!(
        ext_exp < 5e-3 && ext_exp < ext_strang / 10.0,
        "extrapolated from 512: exponential error {ext_exp:e}, Strang {ext_strang:e}"
    );
}

/// The modal propagation is the same product in the eigenvector coordinates of `B̄`'s
/// blocks: on the reduced dual rotor (coupled network) it must take the modal path (both
/// bases well conditioned) and give the dense path's monodromy matrix to rounding. Both
/// with Strang's interval map, the only one the dense path has.
#[test]
fn modal_and_dense_products_agree_on_the_dual_rotor() {
    let p = dual_rotor_point(450.0, true);
    let (sys, orbit) = (&p.sys, &p.orbit);
    let cb = CraigBampton::new(sys, 450.0, ReductionSettings::default()).expect("reduction");
    let rs = cb.system(sys).expect("reduced system");
    let view = ReducedOrbit::new(orbit, &cb);
    let with = |modal: bool| ExpSip {
        intervals: 128,
        max_intervals: 0,
        modal,
        interval_map: IntervalMap::Strang,
        ..ExpSip::default()
    };
    let conds = with(true)
        .modal_conditions(&rs, &view)
        .expect("setup")
        .expect("both blocks have a modal basis");
    assert_eq!(conds.len(), 2, "mechanical and thermal blocks");
    assert!(conds.iter().all(|&c| c < 1e4), "conditions {conds:?}");
    assert!(
        with(false)
            .modal_conditions(&rs, &view)
            .expect("setup")
            .is_none()
    );

    let dense = with(false).monodromy(&rs, &view).expect("dense");
    let modal = with(true).monodromy(&rs, &view).expect("modal");
    let norm = |m: &faer::Mat<f64>| m.norm_l2();
    let diff = norm(&(&modal - &dense)) / norm(&dense);
    assert!(
        diff < 1e-10,
        "relative difference of the monodromy matrices {diff:e}"
    );
    assert!(diff > 0.0, "the two paths must not be the same computation");

    let mu_dense = with(false)
        .multipliers(&rs, &view)
        .expect("dense")
        .multipliers;
    let mu_modal = with(true)
        .multipliers(&rs, &view)
        .expect("modal")
        .multipliers;
    let near: Vec<Complex64> = mu_dense
        .iter()
        .copied()
        .filter(|m| m.norm() > 0.5)
        .collect();
    assert!(near.len() >= 66, "the thermal multipliers at least");
    let d = matched_distance(&near, &mu_modal, near.len());
    assert!(d < 1e-10, "multipliers above 1/2 differ by {d:e}");

    // The coupled split (the whole mean state matrix taken exactly, one modal block)
    let coupled = |modal: bool| ExpSip {
        mean_split: MeanSplit::Coupled,
        ..with(modal)
    };
    let conds = coupled(true)
        .modal_conditions(&rs, &view)
        .expect("setup")
        .expect("the coupled mean matrix has a modal basis");
    assert_eq!(conds.len(), 1);
    let dense = coupled(false).monodromy(&rs, &view).expect("dense");
    let modal = coupled(true).monodromy(&rs, &view).expect("modal");
    let diff = norm(&(&modal - &dense)) / norm(&dense);
    assert!(diff < 1e-10, "coupled split: relative difference {diff:e}");
}

/// The matched distance from the reference multipliers above 1/2 in modulus (the dual
/// rotor's 66 thermal ones at least) to `mu`.
fn distance_above_half(reference: &[Complex64], mu: &[Complex64]) -> f64 {
    let near: Vec<Complex64> = reference
        .iter()
        .copied()
        .filter(|m| m.norm() > 0.5)
        .collect();
    assert!(near.len() >= 66, "the thermal multipliers at least");
    matched_distance(&near, mu, near.len())
}

#[test]
fn thermal_field_in_blocks_equals_the_per_interval_product_on_the_dual_rotor() {
    // The thermal rows brought forward every 16 (or 24: a shorter last block) intervals
    // against every interval. Measured: the monodromy matrices within 1.1e-7 / 1.3e-7
    // (relative, 2-norm; the truncation `(BΔ|λ|)²/2` of the kicks' drift inside a block),
    // the multipliers above 1/2 within 2e-11 / 4e-11, far below the product's own error
    // (3e-3 on the unstable orbit of the sweep test above).
    let p = dual_rotor_point(450.0, true);
    let (sys, orbit) = (&p.sys, &p.orbit);
    let cb = CraigBampton::new(sys, 450.0, ReductionSettings::default()).expect("reduction");
    let rs = cb.system(sys).expect("reduced system");
    let view = ReducedOrbit::new(orbit, &cb);
    let with = |thermal_block: usize| ExpSip {
        thermal_block,
        ..ExpSip::default()
    };
    let every = with(1).monodromy(&rs, &view).expect("every interval");
    let norm = |m: &faer::Mat<f64>| m.norm_l2();
    let mu_every = with(1).multipliers(&rs, &view).expect("every").multipliers;
    for block in [16, 24] {
        let blocks = with(block).monodromy(&rs, &view).expect("blocks");
        let diff = norm(&(&blocks - &every)) / norm(&every);
        assert!(diff < 1e-6, "block {block}: relative difference {diff:e}");
        assert!(diff > 0.0, "block {block}: the blocks were not used");
        let mu = with(block)
            .multipliers(&rs, &view)
            .expect("blocks")
            .multipliers;
        let d = distance_above_half(&mu_every, &mu);
        assert!(
            d < 1e-9,
            "block {block}: multipliers above 1/2 differ by {d:e}"
        );
    }
}

#[test]
fn panels_equal_the_column_blocks_on_the_dual_rotor() {
    // The product on panels of eight columns stored by rows (the crate's own kernels)
    // against the column blocks through faer's matrix products: the same arithmetic in
    // another order, so the monodromy matrices agree to rounding (measured 6e-15 relative)
    // and so do the multipliers.
    let p = dual_rotor_point(450.0, true);
    let (sys, orbit) = (&p.sys, &p.orbit);
    let cb = CraigBampton::new(sys, 450.0, ReductionSettings::default()).expect("reduction");
    let rs = cb.system(sys).expect("reduced system");
    let view = ReducedOrbit::new(orbit, &cb);
    let with = |panels: bool| ExpSip {
        panels,
        ..ExpSip::default()
    };
    let blocks = with(false).monodromy(&rs, &view).expect("column blocks");
    let panels = with(true).monodromy(&rs, &view).expect("panels");
    let diff = (&panels - &blocks).norm_l2() / blocks.norm_l2();
    assert!(diff < 1e-12, "relative difference {diff:e}");
    assert!(diff > 0.0, "the panels were not used");
    let mu_blocks = with(false)
        .multipliers(&rs, &view)
        .expect("blocks")
        .multipliers;
    let mu_panels = with(true)
        .multipliers(&rs, &view)
        .expect("panels")
        .multipliers;
    let d = distance_above_half(&mu_blocks, &mu_panels);
    assert!(d < 1e-10, "multipliers above 1/2 differ by {d:e}");
}

#[test]
fn the_orbit_mapped_once_equals_the_projection_per_sample() {
    // The harmonic solution maps its coefficients into the reduced coordinates once; the
    // view projects the full state at every sample. The same linear map, so the states
    // agree to rounding at any time, and so do the multipliers of the reduced product.
    let p = dual_rotor_point(450.0, true);
    let (sys, orbit) = (&p.sys, &p.orbit);
    let cb = CraigBampton::new(sys, 450.0, ReductionSettings::default()).expect("reduction");
    let rs = cb.system(sys).expect("reduced system");
    let view = ReducedOrbit::new(orbit, &cb);
    let mapped = cb
        .mapped_orbit(orbit)
        .expect("a harmonic solution maps itself");
    let (r, m) = (rs.n_mech(), rs.n_therm());
    let (mut x1, mut v1, mut t1) = (vec![0.0; r], vec![0.0; r], vec![0.0; m]);
    let (mut x2, mut v2, mut t2) = (vec![0.0; r], vec![0.0; r], vec![0.0; m]);
    let scale = |a: &[f64]| a.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
    for k in 0..37 {
        let t = orbit.period() * k as f64 / 37.0;
        view.state_at(t, &mut x1, &mut v1, &mut t1);
        mapped.state_at(t, &mut x2, &mut v2, &mut t2);
        for (a, b, what) in [(&x1, &x2, "x"), (&v1, &v2, "v"), (&t1, &t2, "T")] {
            let s = scale(a);
            assert!(s > 0.0);
            for (ai, bi) in a.iter().zip(b.iter()) {
                assert!(
                    (ai - bi).abs() <= 1e-12 * s,
                    "{what} at t = {t}: {ai} vs {bi}"
                );
            }
        }
    }
    let sip = ExpSip::default();
    let mu_view = sip.multipliers(&rs, &view).expect("view").multipliers;
    let mu_mapped = sip
        .multipliers(&rs, mapped.as_ref())
        .expect("mapped")
        .multipliers;
    let d = matched_distance(&mu_view, &mu_mapped, mu_view.len());
    assert!(d < 1e-9, "multipliers differ by {d}");
}

#[test]
fn kicks_on_the_fluctuations_own_directions_keep_the_multipliers_on_the_dual_rotor() {
    // The kicks gather and spread only the directions the fluctuation uses (on the dual
    // rotor 8 + 12 of the 10 + 26 rows and columns at the default tolerance, the rest
    // exact zeros or below 3e-5 of their block's largest) against all rows and columns:
    // the monodromy matrix and the multipliers above 1/2 the same to rounding. Dropping
    // real directions (a tolerance of 5e-2, which leaves out those of 2e-3 … 5e-2) moves
    // the multipliers by orders of magnitude more.
    let p = dual_rotor_point(450.0, true);
    let (sys, orbit) = (&p.sys, &p.orbit);
    let cb = CraigBampton::new(sys, 450.0, ReductionSettings::default()).expect("reduction");
    let rs = cb.system(sys).expect("reduced system");
    let view = ReducedOrbit::new(orbit, &cb);
    let with = |kick_rank_tol: f64| ExpSip {
        kick_rank_tol,
        ..ExpSip::default()
    };
    let all = with(0.0).monodromy(&rs, &view).expect("all rows");
    let own = with(ExpSip::default().kick_rank_tol)
        .monodromy(&rs, &view)
        .expect("own directions");
    let diff = (&own - &all).norm_l2() / all.norm_l2();
    assert!(diff < 1e-6, "relative difference {diff:e}");
    assert!(diff > 0.0, "the directions were not used");
    let mu = |tol: f64| {
        with(tol)
            .multipliers(&rs, &view)
            .expect("multipliers")
            .multipliers
    };
    let mu_all = mu(0.0);
    let d_own = distance_above_half(&mu_all, &mu(ExpSip::default().kick_rank_tol));
    let d_coarse = distance_above_half(&mu_all, &mu(5e-2));
    // measured: 1.1e-10 and 4.0e-10; at 5e-2, 1.1e-4
    assert!(d_own < 1e-8, "multipliers above 1/2 differ by {d_own:e}");
    assert!(
        d_coarse > 10.0 * d_own,
        "dropping real directions: {d_coarse:e} against {d_own:e}"
    );
}
