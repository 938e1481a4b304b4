//! `tmrotor transient` end to end: the recording on the time axis read back, and outputs
//! that would destroy an input or a non-file refused before any computing.

use std::process::Command;

use tmrotor::record::read_recording;

fn tmrotor() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tmrotor"))
}

#[test]
fn a_fixed_speed_run_is_recorded_on_the_time_axis() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("t.mcap");
    let status = tmrotor()
        .args([
            "transient",
            "--speed",
            "400",
            "--duration",
            "0.2",
            "-q",
            "-o",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let rec = read_recording(&out).expect("reads");
    assert!(rec.complete, "{:?}", rec.notes);
    assert!(rec.points.is_empty());
    let t = rec.transient.expect("transient records");
    let info = t.info.expect("info");
    assert_eq!(info.profile, "fixed speed 400 rad/s");
    // 0.2 s at 400 rad/s: 12.7 revolutions
    assert_eq!(t.revolutions.len(), 12);
    for (k, r) in t.revolutions.iter().enumerate() {
        assert_eq!(r.index, k as u64 + 1);
        let expected = (k + 1) as f64 * std::f64::consts::TAU / 400.0;
        assert!(
            (r.time_s - expected).abs() < 1e-3,
            "{} {}",
            r.time_s,
            expected
        );
        assert_eq!(r.amplitude_rms_m.len(), rec.run.nodes.len());
        assert_eq!(r.temperature_c.len(), rec.run.thermal_nodes.len());
        assert_eq!(r.bearing_load_n.len(), rec.run.bearings.len());
    }
    assert!(t.samples.len() >= 16 * 12, "{}", t.samples.len());
    assert!(t.samples.windows(2).all(|s| s[1].time_s > s[0].time_s));
}

#[test]
fn outputs_that_are_inputs_or_not_files_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = dir.path().join("m.toml");
    let text = tmrotor()
        .args(["model", "show"])
        .output()
        .expect("runs")
        .stdout;
    std::fs::write(&model, &text).expect("write");
    let before = std::fs::read(&model).expect("read");
    let run = |out: &std::path::Path| {
        tmrotor()
            .args([
                "transient",
                "--speed",
                "400",
                "--duration",
                "0.01",
                "-q",
                "--model",
            ])
            .arg(&model)
            .arg("-o")
            .arg(out)
            .output()
            .expect("runs")
    };
    let o = run(&model);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("is an input of this command"), "{err}");
    assert_eq!(std::fs::read(&model).expect("read"), before);
    let o = run(dir.path());
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("is a directory"));
    let o = run(std::path::Path::new("/dev/null"));
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a regular file"));
}

#[test]
fn replay_transient_draws_runs_and_names_their_steepest_change() {
    let dir = tempfile::tempdir().expect("tempdir");
    let run = dir.path().join("up.mcap");
    let o = tmrotor()
        .args([
            "transient",
            "--ramp",
            "400:420",
            "--accel",
            "100",
            "--samples-per-rev",
            "0",
            "-q",
            "-o",
        ])
        .arg(&run)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let figs = dir.path().join("figs");
    let o = Command::new(env!("CARGO_BIN_EXE_replay"))
        .arg("transient")
        .arg(&run)
        .args(["--node", "14", "--format", "svg", "--out"])
        .arg(&figs)
        .output()
        .expect("replay");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("up ") && text.contains("420.000"), "{text}");
    let csv = std::fs::read_to_string(figs.join("transient_amplitude.csv")).expect("csv");
    assert!(csv.lines().count() > 20, "{csv}");
    assert!(figs.join("transient_amplitude.svg").exists());
}

#[test]
fn a_start_along_a_floquet_mode_of_a_recorded_point() {
    let dir = tempfile::tempdir().expect("tempdir");
    let sweep = dir.path().join("s.mcap");
    // the default window's fold pair: its middle points are unstable
    let ok = tmrotor()
        .args(["sweep", "--omega", "521.6:522.0", "--no-verify", "-q", "-o"])
        .arg(&sweep)
        .output()
        .expect("runs");
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let rec = read_recording(&sweep).expect("sweep");
    let point = rec
        .points
        .iter()
        .find(|p| p.stable == Some(false))
        .expect("an unstable point")
        .index;
    let out = dir.path().join("t.mcap");
    let run = |extra: &[&str]| {
        tmrotor()
            .args(["transient", "--from"])
            .arg(&sweep)
            .args([
                "--point",
                &point.to_string(),
                "--duration",
                "0.05",
                "-q",
                "-o",
            ])
            .arg(&out)
            .args(extra)
            .output()
            .expect("runs")
    };
    // without a size: refused, naming the flag to give
    let refused = run(&["--perturb-mode", "0"]);
    assert!(!refused.status.success());
    let msg = String::from_utf8_lossy(&refused.stderr);
    assert!(msg.contains("--perturb"), "{msg}");
    // a mode the point does not have
    let refused = run(&["--perturb-mode", "999", "--perturb", "0.01"]);
    assert!(!refused.status.success());
    let msg = String::from_utf8_lossy(&refused.stderr);
    assert!(msg.contains("Floquet modes near zero"), "{msg}");
    let done = run(&["--perturb-mode", "0", "--perturb", "0.01"]);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let t = read_recording(&out)
        .expect("transient")
        .transient
        .expect("transient records");
    let start = t.info.expect("info").start;
    assert!(
        start.contains("perturbed along Floquet mode 0") && start.contains("multiplier modulus"),
        "{start}"
    );
}
