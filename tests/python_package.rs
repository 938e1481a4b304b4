//! The Python package (`python/`) and the Foxglove layout check, run by their own pytest
//! suite against recordings the suite makes with this build's binaries. `.ci/run`
//! installs the package with its test and Rerun extras into `.venv` and exports
//! `TMROTOR_PYTHON`; without it the test is ignored (skipped, with the reason; `build.rs`), except under `CI=true`
//! where that is a failure (and the suite itself fails, not skips, what it cannot run).

use std::process::Command;

#[test]
#[cfg_attr(
    not(tmrotor_python),
    ignore = "TMROTOR_PYTHON is not set (a Python with './python[rerun,test]'; .ci/run sets it up)"
)]
fn python_package_suite_passes() {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    let python = match std::env::var("TMROTOR_PYTHON") {
        Ok(p) if !p.is_empty() => p,
        _ => {
            assert!(
                !ci,
                "CI=true but TMROTOR_PYTHON is not set: the Python package suite cannot run"
            );
            eprintln!(
                "skipped: TMROTOR_PYTHON is not set (point it at a python with \
                 `pip install './python[rerun,test]'`, as .ci/run does)"
            );
            return;
        }
    };
    let probe = Command::new(&python)
        .args(["-c", "import pandas, pytest, mcap, mcap_protobuf"])
        .status();
    if !probe.is_ok_and(|s| s.success()) {
        assert!(
            !ci,
            "TMROTOR_PYTHON={python} cannot import pandas, pytest, mcap and mcap_protobuf"
        );
        eprintln!("skipped: {python} lacks pandas, pytest or the mcap readers");
        return;
    }
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new(&python)
        .current_dir(root)
        .args([
            "-m",
            "pytest",
            "python/tests",
            "-q",
            "-p",
            "no:cacheprovider",
        ])
        .env("TMROTOR_BIN", env!("CARGO_BIN_EXE_tmrotor"))
        .env("REPLAY_BIN", env!("CARGO_BIN_EXE_replay"))
        .output()
        .expect("run pytest");
    let text = format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(out.status.success(), "python/tests failed:\n{text}");
    assert!(text.contains(" passed"), "{text}");
}
