//! `tmrotor sweep` on the primary basis follows the period-doubled branch from a located
//! period doubling and records it as a branch of its own (`SweepProblem::run`,
//! `switch_branches`). The literature model at 2 L/min with 50 °C cooling, swept down
//! from 700 to 612 rad/s, has a period doubling at ≈ 619.75 rad/s (one of the four of its
//! full sweep); the sweep takes about 12 s.
//!
//! What is checked, apart from the recorded structure: the primary branch's multiplier at
//! the located point is −1; every recorded point of the switched branch has a
//! period-doubled part and solves the harmonic balance on the doubled basis when solved
//! again from its recorded coefficients; the switched branch leaves from the period
//! doubling, and the primary response at the same speeds is a different orbit (two
//! responses coexist there).

use tmrotor::continuation::switch::{doubled_basis, half_order_share};
use tmrotor::derive::{CoupledRederive, ModelRederive, StabilityRederive};
use tmrotor::hb::{HarmonicBalance, NewtonOptions, newton};
use tmrotor::record::{MemorySink, PointRecord};
use tmrotor::stability::BifurcationKind;
use tmrotor::sweep::{
    HarmonicSettings, OperatingSettings, StudySettings, SweepProblem, SweepSettings,
};

fn coefficients(p: &PointRecord) -> Vec<f64> {
    let mut a = p.coeffs_mech.clone();
    a.extend_from_slice(&p.coeffs_therm);
    a
}

