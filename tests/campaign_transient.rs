//! Transient runs in a campaign file (`transient = { … }` in a run): run beside the
//! sweeps, recorded on the time axis, listed in the manifest in revolutions, resumed (a
//! completed transient is not run again; a changed one is, alone), and left out of the
//! campaign figures and the report, which draw branches. A bad `transient` table is
//! refused before anything runs, naming the run and the key.

use std::path::Path;
use std::process::Command;

use tmrotor::campaign::figures::read_manifest_file;

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
