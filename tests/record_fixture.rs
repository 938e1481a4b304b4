//! Recordings written by an earlier build (committed under `tests/fixtures/`, made by
//! `tools/make-fixtures.sh`) must stay readable and hold the closed-form synthetic values.

use std::path::Path;

use tmrotor::record::synthetic::{self, SyntheticOptions};
use tmrotor::record::{RunStatus, read_recording};

fn close(a: &[f64], b: &[f64], scale: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
}

fn check(file: &str, options: SyntheticOptions) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(file);
    let rec = read_recording(&path).expect("fixture readable");
    assert!(rec.complete && rec.status == Some(RunStatus::Completed));
    let want = synthetic::generate(&options);
    let mut run = rec.run.clone();
    run.tool_version = want.run.tool_version.clone();
    assert_eq!(run, want.run);
    assert_eq!(rec.points.len(), want.points.len());
    for (got, want) in rec.points.iter().zip(&want.points) {
        let s = want.amplitude_rms_m[0];
        assert_eq!(got.index, want.index);
        assert!((got.omega_rad_s - want.omega_rad_s).abs() <= 1e-12 * want.omega_rad_s);
        assert!(close(&got.amplitude_rms_m, &want.amplitude_rms_m, s));
        assert!(close(&got.coeffs_mech, &want.coeffs_mech, s));
        assert!(close(&got.orbits[0].x_m, &want.orbits[0].x_m, s));
        assert_eq!(got.stable, want.stable);
        assert_eq!(got.bifurcation, want.bifurcation);
        assert_eq!(got.temperatures.len(), want.temperatures.len());
    }
    assert_eq!(rec.bifurcations.len(), want.bifurcations.len());
}

#[test]
fn thermal_fixture_reads_back_the_closed_form_run() {
    check(
        "synthetic_v1.mcap",
        SyntheticOptions {
            points_per_side: 6,
            ..Default::default()
        },
    );
}

#[test]
fn mechanical_fixture_reads_back_the_closed_form_run() {
    check(
        "synthetic_mech_v1.mcap",
        SyntheticOptions {
            points_per_side: 4,
            thermal: false,
            ..Default::default()
        },
    );
}
