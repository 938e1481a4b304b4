//! The top rung of the validation ladder: the built-in (calibrated) dual rotor against the
//! paper's own numbers, on the two runs whose findings need no multipliers.
//!
//! * 20 L/min, 25 °C (paper Fig. 8b): every |δv| below 1 µm over 300–700 rad/s, and the
//!   branch does not fold.
//! * 2 L/min, 50 °C cooling (paper Figs. 21–22): four saddle-nodes; over all thermal nodes
//!   and speeds the lowest temperature about 50 °C and the highest about 72 °C (within
//!   3 °C, the reproduction report's rule).
//!
//! The sweeps run without stability (saddle-nodes are the folds of the branch), about five
//! seconds each; `tmrotor report` on the paper campaign scores all thirteen statements
//! (`examples/reproduction.md`).

use std::path::Path;
use std::process::Command;
use tmrotor::record::{Recording, read_recording};
use tmrotor::stability::BifurcationKind;

fn sweep(dir: &Path, name: &str, args: &[&str]) -> Recording {
    let out = dir.join(format!("{name}.mcap"));
    let status = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(["sweep", "--no-stability", "-q", "-o"])
        .arg(&out)
        .args(args)
        .status()
        .expect("tmrotor runs");
    assert!(status.success(), "{name}: {status}");
    let rec = read_recording(&out).expect("recording reads");
    assert!(rec.complete, "{name}: the sweep completed");
    rec
}

fn saddle_nodes(rec: &Recording) -> usize {
    rec.bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::SaddleNode)
        .count()
}

#[test]
fn clearances_stay_within_a_micrometre_at_20_l_min() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = sweep(dir.path(), "q20", &["--flow", "20"]);
    assert_eq!(saddle_nodes(&rec), 0);
    let first = rec.points.first().expect("points").omega_rad_s;
    let last = rec.points.last().expect("points").omega_rad_s;
    assert!(
        first <= 300.0 + 1e-9 && last >= 700.0 - 1e-9,
        "{first}–{last}"
    );
    let worst = rec
        .points
        .iter()
        .flat_map(|p| p.clearances.iter().map(|c| c.delta_v_m.abs()))
        .fold(0.0_f64, f64::max);
    assert!(worst < 1e-6, "max |δv| = {:.3} µm", worst * 1e6);
}

#[test]
fn four_saddle_nodes_and_the_papers_temperature_range_at_50_c_cooling() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = sweep(
        dir.path(),
        "q2-50C",
        &["--flow", "2", "--cooling-temp", "50"],
    );
    assert_eq!(saddle_nodes(&rec), 4);
    let (mut low, mut high) = (f64::MAX, f64::MIN);
    for p in &rec.points {
        for t in &p.temperatures {
            low = low.min(t.mean_c);
            high = high.max(t.mean_c);
        }
    }
    assert!(
        (low - 50.0).abs() <= 3.0,
        "lowest {low:.2} °C, paper ≈ 50 °C"
    );
    assert!(
        (high - 72.0).abs() <= 3.0,
        "highest {high:.2} °C, paper ≈ 72 °C"
    );
}
