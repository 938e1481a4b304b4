//! Parameter studies over the model file: a campaign's `set` tables (defaults, grid, runs)
//! and the sweep's `--set` edit values of the model file by path; bad paths and values stop
//! the campaign before anything runs, naming the run, the path and the reason; the values
//! are recorded in the manifest, the recording's settings and its embedded model, and
//! replay rebuilds the edited model.

use std::path::Path;

use tmrotor::campaign;
use tmrotor::derive::ModelRederive;
use tmrotor::derive::coupled::CoupledRederive;
use tmrotor::record::read_recording;

/// Short coupled runs (thermal network on), order 1, no stability: a grid over the 1#
/// bearing's Palmgren f_v, and a listed run with a wider 1# clearance.
const CAMPAIGN: &str = r#"
output_dir = "out"
[defaults]
order = 1
omega_start = 400.0
omega_end = 402.0
max_points = 2
stability = false
set."damping.damping_ratio" = 0.03

[grid]
name = "fv{thermal.bearings[1#].f_v}"
set."thermal.bearings[1#].f_v" = [2.0, 4.0]

[[runs]]
name = "wide"
set."bearings[1#].initial_clearance_m" = 5e-6
"#;

fn write(dir: &Path, text: &str) -> std::path::PathBuf {
    let path = dir.join("c.toml");
    std::fs::write(&path, text).expect("write campaign");
    path
}

#[test]
fn set_tables_merge_and_name_the_grid_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, runs, _) = campaign::load(&write(dir.path(), CAMPAIGN)).expect("load");
    let got: Vec<(&str, Vec<(String, String)>)> = runs
        .iter()
        .map(|r| {
            let set = r
                .settings
                .set
                .iter()
                .map(|(k, v)| (k.clone(), v.to_string()))
                .collect();
            (r.name.as_str(), set)
        })
        .collect();
    let pair = |k: &str, v: &str| (k.to_string(), v.to_string());
    assert_eq!(
        got,
        [
            (
                "fv2",
                vec![
                    pair("damping.damping_ratio", "0.03"),
                    pair("thermal.bearings[1#].f_v", "2.0")
                ]
            ),
            (
                "fv4",
                vec![
                    pair("damping.damping_ratio", "0.03"),
                    pair("thermal.bearings[1#].f_v", "4.0")
                ]
            ),
            (
                "wide",
                vec![
                    pair("bearings[1#].initial_clearance_m", "0.000005"),
                    pair("damping.damping_ratio", "0.03")
                ]
            ),
        ]
    );
}

#[test]
fn bad_paths_and_values_stop_the_campaign_before_anything_runs() {
    for (set, expected) in [
        (
            r#"set."thermal.bearings[9#].f_v" = 3.0"#,
            r#"no entry named "9#" (names: 1#, 2#, 3#, 4#)"#,
        ),
        (
            r#"set."thermal.bearings[1#].fv" = 3.0"#,
            "thermal.bearings[0].fv: unknown field `fv`",
        ),
        (
            r#"set."thermal.bearings[1#].f_v" = -3.0"#,
            "thermal.bearings[0].f_v: must be a finite number > 0",
        ),
        (
            r#"set."bearings[1#].initial_clearance_m" = "wide""#,
            "bearings[0].initial_clearance_m",
        ),
        (
            r#"set."thermal.viscositi.nu0_mm2_s" = 30.0"#,
            "`thermal` has no key `viscositi`",
        ),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let text = format!(
            "output_dir = \"out\"\n[defaults]\norder = 1\n[[runs]]\nname = \"ok\"\n\
             [[runs]]\nname = \"typo\"\n{set}\n"
        );
        let file = write(dir.path(), &text);
        let msg = campaign::plan(&file, None)
            .map(|_| ())
            .expect_err(set)
            .to_string();
        assert!(
            msg.contains("c.toml") && msg.contains("run typo") && msg.contains(expected),
            "{set}: {msg}"
        );
        assert!(
            !dir.path().join("out").exists(),
            "nothing is written: {set}"
        );
    }
}

