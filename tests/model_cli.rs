//! The `model`, `modes` and `campbell` commands, in-process and as a process.

use std::process::Command as Process;

use clap::Parser;
use tmrotor::cli::{Cli, Command, campbell, model, modes};
use tmrotor::linear;
use tmrotor::model::{Assembly, BUILTIN_TOML, Model};

const BIN: &str = env!("CARGO_BIN_EXE_tmrotor");

fn example(name: &str) -> String {
    format!("{}/examples/rotors/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn parse(args: &[&str]) -> Command {
    Cli::try_parse_from(args)
        .expect("arguments parse")
        .command
        .expect("a subcommand")
}

#[test]
fn modes_csv_in_process_matches_library() {
    let Command::Modes(args) = parse(&[
        "tmrotor", "modes", "--speed", "500", "--count", "6", "--csv",
    ]) else {
        panic!("not modes")
    };
    let mut out = Vec::new();
    modes::run(&args, &mut out).expect("runs");
    let text = String::from_utf8(out).expect("utf-8");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "mode,frequency_rad_s,frequency_hz,damping_ratio,whirl,undamped_rad_s,log_decrement,forward_share"
        )
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 6);
    let asm = Assembly::new(&Model::builtin().expect("model")).expect("assembles");
    let lib = linear::modes(&asm, 500.0, 6).expect("modes");
    for (row, m) in rows.iter().zip(&lib) {
        let f: f64 = row[1].parse().expect("number");
        let hz: f64 = row[2].parse().expect("number");
        assert!((f - m.frequency_rad_s).abs() < 1e-5);
        assert!((hz * 2.0 * std::f64::consts::PI - f).abs() < 1e-4);
        assert!(["forward", "backward", "planar"].contains(&row[4].as_str()));
        let dec: f64 = row[6].parse().expect("number");
        assert!((dec - m.log_decrement()).abs() < 1e-5);
    }
}

#[test]
fn bad_arguments_are_rejected() {
    assert!(Cli::try_parse_from(["tmrotor", "modes", "--speed", "fast"]).is_err());
    assert!(
        Cli::try_parse_from(["tmrotor", "campbell"]).is_err(),
        "--speeds is required"
    );
    for bad in ["0:100", "100:0:5", "0:100:1", "a:b:c", "0:100:-3"] {
        assert!(campbell::parse_speeds(bad).is_err(), "{bad}");
    }
    assert_eq!(
        campbell::parse_speeds("0:100:5").expect("ok"),
        vec![0.0, 25.0, 50.0, 75.0, 100.0]
    );
}

/// Each reported critical speed, checked by a second computation: the modes at that
/// speed have the mode's frequency on the excitation line.
#[test]
fn campbell_critical_speeds_lie_on_the_excitation_lines() {
    let Command::Campbell(args) = parse(&[
        "tmrotor",
        "campbell",
        "--model",
        &example("jeffcott_midspan_disk.toml"),
        "--speeds",
        "0:300:61",
        "--count",
        "4",
    ]) else {
        panic!("not campbell")
    };
    let mut out = Vec::new();
    campbell::run(&args, &mut out).expect("runs");
    let text = String::from_utf8(out).expect("utf-8");
    assert!(text.contains("1×rotor"), "{text}");

    let model = Model::from_file(example("jeffcott_midspan_disk.toml")).expect("model");
    let asm = Assembly::new(&model).expect("assembles");
    let speeds = linear::speed_grid(0.0, 300.0, 61).expect("grid");
    let c = linear::campbell(&asm, &speeds, 4).expect("campbell");
    // Jeffcott: translation at √(k/m) = 22.24 rad/s is crossed by 1× at 22.24 rad/s
    // (forward and backward translation coincide); the forward tilt mode rises faster
    // than 1× (J_p/J_d = 2) and is never crossed; the backward tilt (157 → 38.7 rad/s)
    // is crossed once.
    assert!(!c.critical_speeds.is_empty());
    // Tolerance 1e-5: this example's near-massless shaft next to 1e12 N/m supports puts
    // the eigenvalue noise of its (degenerate) translation pair at ~1e-6.
    for cs in &c.critical_speeds {
        let line = cs.speed_ratio * cs.speed_rad_s;
        let m = linear::modes(&asm, cs.speed_rad_s, 8).expect("modes");
        assert!(
            m.iter()
                .any(|m| (m.frequency_rad_s - line).abs() < 1e-5 * line),
            "{cs:?}: no mode at {line} rad/s"
        );
    }
    assert!(
        c.critical_speeds
            .iter()
            .any(|cs| (cs.speed_rad_s - 22.2417).abs() < 0.05)
    );
}

#[test]
fn model_show_prints_the_builtin_file_as_a_process() {
    let out = Process::new(BIN)
        .args(["model", "show"])
        .output()
        .expect("runs");
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout), BUILTIN_TOML);
    // In-process too.
    let Command::Model(cmd) = parse(&["tmrotor", "model", "show"]) else {
        panic!("not model")
    };
    let mut buf = Vec::new();
    model::run(&cmd, &mut buf).expect("runs");
    assert_eq!(buf, BUILTIN_TOML.as_bytes());
}