#[test]
fn the_sweep_follows_the_period_doubled_branch_as_its_own() {
    let root = env!("CARGO_MANIFEST_DIR");
    let settings = StudySettings {
        model: Some(format!("{root}/models/dual_rotor_literature.toml").into()),
        operating: OperatingSettings {
            flow_l_min: 2.0,
            cooling_temp_c: 50.0,
            ..Default::default()
        },
        harmonic: HarmonicSettings {
            half_orders: false,
            ..Default::default()
        },
        sweep: SweepSettings {
            omega_start: 700.0,
            omega_end: 612.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let problem = SweepProblem::new(&settings).expect("problem");
    assert!(problem.switches_branches());
    let mut sink = MemorySink::new();
    let report = problem.run(&mut sink, None, |_| {}).expect("sweep");

    // the period doubling on the run's branch: a multiplier at −1
    let pd = sink
        .bifurcations
        .iter()
        .find(|b| b.branch == 0 && b.kind == BifurcationKind::PeriodDoubling)
        .expect("a period doubling on the primary branch");
    let nearest = pd
        .multipliers
        .iter()
        .map(|m| (m + 1.0).norm())
        .fold(f64::INFINITY, f64::min);
    assert!(nearest < 1e-2, "multiplier nearest −1 is {nearest} away");

    // the switched branch, described and recorded
    assert_eq!(sink.branches.len(), 1, "{:?}", report.branches);
    let b = &sink.branches[0];
    let doubled = doubled_basis(&problem.basis).expect("doubled basis");
    assert_eq!(b.branch, 1);
    assert_eq!(b.kind, "period_doubled");
    assert_eq!(b.parent, 0);
    assert_eq!(b.origin_bifurcation, pd.number);
    assert_eq!(b.origin_omega_rad_s, pd.omega_rad_s);
    assert_eq!(b.harmonics, doubled.harmonics());
    let points: Vec<&PointRecord> = sink.points.iter().filter(|p| p.branch == 1).collect();
    assert_eq!(report.branches.len(), 1);
    assert_eq!(report.branches[0].points, points.len());
    assert!(points.len() >= 5, "{} points", points.len());
    let indices: Vec<u64> = sink.points.iter().map(|p| p.index).collect();
    assert!(
        indices.windows(2).all(|w| w[1] == w[0] + 1),
        "one index sequence over both branches"
    );
    eprintln!(
        "period doubling at {:.4} rad/s; branch 1: {} points over {:?}, {}",
        pd.omega_rad_s,
        points.len(),
        report.branches[0].omega_range,
        report.branches[0].end
    );

    // every point period-doubled, and a solution of the balance on the doubled basis
    let hb = HarmonicBalance::new(&problem.system, &doubled, None).expect("hb");
    let mut shares = Vec::new();
    for p in &points {
        let a = coefficients(p);
        let share = half_order_share(&a, &problem.basis, &doubled);
        assert!(share > 1e-3, "point {}: half-order share {share}", p.index);
        let (again, stats) = newton::solve_fixed(&hb, p.omega_rad_s, &a, &NewtonOptions::default())
            .expect("the recorded point solves the balance");
        let moved = a
            .iter()
            .zip(&again)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(
            stats.iterations <= 1 && moved < 1e-9,
            "point {}: {} iterations, moved {moved:e}",
            p.index,
            stats.iterations
        );
        shares.push((p.omega_rad_s, share));
    }
    eprintln!("(ω, share) on branch 1: {shares:?}");
    // it leaves from the period doubling: its first point is the nearest to it
    let first = points[0].omega_rad_s;
    let gap = (first - pd.omega_rad_s).abs();
    assert!(
        gap < 2.0,
        "first point {first} vs period doubling {}",
        pd.omega_rad_s
    );
    assert!(
        points
            .iter()
            .all(|p| (p.omega_rad_s - pd.omega_rad_s).abs() >= gap - 1e-9),
        "the branch starts beside the period doubling"
    );
    // the primary response at the first point's speed is another orbit
    let primary_hb = HarmonicBalance::new(&problem.system, &problem.basis, None).expect("hb");
    let mut pd_a = pd.coeffs_mech.clone();
    pd_a.extend_from_slice(&pd.coeffs_therm);
    let (primary, _) = newton::solve_fixed(&primary_hb, first, &pd_a, &NewtonOptions::default())
        .expect("the primary response beside the period doubling");
    let embedded = tmrotor::continuation::switch::embed(&primary, &problem.basis, &doubled);
    let a = coefficients(points[0]);
    let diff = a
        .iter()
        .zip(&embedded)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    assert!(diff > 1e-7, "the two responses differ by {diff:e}");
    // multipliers on the doubled branch (the doubled period), for the log
    eprintln!(
        "first point multipliers {:?}",
        points[0].multipliers.iter().take(6).collect::<Vec<_>>()
    );

    // replay's re-derivation reads a branch point on the branch's basis: the same
    // multipliers and the same clearances as recorded
    let run = b.run_of(sink.run.as_ref().expect("run"));
    let again = CoupledRederive::from_run(&run).expect("re-derivation");
    let p = points[points.len() / 2];
    let f = again.floquet(p).expect("multipliers of a branch point");
    let radius = |m: &[num_complex::Complex64]| m.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let (r0, r1) = (radius(&p.multipliers), radius(&f.multipliers));
    assert!(
        (r0 - r1).abs() <= 1e-9 * r0,
        "spectral radius recorded {r0}, re-derived {r1}"
    );
    let bearings = again
        .bearings(p, tmrotor::sweep::RECORD_SAMPLES)
        .expect("bearing quantities");
    for (c, d) in p.clearances.iter().zip(&bearings.clearances) {
        assert!(
            (c.delta_v_m - d.delta_v_m).abs() <= 1e-12,
            "δv recorded {}, re-derived {}",
            c.delta_v_m,
            d.delta_v_m
        );
    }
}

/// Which bases switch: the dual rotor's paper basis holds the half orders (no switching;
/// `--no-half-orders` switches), a single rotor's integer basis holds none, so its period
/// doublings are followed with the default settings, and `switch_branches = false` or no
/// stability turn it off.
#[test]
fn a_single_rotor_switches_by_default_the_paper_basis_does_not() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dual = StudySettings::default();
    assert!(!SweepProblem::new(&dual).expect("dual").switches_branches());
    let mut primary = dual.clone();
    primary.harmonic.half_orders = false;
    assert!(
        SweepProblem::new(&primary)
            .expect("primary")
            .switches_branches()
    );
    let single = StudySettings {
        model: Some(format!("{root}/examples/rotors/jeffcott_midspan_disk.toml").into()),
        ..Default::default()
    };
    assert!(
        single.harmonic.half_orders,
        "the default keeps the setting on"
    );
    assert!(
        SweepProblem::new(&single)
            .expect("single")
            .switches_branches()
    );
    let mut off = single.clone();
    off.sweep.switch_branches = false;
    assert!(!SweepProblem::new(&off).expect("off").switches_branches());
    let mut no_stability = single;
    no_stability.floquet.stability = false;
    assert!(
        !SweepProblem::new(&no_stability)
            .expect("no stability")
            .switches_branches()
    );
}
