//! The truncation study on the dual rotor (cheap configuration) and its command line.

use clap::Parser;
use tmrotor::cli::{Cli, Command};
use tmrotor::sweep::{StudySettings, SweepSettings};
use tmrotor::truncation::{self, TruncationOptions};

/// Orders 1 and 2 at ω = 400 rad/s, each reached by continuation over a short range: the
/// residual of the equations at the 3# bearing (node 8) and overall falls with the order,
/// while the HPC disk (node 14, no nonlinear force) is balanced to rounding at both orders
/// — the harmonic balance solves linear DoFs exactly in the retained harmonics, and their
/// loads (unbalance, gravity) lie in the basis.
#[test]
fn dual_rotor_residual_falls_from_order_one_to_two() {
    let settings = StudySettings {
        sweep: SweepSettings {
            omega_start: 398.0,
            omega_end: 402.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let opts = TruncationOptions {
        orders: vec![1, 2],
        omegas_rad_s: vec![400.0],
        ..Default::default()
    };
    let report = truncation::run(&settings, &opts, |_| {}).expect("study");
    assert!(report.missed.is_empty() && report.unreached.is_empty());
    assert_eq!(report.rows.len(), 2);
    let (r1, r2) = (&report.rows[0], &report.rows[1]);
    assert_eq!((r1.order, r2.order), (1, 2));
    for r in [r1, r2] {
        assert_eq!(r.omega_rad_s, 400.0);
        assert_eq!((r.solution, r.solutions, r.crossings), (1, 1, 1));
        // the time-domain residual measures truncation, not the Newton tolerance: it is
        // far above the harmonic-balance residual the solution converged to
        assert!(r.residual_mech_n.rms > 1e3 * r.hb_residual.mech);
        // linear node: rounding only, relative to the bearing node
        assert!(r.residual_node_n[1].rms < 1e-9 * r.residual_node_n[0].rms);
        // the bearing node's residual is a small part of its nonlinear force
        assert!(r.residual_node_n[0].rms < 0.1 * r.nonlinear_node_n[0].rms);
        assert!(r.temperature_c.iter().all(|t| *t > 25.0));
    }
    let fall = |a: f64, b: f64| b < 0.8 * a;
    assert!(
        fall(r1.residual_node_n[0].rms, r2.residual_node_n[0].rms),
        "node 8: {:?} → {:?}",
        r1.residual_node_n[0],
        r2.residual_node_n[0]
    );
    assert!(
        fall(r1.residual_mech_n.rms, r2.residual_mech_n.rms),
        "mechanical: {:?} → {:?}",
        r1.residual_mech_n,
        r2.residual_mech_n
    );
    assert!(r2.residual_therm_w.rms < r1.residual_therm_w.rms);
    // the response itself barely changes between the orders at this speed
    assert!((r1.amplitude_m[0] - r2.amplitude_m[0]).abs() < 0.05 * r2.amplitude_m[0]);

    let md = truncation::markdown(&report);
    assert_eq!(md.lines().count(), 4, "{md}");
    assert!(
        md.lines()
            .next()
            .is_some_and(|h| h.contains("r node 8 (N)"))
    );
    let csv = truncation::csv(&report);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3);
    let cols = lines[0].split(',').count();
    assert!(lines.iter().all(|l| l.split(',').count() == cols));
}

fn resolve(args: &[&str]) -> anyhow::Result<(StudySettings, TruncationOptions)> {
    let cli = Cli::try_parse_from(["tmrotor", "truncation"].iter().chain(args))?;
    match cli.command {
        Some(Command::Truncation(a)) => a.resolve(),
        _ => anyhow::bail!("not the truncation command"),
    }
}

#[test]
fn command_line_defaults_are_the_paper_points() {
    let (s, o) = resolve(&[]).expect("defaults");
    assert_eq!(o.orders, vec![1, 2, 3, 4]);
    assert_eq!(o.omegas_rad_s, vec![400.0, 484.0, 530.0, 584.0]);
    // no nodes named: the model's own (8, 14 and 41, 58 for the dual rotor, see
    // default_nodes_come_from_the_model_at_hand)
    assert!(o.dynamic_nodes.is_empty() && o.thermal_nodes.is_empty());
    assert_eq!(
        (s.operating.flow_l_min, s.operating.cooling_temp_c),
        (2.0, 25.0)
    );
    assert!(!s.floquet.stability);
    let (s, o) = resolve(&["--flow", "20", "--orders", "2, 3", "--omega", "450"]).expect("ok");
    assert_eq!(
        (s.operating.flow_l_min, o.orders, o.omegas_rad_s),
        (20.0, vec![2, 3], vec![450.0])
    );
}

#[test]
fn bad_command_line_input_names_the_option() {
    for (args, option, reason) in [
        (&["--orders", "0,2"][..], "--orders", "between 1 and 12"),
        (&["--orders", "one"][..], "--orders", "not a whole number"),
        (
            &["--omega", "800"][..],
            "--omega",
            "outside the traced range",
        ),
        (&["--omega", "fast"][..], "--omega", "not a number"),
        (
            &["--range", "500:400"][..],
            "--range",
            "END must exceed START",
        ),
        (&["--range", "500"][..], "--range", "START:END"),
        (&["--nodes", ""][..], "--nodes", "comma-separated list"),
    ] {
        let msg = resolve(args).expect_err("must fail").to_string();
        assert!(
            msg.contains(option) && msg.contains(reason),
            "{args:?}: {msg}"
        );
    }
    // a downward study range (from a study file) is refused by the study itself
    let down = StudySettings {
        sweep: SweepSettings {
            omega_start: 700.0,
            omega_end: 300.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let msg = truncation::run(&down, &TruncationOptions::default(), |_| {})
        .expect_err("downward")
        .to_string();
    assert!(msg.contains("traced upwards"), "{msg}");
    // a node the model does not have is reported by the study itself
    let settings = StudySettings {
        sweep: SweepSettings {
            omega_start: 398.0,
            omega_end: 402.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let opts = TruncationOptions {
        orders: vec![1],
        omegas_rad_s: vec![400.0],
        dynamic_nodes: vec![99],
        ..Default::default()
    };
    let msg = truncation::run(&settings, &opts, |_| {})
        .expect_err("no node 99")
        .to_string();
    assert!(msg.contains("dynamic node 99"), "{msg}");
}

/// At exactly ω = 484 rad/s the order-1 Newton stalls just above its tolerance (a bearing
/// contact event on an AFT sample, see the module docs); the study then reports the
/// nearest nudged speed that converges, and says so, instead of a missing row. Whether it
/// stalls depends on the start guess, interpolated from the branch points around the
/// target: traced over 482–486 rad/s the chord iterations converge there, over 470–500
/// rad/s they stall.
#[test]
fn a_stalled_target_is_reported_at_the_nearest_converged_speed() {
    // on the literature values (docs/calibration.md), where the stall was found
    let settings = StudySettings {
        model: Some(
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/models/dual_rotor_literature.toml"
            )
            .into(),
        ),
        sweep: SweepSettings {
            omega_start: 470.0,
            omega_end: 500.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let opts = TruncationOptions {
        orders: vec![1],
        omegas_rad_s: vec![484.0],
        ..Default::default()
    };
    let report = truncation::run(&settings, &opts, |_| {}).expect("study");
    assert!(report.missed.is_empty(), "{:?}", report.missed);
    assert_eq!(report.rows.len(), 1);
    let r = &report.rows[0];
    assert_eq!(r.target_rad_s, 484.0);
    assert!((r.omega_rad_s - 484.0).abs() <= 0.05, "{}", r.omega_rad_s);
    // the row's solution is converged at the speed it reports
    assert!(r.hb_residual.mech > 0.0);
    // the fallback is exercised here (should the model become smooth at this point, the
    // test needs another stalled speed to cover it)
    assert_ne!(r.omega_rad_s, 484.0, "Newton no longer stalls at 484 rad/s");
    let md = truncation::markdown(&report);
    assert!(md.contains("484 → "), "{md}");
}

/// A model of the user's own gets its own default nodes: its disks, then its bearings'
/// shaft-side nodes (the paper's 8 and 14 belong to the dual rotor's numbering).
#[test]
fn default_nodes_come_from_the_model_at_hand() {
    use tmrotor::model::Model;
    use tmrotor::truncation::{default_dynamic_nodes, default_thermal_nodes};
    let builtin = Model::builtin().expect("the built-in model");
    assert_eq!(default_dynamic_nodes(&builtin), vec![8, 14]);
    assert_eq!(default_thermal_nodes(&builtin), vec![41, 58]);
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/rotors/two_disk_ball_bearings.toml"
    );
    let own = Model::from_file(path).expect("the example model");
    let disks: Vec<u32> = own.spec.disks.iter().map(|d| d.node).collect();
    let bearings: Vec<u32> = own.spec.bearings.iter().map(|b| b.inner_node).collect();
    let nodes = default_dynamic_nodes(&own);
    assert_eq!(&nodes[..disks.len()], &disks[..]);
    assert!(bearings.iter().all(|b| nodes.contains(b)), "{nodes:?}");
    assert!(default_thermal_nodes(&own).is_empty());
}