#[test]
fn set_values_are_recorded_and_replay_rebuilds_the_edited_model() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write(dir.path(), CAMPAIGN);
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    let out = dir.path().join("out");
    let mut element_temp = Vec::new();
    for entry in &m.runs {
        assert_eq!(entry.status, "completed", "{entry:?}");
        // the manifest's settings carry the values
        let set = entry.settings["set"]
            .as_table()
            .expect("set in the manifest");
        assert_eq!(set["damping.damping_ratio"].as_float(), Some(0.03));
        let rec = read_recording(out.join(&entry.recording)).expect("recording");
        // … and the recording's settings, path by path
        assert!(
            rec.run
                .settings
                .iter()
                .any(|(k, v)| k == "set.damping.damping_ratio" && v == "0.03"),
            "{:?}",
            rec.run.settings
        );
        // the embedded model is the edited file, comments kept
        let model: toml::Table = rec.run.model_text.parse().expect("embedded model");
        assert_eq!(model["damping"]["damping_ratio"].as_float(), Some(0.03));
        assert!(rec.run.model_text.contains("# Table A.1, 1# ball bearing."));
        let clearance_1 = rec.run.bearings[0].initial_clearance_m;
        let fv_1 = model["thermal"]["bearings"][0]["f_v"].as_float();
        match entry.name.as_str() {
            "fv2" => assert_eq!((fv_1, clearance_1), (Some(2.0), 1e-6)),
            "fv4" => assert_eq!((fv_1, clearance_1), (Some(4.0), 1e-6)),
            "wide" => assert_eq!(clearance_1, 5e-6),
            other => panic!("unexpected run {other}"),
        }
        // replay rebuilds the edited model: its clearances equal the recorded ones
        let rederive = CoupledRederive::from_run(&rec.run).expect("rederive");
        let p = &rec.points[0];
        let again = rederive.bearings(p, 64).expect("bearings");
        for (a, b) in again.clearances.iter().zip(&p.clearances) {
            assert!(
                (a.effective_m - b.effective_m).abs() <= 1e-12,
                "{}: {} vs {}",
                entry.name,
                a.effective_m,
                b.effective_m
            );
        }
        let node = rec
            .run
            .thermal_nodes
            .iter()
            .position(|n| n.name == "1# rolling elements")
            .expect("1# elements node");
        element_temp.push((entry.name.clone(), p.temperatures[node].mean_c));
    }
    // twice the viscous friction coefficient heats the 1# rolling elements
    let t = |name: &str| {
        element_temp
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, t)| *t)
            .expect("run")
    };
    assert!(t("fv4") > t("fv2") + 1.0, "{element_temp:?}");
}

#[test]
fn the_command_line_sets_values_and_takes_negative_numbers() {
    let bin = env!("CARGO_BIN_EXE_tmrotor");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.mcap");
    let run = |args: &[&str]| {
        std::process::Command::new(bin)
            .args(args)
            .output()
            .expect("runs")
    };
    // a bad path fails at once, naming it, and writes nothing
    let o = run(&[
        "sweep",
        "--set",
        "thermal.bearings[9#].f_v=3",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("set thermal.bearings[9#].f_v") && err.contains("no entry named"),
        "{err}"
    );
    assert!(!out.exists());
    // `model check --set` makes the same checks
    let o = run(&[
        "model",
        "check",
        &format!("{}/models/dual_rotor.toml", env!("CARGO_MANIFEST_DIR")),
        "--set",
        "thermal.bearings[2#].f_v=-1",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("(edited by `set`)") && err.contains("thermal.bearings[1].f_v"),
        "{err}"
    );
    // a negative value of a flag is a value, not a flag
    let o = run(&[
        "sweep",
        "--cooling-temp",
        "-20",
        "--ambient-temp",
        "-5",
        "--order",
        "1",
        "--omega",
        "400:400.5",
        "--no-stability",
        "-q",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rec = read_recording(&out).expect("recording");
    assert!(
        rec.run
            .settings
            .iter()
            .any(|(k, v)| k == "cooling_temp_c" && v == "-20.0"),
        "{:?}",
        rec.run.settings
    );
}

#[test]
fn an_edited_model_file_runs_again_on_resume() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = dir.path().join("rotor.toml");
    std::fs::write(&model, tmrotor::model::BUILTIN_TOML).expect("model");
    let file = write(
        dir.path(),
        "output_dir = \"out\"\n[defaults]\nmodel = \"rotor.toml\"\norder = 1\n\
         omega_start = 400.0\nomega_end = 401.0\nmax_points = 2\nstability = false\n\
         [[runs]]\nname = \"a\"\n",
    );
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(1), None, None, &quiet).expect("campaign");
    assert_eq!(m.runs[0].status, "completed");
    assert_eq!(m.runs[0].model_sha256.len(), 64);
    let skip = |file: &Path| campaign::plan(file, None).expect("plan").0[0].skip;
    assert!(skip(&file), "unchanged: skipped");
    // the same settings, another model text: run again
    let edited =
        tmrotor::model::BUILTIN_TOML.replace("damping_ratio = 0.0325", "damping_ratio = 0.04");
    assert_ne!(edited, tmrotor::model::BUILTIN_TOML);
    std::fs::write(&model, edited).expect("model");
    assert!(!skip(&file), "edited model: runs again");
    let again = campaign::run(&file, Some(1), None, None, &quiet).expect("campaign");
    assert_ne!(again.runs[0].model_sha256, m.runs[0].model_sha256);
    assert!(skip(&file));
}
