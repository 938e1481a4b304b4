//! Every shipped model file sweeps without a panic: a short range of each, through the
//! command line as a user runs it (linear rotors included: nothing nonlinear to assess is
//! not a crash).

use std::process::Command;

#[test]
fn every_shipped_rotor_sweeps_without_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(root.join("examples/rotors"))
        .expect("examples/rotors")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    let mut failures = Vec::new();
    for f in &files {
        let out = dir
            .path()
            .join(f.file_stem().expect("stem"))
            .with_extension("mcap");
        let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
            .args(["sweep", "--max-points", "12", "-q", "--model"])
            .arg(f)
            .arg("-o")
            .arg(&out)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        println!("{}: exit {:?}", f.display(), o.status.code());
        if o.status.code() == Some(101) || err.contains("panicked") {
            failures.push(format!("{}: {err}", f.display()));
        } else if !o.status.success() {
            // a clean refusal must name the file
            if !err.contains(f.file_name().and_then(|n| n.to_str()).unwrap_or("?")) {
                failures.push(format!(
                    "{}: error without the file's name: {err}",
                    f.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Every shipped campaign plans without a panic (`--dry-run`: its runs, settings and
/// outputs checked, nothing computed), and the shipped study file sweeps.
#[test]
fn every_shipped_campaign_plans_and_the_study_file_sweeps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(root.join("examples"))
        .expect("examples")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .filter(|p| p.file_name().is_some_and(|n| n != "study.toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    for f in &files {
        let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
            .args(["campaign", "--dry-run"])
            .arg(f)
            .output()
            .expect("runs");
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        println!("{}: exit {:?}", f.display(), o.status.code());
        assert!(o.status.success(), "{}: {text}", f.display());
        assert!(text.contains("dry run"), "{}: {text}", f.display());
    }
    let out = dir.path().join("study.mcap");
    let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep",
            "--max-points",
            "12",
            "-q",
            "--no-verify",
            "--study",
        ])
        .arg(root.join("examples/study.toml"))
        .arg("-o")
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `examples/rotors/dual_rotor_fine.toml` (the built-in rotor with every shaft element split
/// in two, `tools/refine_mesh.py`) has the built-in rotor's modes. At rest the undamped
/// problem is symmetric and the meshes are nested, so the fine mesh's frequencies lie at or
/// below the built-in's (Rayleigh–Ritz), by little (cubic elements: at most 7.3e-5
/// relative over the first eight); at 500 rad/s (gyroscopic, no such bound) within 3e-4
/// (2.2e-4 at most).
#[test]
fn the_fine_mesh_rotor_has_the_built_in_rotors_modes() {
    use tmrotor::model::{Assembly, Model};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let coarse = Model::builtin().expect("built-in");
    let fine = Model::from_file(root.join("examples/rotors/dual_rotor_fine.toml")).expect("fine");
    assert_eq!(fine.n_nodes(), coarse.n_nodes() + 16);
    for (speed, bound) in [(0.0, -1e-9..1e-4), (500.0, -3e-4..3e-4)] {
        let modes = |m: &Model| {
            tmrotor::linear::modes(&Assembly::new(m).expect("assembles"), speed, 8).expect("modes")
        };
        let (c, f) = (modes(&coarse), modes(&fine));
        for (a, b) in c.iter().zip(&f) {
            let rel = (a.undamped_rad_s - b.undamped_rad_s) / a.undamped_rad_s;
            println!(
                "{speed} rad/s: {} {} {rel:.3e}",
                a.undamped_rad_s, b.undamped_rad_s
            );
            assert!(
                bound.contains(&rel),
                "at {speed} rad/s: {} against {} rad/s",
                a.undamped_rad_s,
                b.undamped_rad_s
            );
        }
    }
}
