//! Tells the tests what this machine can run, so that a test whose tools are missing shows
//! as skipped (ignored, with the reason) instead of passing without doing anything:
//!
//! - `tmrotor_python`: `TMROTOR_PYTHON` names a Python for the Python-reader tests
//!   (`.ci/run` sets it up); under `CI=true` always, so that a CI without it fails
//!   instead of skipping them;
//! - `tmrotor_slurm`: running as root with Slurm's daemons and commands on `PATH` (the
//!   cluster test starts a private single-node Slurm).
//!
//! Rebuilt when either variable changes. `cargo nextest run --run-ignored all` runs the
//! skipped tests anyway; they then say what they lack.

fn on_path(name: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join(name).is_file()))
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status").is_ok_and(|s| {
        s.lines()
            .find_map(|l| l.strip_prefix("Uid:"))
            .and_then(|ids| ids.split_whitespace().nth(1))
            == Some("0")
    })
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(tmrotor_python)");
    println!("cargo::rustc-check-cfg=cfg(tmrotor_slurm)");
    println!("cargo::rerun-if-env-changed=TMROTOR_PYTHON");
    println!("cargo::rerun-if-env-changed=PATH");
    println!("cargo::rerun-if-env-changed=CI");
    let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    if ci || std::env::var("TMROTOR_PYTHON").is_ok_and(|p| !p.is_empty()) {
        println!("cargo::rustc-cfg=tmrotor_python");
    }
    let slurm = ["munged", "slurmctld", "slurmd", "sbatch", "sinfo"];
    if is_root() && slurm.iter().all(|b| on_path(b)) {
        println!("cargo::rustc-cfg=tmrotor_slurm");
    }
}
