//! The coupled dual rotor through the engine and into a recording.

use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use tmrotor::derive::CoupledRederive;
use tmrotor::derive::ModelRederive;
use tmrotor::hb::{Basis, HarmonicBalance, NewtonOptions, Ratio, newton};
use tmrotor::model::Model;
use tmrotor::record::MemorySink;
use tmrotor::sweep::{
    FloquetSettings, HarmonicSettings, OperatingSettings, StudySettings, SweepProblem,
    SweepSettings,
};

fn solve(sys: &CoupledRotor, basis: &Basis, omega: f64) -> Vec<f64> {
    let hb = HarmonicBalance::new(sys, basis, None).expect("hb");
    let a0 = sys.initial_guess(basis.n_coeffs());
    let (a, _) =
        newton::solve_fixed(&hb, omega, &a0, &NewtonOptions::default()).expect("converges");
    a
}

/// With the clearance frozen at δ0 the thermal network is solved but cannot act back on
/// the vibration: the mechanical coefficients must equal those of the mechanical-only
/// model, which never builds the network.
#[test]
fn frozen_clearance_reproduces_the_mechanical_only_solution() {
    let model = Model::builtin().expect("built-in");
    let study = StudyOverrides::default();
    let mech = CoupledRotor::new(
        &model,
        &study,
        CouplingOptions {
            thermal: false,
            frozen_clearance: false,
            ..Default::default()
        },
    )
    .expect("mechanical");
    let frozen = CoupledRotor::new(
        &model,
        &study,
        CouplingOptions {
            thermal: true,
            frozen_clearance: true,
            ..Default::default()
        },
    )
    .expect("frozen");
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let a = solve(&mech, &basis, 400.0);
    let b = solve(&frozen, &basis, 400.0);
    let n = a.len();
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(&b[..n])
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        diff <= 1e-6 * scale,
        "max difference {diff:e} vs scale {scale:e}"
    );
    // and the temperatures are above ambient: the network did run
    let nc = basis.n_coeffs();
    let t_max = (0..66).map(|p| b[n + p * nc]).fold(f64::MIN, f64::max);
    assert!(t_max > 26.0, "hottest node {t_max} °C");
}

/// Fully coupled at one speed: temperatures rise above the cooling temperature and the
/// clearance variation is what Eqs. 1–2 give for the solved temperatures; thermal
/// expansion changes the vibration relative to the frozen-clearance solution.
#[test]
fn two_way_coupling_changes_the_vibration() {
    let model = Model::builtin().expect("built-in");
    let study = StudyOverrides {
        flow_l_min: Some(1.0),
        ..Default::default()
    };
    let full = CoupledRotor::new(&model, &study, CouplingOptions::default()).expect("full");
    let frozen = CoupledRotor::new(
        &model,
        &study,
        CouplingOptions {
            thermal: true,
            frozen_clearance: true,
            ..Default::default()
        },
    )
    .expect("frozen");
    let basis = Basis::paper(1, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let a = solve(&full, &basis, 450.0);
    let b = solve(&frozen, &basis, 450.0);
    let n = 72 * basis.n_coeffs();
    let diff = a[..n]
        .iter()
        .zip(&b[..n])
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        diff > 1e-8,
        "thermal clearance must act on the rotor: {diff:e}"
    );
}

