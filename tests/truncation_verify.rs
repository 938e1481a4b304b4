//! `replay verify`: a recording's located bifurcations re-solved at other truncation
//! orders. At the recorded order the check must find every saddle-node where the sweep
//! put it (the folds are located by the tangent, independent of the step); at higher
//! orders each one gets a verdict.

use std::process::Command;

#[test]
fn the_recorded_order_finds_the_folds_again_and_higher_orders_give_a_verdict() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("w.mcap");
    let sweep = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(["sweep", "--omega", "515:530", "-q", "--lean", "-o"])
        .arg(&file)
        .output()
        .expect("tmrotor runs");
    assert!(
        sweep.status.success(),
        "{}",
        String::from_utf8_lossy(&sweep.stderr)
    );
    let out = Command::new(env!("CARGO_BIN_EXE_replay"))
        .args(["verify"])
        .arg(&file)
        .args(["--orders", "3,4"])
        .output()
        .expect("replay runs");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let folds: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("saddle-node at"))
        .collect();
    assert_eq!(folds.len(), 2, "{text}");
    for l in &folds {
        assert!(l.contains("order 3 converged"), "{l}");
        assert!(
            ["order 4 converged", "order 4 moved", "order 4 vanished"]
                .iter()
                .any(|v| l.contains(v)),
            "{l}"
        );
    }
    // the sweep's own summary, with --verify
    let again = dir.path().join("v.mcap");
    let sweep = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep", "--omega", "515:530", "-q", "--lean", "--verify", "-o",
        ])
        .arg(&again)
        .output()
        .expect("tmrotor runs");
    let summary = String::from_utf8_lossy(&sweep.stdout).to_string();
    assert!(sweep.status.success(), "{summary}");
    assert!(summary.contains("at higher truncation orders"), "{summary}");
    assert_eq!(
        summary
            .lines()
            .filter(|l| l.contains("saddle-node at ω") && l.contains("order 4 "))
            .count(),
        2,
        "{summary}"
    );
    // bad input is refused by name
    let bad = Command::new(env!("CARGO_BIN_EXE_replay"))
        .args(["verify"])
        .arg(&file)
        .args(["--window", "-1"])
        .output()
        .expect("replay runs");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--window"));
}
