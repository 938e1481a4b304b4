//! Transient runs in a campaign file (`transient = { … }` in a run): run beside the
//! sweeps, recorded on the time axis, listed in the manifest in revolutions, resumed (a
//! completed transient is not run again; a changed one is, alone), and left out of the
//! campaign figures and the report, which draw branches. A bad `transient` table is
//! refused before anything runs, naming the run and the key.

use std::path::Path;
use std::process::Command;

use tmrotor::campaign::read_manifest_file;

fn tmrotor(args: &[&str], dir: &Path) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("runs");
    (
        o.status.success(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    )
}

fn campaign(duration: f64) -> String {
    format!(
        "output_dir = \"c-out\"\n[defaults]\norder = 1\nverify = false\n\n\
         [[runs]]\nname = \"sweep\"\nomega_start = 400.0\nomega_end = 410.0\n\n\
         [[runs]]\nname = \"fixed\"\ntransient = {{ speed = 400.0, duration_s = {duration} }}\n\n\
         [[runs]]\nname = \"ramp\"\ntransient = {{ ramp = \"400:405\", accel = 50.0 }}\n"
    )
}

#[test]
fn transient_runs_run_resume_and_stay_out_of_the_figures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::write(d.join("c.toml"), campaign(0.2)).expect("write");
    let (ok, text) = tmrotor(&["campaign", "c.toml"], d);
    assert!(ok, "{text}");
    let m = read_manifest_file(&d.join("c-out/manifest.toml")).expect("manifest");
    assert_eq!(m.runs.len(), 3);
    for e in &m.runs {
        assert_eq!(e.status, "completed", "{e:?}");
    }
    let fixed = m.runs.iter().find(|e| e.name == "fixed").expect("fixed");
    assert!(fixed.is_transient());
    // 0.2 s at 400 rad/s: 12.7 revolutions, the whole ones recorded
    assert_eq!(fixed.points, 12, "{fixed:?}");
    assert!(text.contains("12 revolutions"), "{text}");
    let ramp = m.runs.iter().find(|e| e.name == "ramp").expect("ramp");
    assert!(ramp.ended.contains("405.000 rad/s at the end"), "{ramp:?}");
    // the recording is a transient one
    let replay = Command::new(env!("CARGO_BIN_EXE_replay"))
        .arg("info")
        .arg(d.join("c-out/ramp.mcap"))
        .output()
        .expect("replay");
    let info = String::from_utf8_lossy(&replay.stdout);
    assert!(info.contains("transient:"), "{info}");
    // the figures and the report drew the sweep alone
    assert!(d.join("c-out/figures").is_dir(), "{text}");
    let (ok, report) = tmrotor(&["report", "c-out", "-o", "r.md"], d);
    assert!(ok, "{report}");
    let md = std::fs::read_to_string(d.join("r.md")).expect("report");
    assert!(!md.contains("ramp.mcap") && !md.contains("| ramp"), "{md}");
    // resume: nothing to do
    let (ok, text) = tmrotor(&["campaign", "c.toml", "--no-figures"], d);
    assert!(ok, "{text}");
    assert_eq!(text.matches("not redone").count(), 3, "{text}");
    // a changed transient runs again, alone
    std::fs::write(d.join("c.toml"), campaign(0.3)).expect("write");
    let (ok, text) = tmrotor(&["campaign", "c.toml", "--no-figures"], d);
    assert!(ok, "{text}");
    assert_eq!(text.matches("not redone").count(), 2, "{text}");
    assert!(text.contains("fixed: completed, 19 revolutions"), "{text}");
}

#[test]
fn a_bad_transient_table_is_refused_with_the_run_and_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    for (table, needle) in [
        ("{ speed = 400.0, ramp = \"1:2\" }", "not both"),
        ("{ spede = 400.0 }", "unknown field `spede`"),
        ("{ ramp = \"400:300\", accel = -1.0 }", "accel"),
        ("{ ramp = \"x\" }", "START:END"),
        ("{ speed = 400.0, duration_s = 0.0 }", "duration_s"),
        ("{ speed = 400.0, accel = 1.0 }", "only with a ramp"),
    ] {
        std::fs::write(
            d.join("bad.toml"),
            format!("[[runs]]\nname = \"t\"\ntransient = {table}\n"),
        )
        .expect("write");
        let (ok, text) = tmrotor(&["campaign", "bad.toml", "--dry-run"], d);
        assert!(!ok, "{table}: accepted");
        assert!(
            text.contains("bad.toml: runs[0]: transient") && text.contains(needle),
            "{table}: {text}"
        );
    }
}

