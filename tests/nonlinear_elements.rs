//! `[[nonlinear]]` elements of the model file through the whole pipeline: the Jeffcott
//! rotor with rub of `examples/rotors/jeffcott_rub.toml` swept by harmonic balance, its
//! orbits against direct time integration (Dormand–Prince) started on them and run to
//! steady state; the model file's checks of the elements. (The exact Jacobians of the laws
//! against finite differences: unit tests in `coupled::elements`.)

mod engine_support;

use tmrotor::integrate::{SteadyStateOptions, steady_state_with};
use tmrotor::model::{InvalidKind, Model};
use tmrotor::record::MemorySink;
use tmrotor::sweep::{
    FloquetSettings, HarmonicSettings, StudySettings, SweepProblem, SweepSettings,
};
use tmrotor::system::System;

fn example() -> std::path::PathBuf {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/rotors/jeffcott_rub.toml"
    )
    .into()
}

/// x(t) and ẋ(t) of every mechanical DoF from a point's coefficients.
fn state_at(problem: &SweepProblem, coeffs: &[f64], omega: f64, t: f64) -> (Vec<f64>, Vec<f64>) {
    let basis = &problem.basis;
    let (nc, h) = (basis.n_coeffs(), basis.n_harmonics());
    let n = coeffs.len() / nc;
    let mut x = vec![0.0; n];
    let mut v = vec![0.0; n];
    for d in 0..n {
        let c = &coeffs[d * nc..(d + 1) * nc];
        x[d] = c[0];
        for (k, r) in basis.harmonics().iter().enumerate() {
            let w = r.value() * omega;
            let (a, b) = (c[1 + k], c[1 + h + k]);
            x[d] += a * (w * t).cos() + b * (w * t).sin();
            v[d] += -a * w * (w * t).sin() + b * w * (w * t).cos();
        }
    }
    (x, v)
}

/// Sweeps `model` at `order` and checks stable points near `targets` against time
/// integration: the disk's x and y over a period within `tol` of the orbit's largest radius;
/// returns the numbers of rubbing and free points checked.
fn branch_matches_time_integration(
    model: std::path::PathBuf,
    order: u32,
    targets: &[f64],
    tol: f64,
) -> (usize, usize) {
    let settings = StudySettings {
        model: Some(model),
        harmonic: HarmonicSettings {
            order,
            ..Default::default()
        },
        sweep: SweepSettings {
            omega_start: 60.0,
            omega_end: 160.0,
            ..Default::default()
        },
        floquet: FloquetSettings::default(),
        ..Default::default()
    };
    let problem = SweepProblem::new(&settings).expect("problem");
    let mut sink = MemorySink::new();
    problem.run(&mut sink, None, |_| {}).expect("sweep");
    let gap = 5e-4;
    let disk_x = 0; // node 1: [x, y, θx, θy]
    let radius = |x: &[f64]| x[disk_x].hypot(x[disk_x + 1]);
    let mut checked = (0, 0);
    for &target in targets {
        let p = sink
            .points
            .iter()
            .filter(|p| p.stable == Some(true))
            .min_by(|a, b| {
                (a.omega_rad_s - target)
                    .abs()
                    .total_cmp(&(b.omega_rad_s - target).abs())
            })
            .expect("a stable point");
        let omega = p.omega_rad_s;
        let period = 2.0 * std::f64::consts::PI * f64::from(problem.basis.base_den()) / omega;
        let (x0, v0) = state_at(&problem, &p.coeffs_mech, omega, 0.0);
        let mut y0 = x0.clone();
        y0.extend(&v0);
        let opts = SteadyStateOptions {
            samples_per_period: 128,
            ..Default::default()
        };
        let ss =
            steady_state_with(&problem.system, omega, &y0, period, 100, &opts).expect("integrates");
        assert!(
            ss.periodicity_error < 1e-7,
            "at {omega}: not settled, {}",
            ss.periodicity_error
        );
        let n = problem.system.n_mech();
        let mut worst: f64 = 0.0;
        let mut r_max: f64 = 0.0;
        for (j, y) in ss.samples.iter().enumerate() {
            let t = ss.t0 + j as f64 * period / 128.0;
            let (x, _) = state_at(&problem, &p.coeffs_mech, omega, t);
            worst = worst.max(
                (x[disk_x] - y[disk_x])
                    .abs()
                    .max((x[disk_x + 1] - y[disk_x + 1]).abs()),
            );
            r_max = r_max.max(radius(&y[..n]));
        }
        let in_contact = r_max > gap;
        if in_contact {
            checked.0 += 1;
        } else {
            checked.1 += 1;
        }
        eprintln!(
            "ω = {omega:.3} rad/s: orbit radius up to {:.4} mm ({}), largest difference {:.3e} m ({:.2e} of it)",
            r_max * 1e3,
            if in_contact { "rubbing" } else { "free" },
            worst,
            worst / r_max
        );
        assert!(
            worst < tol * r_max,
            "at {omega}: HB and time integration differ by {worst}"
        );
    }
    checked
}

