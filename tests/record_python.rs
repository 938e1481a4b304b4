//! The official MCAP Python reader (`mcap` + `mcap-protobuf-support`) decodes every
//! message of a small recording. `.ci/run` installs the packages into `.venv` and exports
//! `TMROTOR_PYTHON`; without it the test is ignored (skipped, with the reason; `build.rs`), except under `CI=true`
//! where a missing reader is a failure.

mod common;

use std::process::Command;

use tmrotor::record::synthetic::{self, SyntheticOptions};

#[test]
#[cfg_attr(
    not(tmrotor_python),
    ignore = "TMROTOR_PYTHON is not set (a Python with mcap and mcap-protobuf-support; .ci/run sets it up)"
)]
fn official_python_reader_decodes_every_message() {
    let python = match std::env::var("TMROTOR_PYTHON") {
        Ok(p) if !p.is_empty() => p,
        _ => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(
                !ci,
                "CI=true but TMROTOR_PYTHON is not set: the Python MCAP reader check cannot run"
            );
            eprintln!(
                "skipped: TMROTOR_PYTHON is not set (point it at a python with `mcap` and \
                 `mcap-protobuf-support`, as .ci/run does)"
            );
            return;
        }
    };
    let probe = Command::new(&python)
        .args(["-c", "import mcap, mcap_protobuf"])
        .status();
    assert!(
        probe.is_ok_and(|s| s.success()),
        "TMROTOR_PYTHON={python} cannot import mcap and mcap_protobuf"
    );

    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("small.mcap");
    let options = SyntheticOptions {
        points_per_side: 6,
        ..Default::default()
    };
    let n = synthetic::write_mcap(&path, &options, true).expect("write");
    let bifs = synthetic::generate(&options).bifurcations.len();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/check_recording.py");
    let mut expected = vec!["/run_info=1".to_string(), format!("/log={}", 2 + bifs)];
    expected.push(format!("/bifurcations={bifs}"));
    for topic in [
        "/summary",
        "/harmonics",
        "/orbits",
        "/temperatures",
        "/clearance",
        "/bearing_loads",
        "/thermal_forces",
        "/floquet",
        "/scene",
    ] {
        expected.push(format!("{topic}={n}"));
    }
    let output = Command::new(&python)
        .arg(script)
        .arg(&path)
        .args(&expected)
        .output()
        .expect("run python");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "Python reader check failed:\n{stdout}\n{stderr}"
    );
    assert!(stdout.contains("decoded"), "{stdout}");
}

/// The Python package reads a recording with a second branch: the `branch` column, the
/// `branches` table, and each branch point's orbit re-derived on its branch's basis equal
/// to the stored one.
#[test]
#[cfg_attr(
    not(tmrotor_python),
    ignore = "TMROTOR_PYTHON is not set (a Python with mcap and mcap-protobuf-support; .ci/run sets it up)"
)]
fn python_package_reads_a_second_branch() {
    let Ok(python) = std::env::var("TMROTOR_PYTHON") else {
        let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
        assert!(!ci, "CI=true but TMROTOR_PYTHON is not set");
        eprintln!("skipped: TMROTOR_PYTHON is not set");
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("branches.mcap");
    let two = common::TwoBranches::new();
    two.write(&path);
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/python/src");
    let script = format!(
        r#"
import sys
sys.path.insert(0, {src:?})
import numpy as np, tmrotor
r = tmrotor.read({path:?})
b = r.branch
assert list(b.columns[:3]) == ["index", "omega_rad_s", "branch"], list(b.columns[:3])
on = b[b.branch == 1]
assert len(on) == {n}, len(on)
assert len(r.branches) == 1 and r.branches.kind[0] == "period_doubled"
assert r.branches.harmonics[0] == {harmonics:?}, r.branches.harmonics[0]
worst = 0.0
for i in on["index"]:
    a, s = r.orbit(int(i), samples=64), r.recorded_orbit(int(i))
    worst = max(worst, float(np.abs(a.filter(like="_x_m").values - s.filter(like="_x_m").values).max()))
assert worst < 1e-15, worst
h1 = r.branch_harmonics(1)
assert sorted(set(h1["index"])) == sorted(on["index"]), h1["index"]
assert h1.attrs["basis"] == {harmonics:?}, h1.attrs["basis"]
assert "b{nh}" in h1.columns and "b{nh1}" not in h1.columns
assert not set(r.harmonics["index"]) & set(on["index"])
print("ok", len(on), worst)
"#,
        src = src,
        path = path.to_str().expect("utf-8"),
        n = two.branch_points.len(),
        nh = two.doubled.n_harmonics(),
        nh1 = two.doubled.n_harmonics() + 1,
        harmonics = two
            .doubled
            .harmonics()
            .iter()
            .map(|h| format!("{}/{}", h.num, h.den))
            .collect::<Vec<_>>(),
    );
    let out = Command::new(&python)
        .args(["-c", &script])
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