/// A transient run from a point of a sweep run of the same campaign: it waits for that run
/// (listed after it here, two at a time), starts on the point's orbit and holds the point's
/// speed, and runs again when the sweep does. Once its RMS window is full, its amplitudes
/// are the point's (Eq. 35), where a cold start at the same speed is far from them; its
/// temperatures are the point's from the first revolution.
#[test]
fn a_transient_run_starts_on_a_point_of_a_sweep_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let file = |end: f64| {
        format!(
            "output_dir = \"c-out\"\n[defaults]\norder = 3\ncombination_tones = true\n\
             verify = false\n\n\
             [[runs]]\nname = \"from-3\"\n\
             transient = {{ from = \"sweep\", point = 3, duration_s = 0.3 }}\n\n\
             [[runs]]\nname = \"cold\"\ntransient = {{ speed = 400.9, duration_s = 0.3 }}\n\n\
             [[runs]]\nname = \"sweep\"\nomega_start = 400.0\nomega_end = {end}\n"
        )
    };
    std::fs::write(d.join("c.toml"), file(410.0)).expect("write");
    let (ok, text) = tmrotor(&["campaign", "c.toml", "--threads", "2", "--no-figures"], d);
    assert!(ok, "{text}");
    let m = read_manifest_file(&d.join("c-out/manifest.toml")).expect("manifest");
    for e in &m.runs {
        assert_eq!(e.status, "completed", "{e:?}");
    }
    let sweep = tmrotor::record::read_recording(d.join("c-out/sweep.mcap")).expect("sweep");
    let point = sweep.point(3).expect("point 3");
    assert!(
        (point.omega_rad_s - 400.9).abs() < 0.5,
        "{}",
        point.omega_rad_s
    );
    let largest = point.amplitude_rms_m.iter().copied().fold(0.0, f64::max);
    // the largest difference from the point's amplitudes, relative to the largest
    // amplitude, over the revolutions whose RMS window is full
    let off = |run: &str| {
        let rec = tmrotor::record::read_recording(d.join(format!("c-out/{run}.mcap")))
            .expect("transient");
        let t = rec.transient.expect("transient records");
        let info = t.info.expect("info");
        let full = t
            .revolutions
            .iter()
            .filter(|r| r.index >= u64::from(info.window_revolutions));
        let worst = full
            .flat_map(|r| r.amplitude_rms_m.iter().zip(&point.amplitude_rms_m))
            .map(|(a, b)| (a - b).abs() / largest)
            .fold(0.0, f64::max);
        (worst, info, t.revolutions)
    };
    let (worst, info, revolutions) = off("from-3");
    assert!(info.start.contains("point 3 of"), "{}", info.start);
    assert_eq!(
        info.profile,
        format!("fixed speed {} rad/s", point.omega_rad_s)
    );
    // the balance with combination tones against the time response at rtol 1e-4: 1.1–1.3 %
    // here (the integrator's tolerance alone moves amplitudes by 0.6 %, docs/transient.md)
    assert!(worst < 0.02, "{worst}");
    let (cold, _, _) = off("cold");
    assert!(cold > 0.1, "the cold start is as close: {cold}");
    let first = revolutions.first().expect("a revolution");
    assert_eq!(first.temperature_c.len(), point.temperatures.len());
    for (a, b) in first.temperature_c.iter().zip(&point.temperatures) {
        assert!(
            (a - b.mean_c).abs() < 0.05,
            "{a} °C against {} °C",
            b.mean_c
        );
    }
    // resumed: nothing to do; the sweep changed: it and the run from it run again
    let (ok, text) = tmrotor(&["campaign", "c.toml", "--no-figures"], d);
    assert!(ok, "{text}");
    assert_eq!(text.matches("not redone").count(), 3, "{text}");
    std::fs::write(d.join("c.toml"), file(412.0)).expect("write");
    let (ok, text) = tmrotor(&["campaign", "c.toml", "--no-figures"], d);
    assert!(ok, "{text}");
    assert_eq!(text.matches("not redone").count(), 1, "{text}");
    assert!(text.contains("cold: completed before"), "{text}");
}

#[test]
fn a_transient_run_from_a_point_names_a_sweep_run_and_takes_its_settings() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    for (runs, needle) in [
        (
            "[[runs]]\nname = \"t\"\ntransient = { from = \"nosuch\", point = 1 }\n",
            "the campaign has no run of that name",
        ),
        (
            "[[runs]]\nname = \"a\"\ntransient = { speed = 400.0 }\n\
             [[runs]]\nname = \"t\"\ntransient = { from = \"a\", point = 1 }\n",
            "that run is a transient run",
        ),
        (
            "[[runs]]\nname = \"s\"\n\
             [[runs]]\nname = \"t\"\nflow_l_min = 2.0\ntransient = { from = \"s\", point = 1 }\n",
            "flow_l_min: a transient run from a recorded point takes the model and settings",
        ),
        (
            "[[runs]]\nname = \"t\"\ntransient = { from = \"s\" }\n",
            "give the point to start on",
        ),
        (
            "[[runs]]\nname = \"t\"\ntransient = { speed = 400.0, perturb = 0.1 }\n",
            "only with from and point",
        ),
        (
            "[[runs]]\nname = \"s\"\n\
             [[runs]]\nname = \"t\"\ntransient = { from = \"s\", point = 1, perturb_mode = 0 }\n",
            "give the size with perturb",
        ),
    ] {
        std::fs::write(d.join("bad.toml"), runs).expect("write");
        let (ok, text) = tmrotor(&["campaign", "bad.toml", "--dry-run"], d);
        assert!(!ok, "{runs}: accepted");
        assert!(
            text.contains("bad.toml") && text.contains(needle),
            "{runs}: {text}"
        );
    }
}