/// The example: an isotropic rotor, so the rubbing orbit is a circle at constant contact
/// force (full annular rub) and the balance is exact at any order: agreement to rounding.
#[test]
fn rub_branch_matches_time_integration() {
    let checked = branch_matches_time_integration(example(), 7, &[75.0, 100.0, 120.0, 140.0], 1e-8);
    assert!(
        checked.0 >= 2 && checked.1 >= 1,
        "rubbing and free points checked: {checked:?}"
    );
}

/// With an anisotropic support (k_y = 1.4 k_x) the orbit is an ellipse that touches the
/// stator twice a revolution (intermittent rub): the contact force is non-smooth in time,
/// the harmonic balance is truncated: at order 12 (harmonics up to 12ω) it stays within
/// 2e-3 of the radius (measured 5e-4 to 1e-3).
#[test]
fn intermittent_rub_converges_to_time_integration() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("aniso_rub.toml");
    std::fs::write(
        &path,
        edited(
            "stiffness_n_m = 1e5\n",
            "stiffness_xx_n_m = 1e5\nstiffness_yy_n_m = 1.4e5\n",
        ),
    )
    .expect("write");
    let checked = branch_matches_time_integration(path, 12, &[95.0, 110.0, 125.0], 2e-3);
    assert!(checked.0 >= 2, "rubbing points checked: {checked:?}");
}

fn edited(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(example()).expect("example");
    assert!(text.contains(from), "{from:?}");
    text.replacen(from, to, 1)
}

#[test]
fn element_keys_are_checked_by_kind() {
    let reject = |text: &str| Model::from_str(text, "rub.toml").expect_err("refused");
    // a key of another kind
    let e = reject(&edited(
        "friction_coefficient = 0.05",
        "friction_coefficient = 0.05\ndirection_deg = 30.0",
    ));
    assert_eq!(e.path(), Some("nonlinear[0].direction_deg"), "{e}");
    assert!(
        e.to_string().contains("a rub element has no direction_deg"),
        "{e}"
    );
    // a missing key
    let e = reject(&edited("gap_m = 5e-4\n", ""));
    assert_eq!(e.path(), Some("nonlinear[0].gap_m"), "{e}");
    assert!(matches!(e.kind(), Some(InvalidKind::MissingKey(_))), "{e}");
    // a value out of range
    let e = reject(&edited("stiffness_n_m = 1e6", "stiffness_n_m = -1e6"));
    assert_eq!(e.path(), Some("nonlinear[0].stiffness_n_m"), "{e}");
    // an unknown kind
    let e = reject(&edited("kind = \"rub\"", "kind = \"squeeze\""));
    assert!(e.to_string().contains("squeeze"), "{e}");
    // a polynomial and a unilateral element load
    let poly = edited(
        "kind = \"rub\"\nnode = 1\ngap_m = 5e-4\nstiffness_n_m = 1e6\nfriction_coefficient = 0.05",
        "kind = \"polynomial\"\nnode = 1\ncoefficients = [0.0, 0.0, 1e13]",
    );
    Model::from_str(&poly, "cubic.toml").expect("polynomial");
    let stop = edited(
        "kind = \"rub\"\nnode = 1\ngap_m = 5e-4\nstiffness_n_m = 1e6\nfriction_coefficient = 0.05",
        "kind = \"unilateral\"\nnode = 1\ngap_m = 1e-4\nstiffness_n_m = 1e7\ndirection_deg = -90.0",
    );
    Model::from_str(&stop, "stop.toml").expect("unilateral");
}

/// NLvib's two-mass contact benchmark written as a model file
/// (`examples/rotors/two_mass_contact.toml`: disks as masses, supports as springs, a
/// unilateral element, a `[[forces]]` entry) and continued exactly as
/// `tests/engine_contact.rs` continues the hand-written system (H = 21 integer harmonics,
/// 1024 AFT samples, shooting): the same published folds (0.6534401, 0.755664) and
/// Neimark–Sacker point (0.618354).
#[test]
fn two_mass_contact_model_file_gives_the_published_bifurcations() {
    use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};

    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/rotors/two_mass_contact.toml"
    );
    let model = Model::from_file(path).expect("model");
    let system = CoupledRotor::new(
        &model,
        &StudyOverrides::default(),
        CouplingOptions::default(),
    )
    .expect("system");
    engine_support::contact_benchmark(&system);
}