#[test]
fn model_check_as_a_process() {
    let out = Process::new(BIN)
        .args(["model", "check", &example("uniform_shaft_pinned.toml")])
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("ok"));

    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        BUILTIN_TOML.replacen("inner_node = 12", "inner_node = 40", 1),
    )
    .expect("write");
    let out = Process::new(BIN)
        .args(["model", "check"])
        .arg(&bad)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml")
            && err.contains("bearings[1].inner_node")
            && err.contains("node 40"),
        "{err}"
    );
}

/// `model check` also runs the thermal layer's checks: a wrong value in the `[thermal]`
/// table is named by its field path (the table is re-read from the parsed file, so a line
/// number would be the wrong one), and a good table is summarised.
#[test]
fn model_check_checks_the_thermal_table() {
    let dir = tempfile::tempdir().expect("tempdir");
    let check = |name: &str, text: String| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write");
        Process::new(BIN)
            .args(["model", "check"])
            .arg(&path)
            .output()
            .expect("runs")
    };
    let good = check("good.toml", BUILTIN_TOML.to_string());
    assert!(good.status.success());
    let stdout = String::from_utf8_lossy(&good.stdout);
    assert!(
        stdout.contains("thermal:  66 nodes, 4 bearings; flow 2 L/min"),
        "{stdout}"
    );
    // the thermal table's first shaft (a one-node list; the mechanical shafts name two)
    let first_shaft = "length_m = 12e-3\nnodes = [1]";
    for (name, from, to, path, reason) in [
        (
            "type.toml",
            "n_nodes = 66",
            "n_nodes = \"66\"",
            "thermal.n_nodes",
            "invalid type",
        ),
        (
            "nested.toml",
            first_shaft,
            "length_m = \"12 mm\"\nnodes = [1]",
            "thermal.shafts[0].length_m",
            "invalid type",
        ),
        (
            "range.toml",
            "flow_l_min = 2.0",
            "flow_l_min = -2.0",
            "thermal.flow_l_min",
            "-2",
        ),
    ] {
        assert!(BUILTIN_TOML.contains(from), "{from}");
        let out = check(name, BUILTIN_TOML.replacen(from, to, 1));
        assert_eq!(out.status.code(), Some(1), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(name) && err.contains(path) && err.contains(reason),
            "{name}: {err}"
        );
        assert!(!err.contains("line "), "{name}: {err}");
    }
}

#[test]
fn modes_and_campbell_as_a_process() {
    let out = Process::new(BIN)
        .args([
            "modes",
            "--model",
            &example("uniform_shaft_pinned.toml"),
            "--count",
            "2",
            "--csv",
        ])
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let first: f64 = text
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').nth(1))
        .and_then(|v| v.parse().ok())
        .expect("a frequency");
    // Exact Timoshenko value in the file header: 739.92 rad/s.
    assert!((first - 739.92).abs() < 0.01 * 739.92, "{first}");

    let dir = tempfile::tempdir().expect("tempdir");
    let csv = dir.path().join("campbell.csv");
    let out = Process::new(BIN)
        .args(["campbell", "--speeds", "300:700:9", "--count", "4", "--csv"])
        .arg(&csv)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = std::fs::read_to_string(&csv).expect("csv written");
    let mut lines = table.lines();
    assert_eq!(
        lines.next(),
        Some(
            "speed_rad_s,mode,frequency_rad_s,frequency_hz,damping_ratio,log_decrement,whirl,forward_share,mac"
        )
    );
    assert_eq!(lines.count(), 9 * 4);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("1×LP") && stdout.contains("1×HP"),
        "{stdout}"
    );

    let out = Process::new(BIN)
        .args(["campbell", "--speeds", "700:300:9"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
}

/// On the built-in dual rotor the refined crossings hold to 1e-8: the critical speed
/// does not depend on the grid once bracketed.
#[test]
fn builtin_critical_speeds_are_grid_independent() {
    let asm = Assembly::new(&Model::builtin().expect("model")).expect("assembles");
    let coarse = linear::campbell(&asm, &linear::speed_grid(300.0, 700.0, 5).expect("grid"), 4)
        .expect("campbell");
    let fine = linear::campbell(
        &asm,
        &linear::speed_grid(300.0, 700.0, 41).expect("grid"),
        4,
    )
    .expect("campbell");
    assert!(!coarse.critical_speeds.is_empty());
    for c in &coarse.critical_speeds {
        let m = linear::modes(&asm, c.speed_rad_s, 4).expect("modes");
        let f = m[c.mode - 1].frequency_rad_s;
        assert!((f - c.frequency_rad_s).abs() < 1e-8 * f, "{c:?} vs {f}");
        assert!(
            fine.critical_speeds.iter().any(|d| d.rotor_id == c.rotor_id
                && d.mode == c.mode
                && (d.speed_rad_s - c.speed_rad_s).abs() < 1e-6 * c.speed_rad_s),
            "{c:?} not found on the fine grid"
        );
    }
}