/// A short sweep into an in-memory sink: every point recorded, bearing quantities
/// re-derived from the embedded model equal the recorded ones.
#[test]
fn short_sweep_records_points_and_replay_rederives_bearings() {
    let settings = StudySettings {
        harmonic: HarmonicSettings {
            order: 1,
            ..Default::default()
        },
        sweep: SweepSettings {
            omega_start: 400.0,
            omega_end: 404.0,
            max_points: 6,
            ..Default::default()
        },
        floquet: FloquetSettings {
            stability: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let problem = SweepProblem::new(&settings).expect("problem");
    let mut sink = MemorySink::new();
    let mut refused = usize::MAX;
    let report = problem
        .run(&mut sink, None, |p| refused = p.rejected_steps)
        .expect("sweep");
    assert_eq!(report.points, sink.points.len());
    assert!(report.points >= 2);
    // the report's refused steps are the progress's last count
    assert_eq!(report.rejected_steps, refused);
    let run = sink.run.as_ref().expect("run info");
    assert_eq!(run.n_mech, 72);
    assert_eq!(run.n_therm, 66);
    let p = &sink.points[sink.points.len() - 1];
    assert_eq!(p.bearing_loads.len(), 4);
    assert!(p.bearing_loads.iter().all(|l| l.mean_n > 100.0));
    let re = CoupledRederive::from_run(run).expect("rebuilds from the embedded model");
    let d = re
        .bearings(p, tmrotor::sweep::RECORD_SAMPLES)
        .expect("re-derives");
    for (a, b) in d.loads.iter().zip(&p.bearing_loads) {
        assert!(
            (a.mean_n - b.mean_n).abs() <= 1e-9 * b.mean_n,
            "{} vs {}",
            a.mean_n,
            b.mean_n
        );
    }
    for (a, b) in d.clearances.iter().zip(&p.clearances) {
        assert!((a.delta_v_m - b.delta_v_m).abs() <= 1e-15 + 1e-9 * b.delta_v_m.abs());
    }
}

/// Replay's stability audit: the multipliers of a short recorded sweep (stability on)
/// recomputed from the embedded model with the recorded settings and with a finer product
/// (`replay stability --sip-intervals`); an impossible interval count is refused naming
/// the setting.
#[test]
fn replay_recomputes_stability_with_recorded_or_finer_intervals() {
    use tmrotor::derive::{StabilityRederive, multiplier_deviation};
    let settings = StudySettings {
        harmonic: HarmonicSettings {
            order: 1,
            ..Default::default()
        },
        sweep: SweepSettings {
            omega_start: 400.0,
            omega_end: 402.0,
            max_points: 3,
            ..Default::default()
        },
        ..Default::default()
    };
    let problem = SweepProblem::new(&settings).expect("problem");
    let mut sink = MemorySink::new();
    problem.run(&mut sink, None, |_| {}).expect("sweep");
    let run = sink.run.as_ref().expect("run info");
    let p = &sink.points[0];
    assert!(!p.multipliers.is_empty() && p.stable == Some(true));

    let same = CoupledRederive::from_run(run).expect("rebuilds");
    let again = same.floquet(p).expect("recomputes").multipliers;
    let dev = multiplier_deviation(&p.multipliers, &again).expect("same count");
    assert!(
        dev < 1e-12,
        "recorded settings reproduce the stored multipliers: {dev:e}"
    );

    let fine = CoupledRederive::from_run_with_intervals(run, Some(2048)).expect("rebuilds");
    let finer = fine.floquet(p).expect("recomputes");
    let dev = multiplier_deviation(&p.multipliers, &finer.multipliers).expect("same count");
    assert!(
        dev > 0.0 && dev < 1e-2,
        "a finer product moves them a little: {dev:e}"
    );
    assert!(finer.stable);

    let err = CoupledRederive::from_run_with_intervals(run, Some(511))
        .err()
        .expect("odd count refused");
    assert!(err.to_string().contains("sip_intervals"), "{err}");
    // a count that would need gigabytes is refused before anything is allocated
    let err = CoupledRederive::from_run_with_intervals(run, Some(10_000_000))
        .err()
        .expect("huge count refused");
    assert!(err.to_string().contains("at most 200000"), "{err}");

    // The interval map is recorded; settings embedded before it was a setting (no
    // `interval_map` line) are re-derived with Strang's map, the one they were made with.
    assert!(
        run.settings_toml.contains("interval_map = \"exponential\""),
        "{}",
        run.settings_toml
    );
    let strang = StudySettings {
        floquet: FloquetSettings {
            interval_map: tmrotor::stability::IntervalMap::Strang,
            ..settings.floquet.clone()
        },
        ..settings.clone()
    };
    let mut sink_strang = MemorySink::new();
    SweepProblem::new(&strang)
        .expect("problem")
        .run(&mut sink_strang, None, |_| {})
        .expect("sweep");
    let p_strang = &sink_strang.points[0];
    let maps_differ = multiplier_deviation(&p.multipliers, &p_strang.multipliers).expect("count");
    assert!(maps_differ > 0.0, "the two maps are different products");
    let mut older = run.clone();
    older.settings_toml = run
        .settings_toml
        .lines()
        .filter(|l| !l.starts_with("interval_map"))
        .collect::<Vec<_>>()
        .join("\n");
    let again = CoupledRederive::from_run(&older)
        .expect("rebuilds")
        .floquet(p_strang)
        .expect("recomputes")
        .multipliers;
    let dev = multiplier_deviation(&p_strang.multipliers, &again).expect("same count");
    assert!(
        dev < 1e-12,
        "older recording re-derived with Strang's map: {dev:e}"
    );
}

/// The 5 L/min branch turns twice between 658 and 661 rad/s. Continued from 650 rad/s
/// with the default sweep's ω scale and a first step of 0.15, one step jumps over both
/// turns (ω falls over it while the tangent rises at both ends); that step must be
/// rejected, and the two folds come out as two saddle-nodes on the turning points of a
/// branch traced 30 times finer (folds are located from the tangent, without multipliers).
/// With the default limit on corrector iterations that step is refused for its five
/// iterations; without the limit, the fold-pair test must refuse it.
#[test]
fn a_step_over_a_fold_pair_is_refused_and_both_folds_are_located() {
    use tmrotor::continuation::{Continuation, ContinuationOptions, RejectReason, StepOutcome};
    use tmrotor::stability::BifurcationKind;
    // the literature values (folds at every flow rate; docs/calibration.md)
    let settings = StudySettings {
        model: Some(
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/models/dual_rotor_literature.toml"
            )
            .into(),
        ),
        operating: OperatingSettings {
            flow_l_min: 5.0,
            ..Default::default()
        },
        ..StudySettings::default()
    };
    let p = SweepProblem::new(&settings).expect("problem");
    let trace = |ds: f64, max_step_iterations: Option<usize>| {
        let hb = HarmonicBalance::new(&p.system, &p.basis, None).expect("hb");
        let mut opts = ContinuationOptions::new(650.0, 665.0);
        if let Some(m) = max_step_iterations {
            opts.max_step_iterations = m;
        }
        opts.ds_max = ds;
        opts.ds_initial = ds;
        opts.scale_omega = Some(400.0);
        opts.initial_guess = Some(p.system.initial_guess(p.basis.n_coeffs()));
        let mut cont = Continuation::new(hb, opts, None).expect("continuation");
        let (mut omegas, mut folds, mut fold_pairs) = (Vec::new(), Vec::new(), 0);
        loop {
            match cont.step().expect("step") {
                StepOutcome::Accepted {
                    point,
                    bifurcations,
                } => {
                    omegas.push(point.solution.omega);
                    for b in bifurcations {
                        assert_eq!(b.bifurcation, Some(BifurcationKind::SaddleNode));
                        folds.push(b.solution.omega);
                    }
                }
                StepOutcome::Rejected(RejectReason::FoldPair { omega_change, .. }) => {
                    assert!(omega_change < 0.0);
                    fold_pairs += 1;
                }
                StepOutcome::Rejected(_) => {}
                StepOutcome::Finished(_) => break,
            }
        }
        (omegas, folds, fold_pairs)
    };
    let (fine, _, _) = trace(0.005, None);
    let turns: Vec<f64> = fine
        .windows(3)
        .filter(|w| (w[1] - w[0]) * (w[2] - w[1]) < 0.0)
        .map(|w| w[1])
        .collect();
    assert_eq!(turns.len(), 2);
    for limit in [None, Some(usize::MAX)] {
        let (_, folds, fold_pairs) = trace(0.15, limit);
        eprintln!(
            "iteration limit {limit:?}: saddle-nodes {folds:?}, fine turning points {turns:?}, \
             {fold_pairs} steps refused as fold pairs"
        );
        if limit.is_some() {
            assert!(fold_pairs >= 1);
        }
        assert_eq!(folds.len(), 2);
        for (f, t) in folds.iter().zip(&turns) {
            // the fine branch's extreme point lies within its own step of the fold
            assert!(
                (f - t).abs() < 0.01,
                "saddle-node at {f}, fine turning point at {t}"
            );
        }
    }
}

/// A short sweep from 600 rad/s at 2 L/min, past the folds of the second resonance, which
/// needs a lead-in to reach its start.
fn inside_the_nonlinear_range() -> StudySettings {
    StudySettings {
        // the literature values (folds at every flow rate; docs/calibration.md)
        model: Some(
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/models/dual_rotor_literature.toml"
            )
            .into(),
        ),
        sweep: SweepSettings {
            omega_start: 600.0,
            omega_end: 601.0,
            max_points: 3,
            ..Default::default()
        },
        floquet: FloquetSettings {
            stability: false,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A sweep that starts inside the nonlinear range (600 rad/s at 2 L/min, past the folds
/// of the second resonance) cannot solve its start from the linear response; it reaches it
/// by continuation from a lower speed, and its first point is the one a sweep from that
/// speed arrives at.
#[test]
fn a_start_inside_the_nonlinear_range_is_reached_by_continuation() {
    use tmrotor::continuation::ContinuationError;
    let settings = inside_the_nonlinear_range();
    let problem = SweepProblem::new(&settings).expect("problem");
    // the premise: from the linear response the start does not converge
    let mut plain = problem.continuation(None).expect("continuation");
    assert!(matches!(plain.step(), Err(ContinuationError::Start { .. })));
    let mut sink = MemorySink::new();
    let report = problem.run(&mut sink, None, |_| {}).expect("sweep");
    let from = report.lead_in_from.expect("a lead-in");
    assert!(from < 600.0, "{from}");
    let first = &sink.points[0];
    assert_eq!(first.omega_rad_s, 600.0);
    // the reference: a sweep from the lead-in's speed, whose last point is re-solved on
    // 600 rad/s
    let reference = StudySettings {
        sweep: SweepSettings {
            omega_start: from,
            omega_end: 600.0,
            max_points: StudySettings::default().sweep.max_points,
            ..inside_the_nonlinear_range().sweep
        },
        floquet: FloquetSettings {
            stability: false,
            ..inside_the_nonlinear_range().floquet
        },
        ..inside_the_nonlinear_range()
    };
    let mut ref_sink = MemorySink::new();
    let ref_report = SweepProblem::new(&reference)
        .expect("problem")
        .run(&mut ref_sink, None, |_| {})
        .expect("reference sweep");
    assert!(ref_report.lead_in_from.is_none());
    let last = ref_sink.points.last().expect("points");
    assert_eq!(last.omega_rad_s, 600.0);
    for (a, b) in first.amplitude_rms_m.iter().zip(&last.amplitude_rms_m) {
        assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-9), "{a} vs {b}");
    }
}

/// The lead-in's steps run in the pools a campaign names, as the sweep's own steps do: a
/// campaign that widens the pool of its last running sweep widens its lead-in too.
#[test]
fn the_lead_in_steps_run_in_the_pools_the_caller_names() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use tmrotor::sweep::StepPools;

    struct Counting {
        pool: rayon::ThreadPool,
        in_lead_in: Arc<AtomicBool>,
        asked: AtomicUsize,
        asked_in_lead_in: AtomicUsize,
    }
    impl StepPools for Counting {
        fn for_next_step(&self) -> Option<&rayon::ThreadPool> {
            self.asked.fetch_add(1, Ordering::Relaxed);
            if self.in_lead_in.load(Ordering::Relaxed) {
                self.asked_in_lead_in.fetch_add(1, Ordering::Relaxed);
            }
            Some(&self.pool)
        }
    }
    let settings = inside_the_nonlinear_range();
    let problem = SweepProblem::new(&settings).expect("problem");
    let in_lead_in = Arc::new(AtomicBool::new(false));
    let pools = Counting {
        pool: rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool"),
        in_lead_in: in_lead_in.clone(),
        asked: AtomicUsize::new(0),
        asked_in_lead_in: AtomicUsize::new(0),
    };
    let mut sink = MemorySink::new();
    let flag = in_lead_in.clone();
    let report = problem
        .run_in(
            &mut sink,
            None,
            move |p| flag.store(p.lead_in, Ordering::Relaxed),
            &pools,
        )
        .expect("sweep");
    assert!(report.lead_in_from.is_some());
    let (asked, in_lead) = (
        pools.asked.load(Ordering::Relaxed),
        pools.asked_in_lead_in.load(Ordering::Relaxed),
    );
    assert!(
        in_lead >= 5,
        "{in_lead} of {asked} steps asked during the lead-in"
    );
    // the same start point as the sweep in the caller's pool
    let mut plain = MemorySink::new();
    problem.run(&mut plain, None, |_| {}).expect("sweep");
    assert_eq!(sink.points[0].coeffs_mech, plain.points[0].coeffs_mech);
}

/// `half_orders = false` (`--no-half-orders`): the dual rotor on the primary basis, the
/// paper's without `ω/2`. Its response repeats after `10π/ω` instead of `20π/ω`, so its
/// Floquet multipliers are taken over half the period: squared, they are the paper basis's
/// (whose response holds only a trace of `ω/2`, from the cage's varying compliance), and
/// the amplitudes agree to that trace.
#[test]
fn primary_basis_takes_half_the_period() {
    let run = |half_orders: bool| {
        let settings = StudySettings {
            harmonic: HarmonicSettings {
                half_orders,
                ..Default::default()
            },
            sweep: SweepSettings {
                omega_start: 400.0,
                omega_end: 402.0,
                max_points: 2,
                ..Default::default()
            },
            ..Default::default()
        };
        let problem = SweepProblem::new(&settings).expect("problem");
        let mut sink = MemorySink::new();
        problem.run(&mut sink, None, |_| {}).expect("sweep");
        sink
    };
    let (paper, primary) = (run(true), run(false));
    let (hp, hq) = (
        &paper.run.as_ref().expect("run").harmonics,
        &primary.run.as_ref().expect("run").harmonics,
    );
    let half = Ratio { num: 1, den: 2 };
    assert!(hp.contains(&half));
    assert!(!hq.contains(&half));
    assert_eq!(hq.len() + 1, hp.len());
    let (p, q) = (&paper.points[0], &primary.points[0]);
    assert_eq!(p.omega_rad_s, q.omega_rad_s);
    assert!((p.period_s - 2.0 * q.period_s).abs() < 1e-12 * p.period_s);
    let radius = |m: &[num_complex::Complex64]| m.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let (rp, rq) = (radius(&p.multipliers), radius(&q.multipliers));
    assert!(rp > 0.0 && rq > 0.0);
    assert!(
        (rp - rq * rq).abs() < 1e-2 * rp,
        "spectral radius {rp} (paper basis) vs {rq}² = {} (primary)",
        rq * rq
    );
    for (a, b) in p.amplitude_rms_m.iter().zip(&q.amplitude_rms_m) {
        assert!((a - b).abs() < 1e-2 * a.abs().max(1e-9), "{a} vs {b}");
    }
}
