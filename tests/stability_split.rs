//! The slow/fast split of the coupled model's stability and its agreement with the
//! branch's folds (docs/stability.md):
//!
//! * the Schur complement onto the thermal means, formed with one factorization and the
//!   Woodbury identity, against the dense Schur complement of the assembled Jacobian;
//! * the slowest slow exponent against a second method: the real multiplier nearest +1
//!   of the monodromy product over the whole coupled state, `ln μ / P`;
//! * on the 10 L/min branch through its fold pair near 582 rad/s: the count of real
//!   multipliers above +1 changes by one at each fold, the middle segment is unstable, and
//!   the fold the multipliers do not confirm is reported.

mod common;

use faer::Mat;
use faer::linalg::solvers::Solve;
use tmrotor::hb::{HarmonicBalance, HbSolution, NewtonOptions, newton};
use tmrotor::record::MemorySink;
use tmrotor::stability::{BifurcationKind, slow_exponents, thermal_schur};
use tmrotor::study::{
    HarmonicSettings, OperatingSettings, StudySettings, SweepProblem, SweepSettings,
    stability_method,
};
use tmrotor::system::{PeriodicOrbit, System};

/// The harmonic balance of `problem` (its basis and AFT samples).
fn balance(problem: &SweepProblem) -> HarmonicBalance<'_> {
    HarmonicBalance::new(
        &problem.system,
        &problem.basis,
        problem.settings.harmonic.aft_samples,
    )
    .expect("hb")
}

/// A converged point of `problem` at `omega`.
fn point(problem: &SweepProblem, hb: &HarmonicBalance<'_>, omega: f64) -> HbSolution {
    let guess = problem.system.initial_guess(problem.basis.n_coeffs());
    let (a, stats) =
        newton::solve_fixed(hb, omega, &guess, &NewtonOptions::default()).expect("converges");
    HbSolution::from_unknowns(omega, &problem.basis, problem.system.n_mech(), &a, &stats)
}

