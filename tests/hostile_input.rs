//! Inputs a hostile or unlucky user gives: impossible values in a model file refused with
//! the field (the same bound as the flags), a conduction chain naming no rotor, a rotor held
//! by nothing, inputs that are devices, FIFOs or too large, counts of zero and huge grids.

use std::path::Path;
use std::process::{Command, Output};

fn tmrotor(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(args)
        .output()
        .expect("runs")
}

fn refused(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "accepted: {err}");
    assert_ne!(o.status.code(), Some(101), "panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "{n:?} not in {err}");
    }
}

fn builtin(dir: &Path) -> (std::path::PathBuf, String) {
    let text = String::from_utf8(tmrotor(&["model", "show"]).stdout).expect("utf-8");
    let path = dir.join("m.toml");
    std::fs::write(&path, &text).expect("write");
    (path, text)
}

#[test]
fn impossible_values_in_a_model_file_are_refused_like_the_flags() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (model, _) = builtin(dir.path());
    let m = model.to_str().expect("path");
    for (set, field, why) in [
        (
            "thermal.cooling_temp_c=-500.0",
            "thermal.cooling_temp_c",
            "absolute zero",
        ),
        (
            "thermal.ambient_temp_c=-300.0",
            "thermal.ambient_temp_c",
            "absolute zero",
        ),
        ("thermal.flow_l_min=0.0", "thermal.flow_l_min", "above 0"),
        (
            "thermal.air.rotor_convection_factor=5.0",
            "thermal.air.rotor_convection_factor",
            "0–1",
        ),
    ] {
        refused(
            &tmrotor(&["model", "check", m, "--set", set]),
            &[m, field, why],
        );
    }
    // the flags' bounds are the same
    refused(
        &tmrotor(&["sweep", "--cooling-temp", "-300", "-o", "/tmp/never.mcap"]),
        &["cooling_temp_c"],
    );
}

#[test]
fn a_chain_naming_no_rotor_and_a_rotor_held_by_nothing_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, text) = builtin(dir.path());
    let bad_chain = dir.path().join("chain.toml");
    std::fs::write(
        &bad_chain,
        text.replacen("chain = \"LP\"", "chain = \"XX\"", 1),
    )
    .expect("write");
    let c = bad_chain.to_str().expect("path");
    refused(
        &tmrotor(&["model", "check", c]),
        &[c, "thermal.shafts[", "chain", "\"XX\" names no rotor"],
    );
    // without gravity and without bearings: the rotors float
    let mut floating = String::new();
    let mut skip = false;
    for line in text.lines() {
        if line.starts_with('[') {
            skip = line.starts_with("[[bearings]]") || line.starts_with("[[thermal.bearings]]");
        }
        if !skip {
            floating.push_str(line);
            floating.push('\n');
        }
    }
    let floating = floating.replace("[gravity]\nenabled = true", "[gravity]\nenabled = false");
    let f = dir.path().join("floating.toml");
    std::fs::write(&f, floating).expect("write");
    let fs = f.to_str().expect("path");
    refused(&tmrotor(&["model", "check", fs]), &[fs, "held by nothing"]);
}

#[test]
fn a_generated_network_too_fine_to_compute_is_refused_with_its_size() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let f = root.join("examples/rotors/dual_rotor_generated.toml");
    let f = f.to_str().expect("path");
    let start = std::time::Instant::now();
    refused(
        &tmrotor(&[
            "model",
            "check",
            f,
            "--set",
            "thermal.segment_length_m=1e-7",
        ]),
        &[
            "thermal.segment_length_m",
            "shaft segment nodes",
            "above the limit of 2000",
        ],
    );
    assert!(start.elapsed().as_secs() < 5, "{:?}", start.elapsed());
}

#[test]
fn devices_fifos_and_huge_files_are_refused_before_reading() {
    let dir = tempfile::tempdir().expect("tempdir");
    refused(
        &tmrotor(&["model", "check", "/dev/zero"]),
        &["/dev/zero", "not a regular file"],
    );
    let big = dir.path().join("big.toml");
    let f = std::fs::File::create(&big).expect("create");
    f.set_len(20 << 20).expect("grow");
    let b = big.to_str().expect("path");
    refused(&tmrotor(&["model", "check", b]), &[b, "above the limit"]);
    refused(
        &tmrotor(&["sweep", "--study", "/dev/zero", "-o", "/tmp/never.mcap"]),
        &["/dev/zero", "not a regular file"],
    );
}

#[test]
fn counts_of_zero_and_huge_grids_are_refused() {
    refused(
        &tmrotor(&["modes", "--count", "0"]),
        &["--count", "at least 1"],
    );
    refused(
        &tmrotor(&["campbell", "--speeds", "0:1000:10", "--count", "0"]),
        &["--count", "at least 1"],
    );
    refused(
        &tmrotor(&["campbell", "--speeds", "0:1000:3000000"]),
        &["--speeds", "at most 100000"],
    );
    refused(
        &tmrotor(&["unbalance", "--speeds", "100:1000:100000000"]),
        &["--speeds", "at most 100000"],
    );
    // a negative value reaches the value check instead of clap's "unexpected argument"
    refused(
        &tmrotor(&["modes", "--speed", "-100"]),
        &["--speed", "-100"],
    );
}

#[test]
fn linear_analyses_take_set_and_truncation_names_its_node_flags() {
    let o = tmrotor(&[
        "modes",
        "--speed",
        "500",
        "--count",
        "2",
        "--set",
        "bearings[0].initial_clearance_m=1e-5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let f = root.join("examples/rotors/jeffcott_midspan_disk.toml");
    refused(
        &tmrotor(&["truncation", "--model", f.to_str().expect("path")]),
        &["--nodes", "dynamic node 8", "its nodes: 1–5"],
    );
    // the tour's study file ships
    assert!(root.join("examples/study.toml").is_file());
}
