//! Rolling elements' contacts sampled or integrated exactly (`--exact-contacts`), on the
//! single-shaft two-disk rotor of `examples/rotors/two_disk_ball_bearings.toml` (its
//! elements lose contact over part of the revolution), swept without the thermal network
//! at order 8 across 530–560 rad/s, where it has a fold pair 0.001 rad/s wide near
//! 544.60 rad/s. Sampled, the bearings' Jacobian jumps as elements cross the samples:
//! the fold pair is stepped over while the multipliers change, and the sweep warns of
//! stability changes it cannot locate. Integrated exactly, the folds are located and each
//! is confirmed by a real multiplier through +1: no warning is left.

use std::process::Command;

fn sweep(extra: &[&str], out: &std::path::Path) -> String {
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/rotors/two_disk_ball_bearings.toml"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep",
            "--model",
            model,
            "--no-thermal",
            "--order",
            "8",
            "--no-switch",
            "--no-verify",
            "--omega",
            "530:560",
            "-o",
        ])
        .arg(out)
        .args(extra)
        .output()
        .expect("runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{text}");
    text
}

#[test]
fn exact_contacts_locate_and_confirm_the_folds_that_sampling_misses() {
    let dir = tempfile::tempdir().expect("tempdir");
    let sampled = sweep(&[], &dir.path().join("s.mcap"));
    let exact = sweep(&["--exact-contacts"], &dir.path().join("e.mcap"));
    eprintln!("sampled:\n{sampled}\nexact:\n{exact}");
    assert!(
        sampled.contains("without a located bifurcation") || sampled.contains("not confirmed"),
        "sampled contacts: {sampled}"
    );
    assert!(!exact.contains("warning"), "exact contacts: {exact}");
    let folds: Vec<f64> = exact
        .lines()
        .filter_map(|l| l.trim().strip_prefix("saddle-node at ω = "))
        .filter_map(|l| l.split_whitespace().next()?.parse().ok())
        .collect();
    assert_eq!(folds.len(), 2, "{exact}");
    for f in folds {
        assert!((f - 544.60).abs() < 0.01, "fold at {f}");
    }
}