#[test]
fn the_thermal_schur_complement_equals_the_dense_one() {
    let settings = StudySettings {
        harmonic: HarmonicSettings {
            order: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    let problem = SweepProblem::new(&settings).expect("problem");
    let hb = HarmonicBalance::new(&problem.system, &problem.basis, None).expect("hb");
    let sol = point(&problem, &hb, 420.0);
    let s = thermal_schur(&hb, &sol).expect("schur");

    // dense: S = J_mm − J_mr J_rr⁻¹ J_rm with m the thermal mean coefficients
    let coeffs = sol.unknowns();
    let mut r = vec![0.0; coeffs.len()];
    let parts = hb
        .residual_jacobian(&coeffs, sol.omega, &mut r)
        .expect("jacobian");
    let j = hb.dense_jacobian(&parts);
    let nu = hb.n_unknowns();
    let nc = hb.n_coeffs();
    let m: Vec<usize> = (0..hb.n_therm()).map(|d| (hb.n_mech() + d) * nc).collect();
    let rest: Vec<usize> = (0..nu).filter(|i| !m.contains(i)).collect();
    let at = |rows: &[usize], cols: &[usize]| {
        Mat::from_fn(rows.len(), cols.len(), |a, b| j[rows[a] * nu + cols[b]])
    };
    let (j_mm, j_mr, j_rm, j_rr) = (at(&m, &m), at(&m, &rest), at(&rest, &m), at(&rest, &rest));
    let x = j_rr.partial_piv_lu().solve(&j_rm);
    let dense = &j_mm - &j_mr * &x;
    let scale = (0..m.len())
        .map(|i| dense[(i, i)].abs())
        .fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for a in 0..m.len() {
        for b in 0..m.len() {
            worst = worst.max((s[(a, b)] - dense[(a, b)]).abs());
        }
    }
    assert!(
        worst < 1e-9 * scale,
        "Woodbury Schur complement off the dense one by {worst:e} (scale {scale:e})"
    );
}

/// 10 L/min on the built-in model: the point of the exponent comparisons.
fn ten_l_min() -> StudySettings {
    StudySettings {
        operating: OperatingSettings {
            flow_l_min: 10.0,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// `ln μ / P` of the real multiplier nearest +1 of the product over the whole coupled state
/// (mechanical and thermal) at `sol`: the slowest exponent by a second method.
fn coupled_product_slowest(
    settings: &StudySettings,
    problem: &SweepProblem,
    sol: &HbSolution,
) -> f64 {
    let method =
        stability_method(settings, &problem.system, settings.sweep.omega_start).expect("m");
    let full = method.multipliers(&problem.system, sol).expect("product");
    let mu = full
        .multipliers
        .iter()
        .filter(|m| m.im == 0.0)
        .min_by(|a, b| (a.re - 1.0).abs().total_cmp(&(b.re - 1.0).abs()))
        .expect("a real multiplier");
    mu.re.ln() / sol.period()
}

#[test]
fn the_slowest_exponent_matches_the_coupled_products_multiplier_nearest_one() {
    let settings = ten_l_min();
    let problem = SweepProblem::new(&settings).expect("problem");
    let hb = balance(&problem);
    let sol = point(&problem, &hb, 400.0);
    let slow = slow_exponents(&hb, &sol).expect("slow exponents");
    let top = slow
        .iter()
        .max_by(|a, b| a.re.total_cmp(&b.re))
        .expect("exponents");
    assert!(top.im == 0.0 && top.re < 0.0, "slowest exponent {top}");

    // second method: the product over the whole coupled state (mechanical and thermal)
    let from_product = coupled_product_slowest(&settings, &problem, &sol);
    eprintln!("slowest exponent {top} 1/s; coupled product → {from_product} 1/s");
    assert!(
        (from_product - top.re).abs() < 1e-5 * top.re.abs(),
        "reduction {} vs product {from_product}",
        top.re
    );
}

/// 10 L/min over 570–595 rad/s on the literature values: a branch through a fold pair near
/// 582 rad/s (docs/calibration.md).
fn fold_pair_branch() -> StudySettings {
    StudySettings {
        operating: OperatingSettings {
            flow_l_min: 10.0,
            ..Default::default()
        },
        sweep: SweepSettings {
            omega_start: 570.0,
            omega_end: 595.0,
            ..Default::default()
        },
        model: Some(
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/models/dual_rotor_literature.toml"
            )
            .into(),
        ),
        ..Default::default()
    }
}

#[test]
fn stability_agrees_with_the_folds_of_a_branch_with_a_fold_pair() {
    let settings = fold_pair_branch();
    let problem = SweepProblem::new(&settings).expect("problem");
    let mut sink = MemorySink::new();
    let report = problem.run(&mut sink, None, |_| {}).expect("sweep");
    let folds: Vec<_> = sink
        .bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::SaddleNode)
        .collect();
    assert_eq!(folds.len(), 2, "the fold pair near 582 rad/s");
    let counts = |i: u64| {
        sink.points[i as usize]
            .floquet_counts
            .expect("stability computed")
    };
    for b in &folds {
        let (before, after) = (counts(b.after_point), counts(b.after_point + 1));
        assert_eq!(
            before.real_above_one.abs_diff(after.real_above_one),
            1,
            "saddle-node at {} rad/s: {before:?} → {after:?}",
            b.omega_rad_s
        );
        assert!(
            !b.coeffs_mech.is_empty(),
            "the fold carries its branch point"
        );
    }
    let middle = folds[0].after_point + 1..=folds[1].after_point;
    assert!(!middle.is_empty());
    for i in middle {
        assert_eq!(sink.points[i as usize].stable, Some(false), "point {i}");
    }
    // every change of the stable flag is at a located bifurcation or reported
    for w in sink.points.windows(2) {
        if w[0].stable != w[1].stable {
            let located = sink
                .bifurcations
                .iter()
                .any(|b| b.after_point == w[0].index);
            let noted = sink.notes.iter().any(|(k, _)| *k == w[0].index);
            assert!(located || noted, "silent change after point {}", w[0].index);
        }
    }
    // what the multipliers do not confirm is said, in the recording and the report
    let unconfirmed = folds.iter().filter(|b| !b.confirmed).count();
    let said = sink
        .notes
        .iter()
        .filter(|(_, t)| t.contains("not confirmed"))
        .count();
    assert_eq!(said, unconfirmed);
    assert_eq!(report.warnings.len(), sink.notes.len());
}

/// `tools/check_fold_stability.py` (official MCAP readers only) on a recorded branch with a
/// fold pair: no problem; on the same branch with the middle segment's verdicts replaced
/// by the product's own (as versions before the fold parity recorded them): problems found
/// (the check can fail).
#[test]
fn an_independent_reader_finds_the_flags_consistent_with_the_folds() {
    use tmrotor::record::Sink;
    let Some(python) = common::python() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let settings = fold_pair_branch();
    let problem = SweepProblem::new(&settings).expect("problem");
    let mut memory = MemorySink::new();
    problem.run(&mut memory, None, |_| {}).expect("sweep");
    // the middle segment of the fold pair, whose real exponent above zero the tampered
    // file drops (as the monodromy product alone, without the fold parity, recorded it)
    let folds: Vec<u64> = memory
        .bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::SaddleNode)
        .map(|b| b.after_point)
        .collect();
    assert_eq!(folds.len(), 2, "the fold pair");
    let middle = folds[0].min(folds[1]) + 1..=folds[0].max(folds[1]);
    let write = |name: &str, tamper: bool| {
        let path = dir.path().join(name);
        let mut sink = tmrotor::record::McapSink::create(&path, Default::default()).expect("file");
        sink.begin_run(memory.run.as_ref().expect("run"))
            .expect("begin");
        for p in &memory.points {
            let mut p = p.clone();
            if tamper
                && middle.contains(&p.index)
                && let Some(c) = p.floquet_counts.as_mut()
                && c.real_above_one > 0
            {
                c.fold_parity_mismatch = false;
                c.real_above_one -= 1;
                c.unstable -= 1;
                p.stable = Some(c.unstable == 0);
            }
            sink.write_point(&p).expect("point");
        }
        for b in &memory.bifurcations {
            sink.write_bifurcation(b).expect("bifurcation");
        }
        for (k, text) in &memory.notes {
            sink.write_note(*k, text).expect("note");
        }
        sink.finish(tmrotor::record::RunStatus::Completed)
            .expect("finish");
        path
    };
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/check_fold_stability.py");
    let run = |file: &std::path::Path| {
        let out = std::process::Command::new(&python)
            .arg(script)
            .arg(file)
            .output()
            .expect("python runs");
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).to_string(),
        )
    };
    let (ok, text) = run(&write("q10.mcap", false));
    assert!(ok && text.contains("2 saddle-nodes, ok"), "{text}");
    let (ok, text) = run(&write("product_only.mcap", true));
    assert!(!ok && text.contains("problems"), "{text}");
    assert!(text.contains("not flagged unstable"), "{text}");
}

