//! `replay verify`: a recording's located bifurcations re-solved at other truncation
//! orders. At the recorded order the check must find every saddle-node where the sweep
//! put it (the folds are located by the tangent, independent of the step); at higher
//! orders each one gets a verdict. The sweep itself checks at the order + 1 and + 2 by
//! default and records the verdicts on `/truncation`.

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
    // the sweep checks its own bifurcations by default: in the summary, on /truncation
    // (read back by replay info), and not with --no-verify
    let summary = String::from_utf8_lossy(&sweep.stdout).to_string();
    assert!(
        summary.contains("truncation check: orders 4, 5"),
        "{summary}"
    );
    let checked = summary
        .lines()
        .filter(|l| {
            l.contains("saddle-node at ω") && (l.contains("; holds") || l.contains("; moved"))
        })
        .count();
    assert_eq!(checked, 2, "{summary}");
    let rec = tmrotor::record::read_recording(&file).expect("reads");
    assert_eq!(
        rec.truncation.iter().filter(|c| c.kind.is_some()).count(),
        rec.bifurcations.iter().filter(|b| b.branch == 0).count()
    );
    for c in &rec.truncation {
        assert_eq!(c.recorded_order, 3);
        let orders: Vec<u32> = c.orders.iter().map(|(k, _)| *k).collect();
        assert_eq!(orders, [4, 5]);
    }
    let info = Command::new(env!("CARGO_BIN_EXE_replay"))
        .arg("info")
        .arg(&file)
        .output()
        .expect("replay runs");
    let info = String::from_utf8_lossy(&info.stdout).to_string();
    assert!(info.contains("at higher truncation orders: "), "{info}");
    let again = dir.path().join("v.mcap");
    let sweep = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep",
            "--omega",
            "515:530",
            "-q",
            "--lean",
            "--no-verify",
            "-o",
        ])
        .arg(&again)
        .output()
        .expect("tmrotor runs");
    let summary = String::from_utf8_lossy(&sweep.stdout).to_string();
    assert!(sweep.status.success(), "{summary}");
    assert!(!summary.contains("truncation check"), "{summary}");
    let rec = tmrotor::record::read_recording(&again).expect("reads");
    assert!(rec.truncation.is_empty());
    assert!(!rec.topics.iter().any(|t| t.topic == "/truncation"));
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