/// The coupled exponents nearest zero (Hill's eigenproblem) on the dual rotor against two
/// other methods at a point far from folds (10 L/min, 400 rad/s): the slowest one against
/// the real multiplier nearest +1 of the product over the whole coupled state, and the
/// thermal ones against the quasi-static reduction, which holds where they are slow
/// against the fast exponent nearest zero.
#[test]
fn the_near_zero_exponents_match_the_coupled_product_and_the_reduction() {
    let settings = ten_l_min();
    let problem = SweepProblem::new(&settings).expect("problem");
    let hb = balance(&problem);
    let sol = point(&problem, &hb, 400.0);
    let nz = tmrotor::stability::near_zero_exponents(
        &hb,
        &sol,
        None,
        &tmrotor::stability::HillOptions::default(),
    )
    .expect("near zero");
    assert!(
        nz.exponents.len() >= hb.n_therm(),
        "{} exponents",
        nz.exponents.len()
    );
    let top = nz
        .exponents
        .iter()
        .max_by(|a, b| a.re.total_cmp(&b.re))
        .expect("exponents");
    let from_product = coupled_product_slowest(&settings, &problem, &sol);
    eprintln!("Hill: slowest {top} 1/s; coupled product → {from_product} 1/s");
    assert!(
        (from_product - top.re).abs() < 1e-5 * top.re.abs(),
        "Hill {} vs product {from_product}",
        top.re
    );
    // the reduction's thermal exponents, each matched by a Hill exponent
    let slow = slow_exponents(&hb, &sol).expect("slow exponents");
    let mut worst: f64 = 0.0;
    for l in &slow {
        let d = nz
            .exponents
            .iter()
            .map(|m| (m - l).norm())
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(d / l.norm());
    }
    eprintln!(
        "reduction against Hill: worst relative difference {worst:.2e} over {} exponents",
        slow.len()
    );
    assert!(worst < 1e-5, "{worst}");
}

/// The block Arnoldi iteration (the Krylov space grown by several vectors a step, with one
/// solve of many right-hand sides; the default on large condensed systems) against the
/// classical one on the dual rotor at order 5 (900 condensed unknowns), 10 L/min, 400
/// rad/s: the same exponents in the same disk, each to far below the truncation's
/// accuracy.
#[test]
fn block_arnoldi_finds_the_classical_iterations_exponents() {
    let mut settings = ten_l_min();
    settings.harmonic.order = 5;
    let problem = SweepProblem::new(&settings).expect("problem");
    let hb = balance(&problem);
    let sol = point(&problem, &hb, 400.0);
    let near_zero = |block: usize| {
        let options = tmrotor::stability::HillOptions {
            block,
            ..Default::default()
        };
        tmrotor::stability::near_zero_exponents(&hb, &sol, None, &options).expect("near zero")
    };
    let (one, four, auto) = (near_zero(1), near_zero(4), near_zero(0));
    eprintln!(
        "{} exponents: {} steps one at a time, {} in blocks of 4, {} automatic",
        one.exponents.len(),
        one.steps,
        four.steps,
        auto.steps
    );
    assert!(one.exponents.len() >= hb.n_therm(), "{one:?}");
    assert_eq!(
        auto, four,
        "the automatic choice is blocks of 4 at this size"
    );
    assert_eq!(four.steps % 4, 0, "{} steps", four.steps);
    assert_eq!(one.exponents.len(), four.exponents.len());
    for (a, b) in one.exponents.iter().zip(&four.exponents) {
        assert!(
            (a - b).norm() <= 1e-8 * a.norm().max(1.0),
            "classical {a} against block {b}"
        );
    }
}
