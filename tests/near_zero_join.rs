//! The coupled exponents nearest zero joined with the frozen-temperature multipliers, on
//! the single-shaft rotor of `examples/rotors/two_disk_ball_bearings.toml` with its
//! thermal network (order 3). Near its fold at 605.38 rad/s the thermal coupling turns a
//! frozen real pair above +1 into the coupled complex pair of a thermo-mechanical
//! Neimark–Sacker mode, with a stable frozen multiplier between the two in modulus, and a
//! frozen real multiplier sits where the disk's edge falls. Joined by the disk's radius
//! alone, a mode was lost or counted twice from one point to the next: the recorded count
//! alternated (2 ↔ 4, 3 ↔ 5) and the sweep warned six times of stability changes without
//! a located bifurcation.
//!
//! Independent reference: the monodromy product over the whole coupled state (mechanical
//! and thermal, no split by time scale, [`CoupledRederive::coupled_product`]), whose
//! multipliers outside the unit circle are counted directly.

use std::process::Command;

use tmrotor::derive::coupled::CoupledRederive;
use tmrotor::record::read_recording;

#[test]
fn the_joint_count_matches_the_coupled_product_where_the_modes_reorder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("two_disk.mcap");
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/rotors/two_disk_ball_bearings.toml"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep",
            "--model",
            model,
            "--no-switch",
            "--no-verify",
            "-o",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{text}");
    assert!(
        !text.contains("without a located bifurcation"),
        "a stability change the sweep could not locate:\n{text}"
    );

    let rec = read_recording(&out).expect("reads");
    let rederive = CoupledRederive::from_run(&rec.run).expect("rebuilds");
    // the points within 2 rad/s below the fold, on both segments, where the radius
    // alone lost or doubled a mode
    let near: Vec<_> = rec
        .points
        .iter()
        .filter(|p| (603.5..605.3).contains(&p.omega_rad_s))
        .filter(|p| p.floquet_counts.is_some())
        .collect();
    assert!(near.len() >= 20, "{} points near the fold", near.len());
    let mut compared = 0;
    let mut differ = 0;
    // a multiplier within this of the unit circle is not resolved by the coupled product
    // (its thermal multipliers crowd +1): such points are skipped
    const MARGIN: f64 = 1e-3;
    for p in &near {
        let period = p.period_s;
        let full = rederive.coupled_product(p).expect("coupled product");
        let near_circle = |m: &num_complex::Complex64| (m.norm() - 1.0).abs() <= MARGIN;
        let fast_near: Vec<_> = full
            .multipliers
            .iter()
            .chain(&p.multipliers)
            .filter(|m| near_circle(m) && (m.re - 1.0).abs() > 2e-2)
            .collect();
        let outside = |ms: &mut dyn Iterator<Item = &num_complex::Complex64>| {
            ms.filter(|m| m.norm() > 1.0 + MARGIN).count()
        };
        let product = outside(&mut full.multipliers.iter());
        // the joint set: the fast multipliers the disk does not supersede, and the disk's
        let counted = outside(
            &mut p
                .multipliers
                .iter()
                .zip(&p.superseded)
                .filter(|(_, s)| !**s)
                .map(|(m, _)| m),
        );
        let hill = p
            .slow_exponents
            .iter()
            .filter(|l| l.re * period > MARGIN)
            .count();
        // the product's estimates of the disk's modes
        let estimates = outside(
            &mut p
                .multipliers
                .iter()
                .zip(&p.superseded)
                .filter(|(_, s)| **s)
                .map(|(m, _)| m),
        );
        eprintln!(
            "point {} at {:.4} rad/s: coupled product {product}, joint {}; in the disk {hill} \
             unstable against {estimates} of the frozen product's",
            p.index,
            p.omega_rad_s,
            counted + hill
        );
        if !fast_near.is_empty() {
            eprintln!(
                "  skipped: {} multipliers within {MARGIN} of the circle",
                fast_near.len()
            );
            continue;
        }
        // every mode outside the disk counted once, as the coupled product counts it
        assert_eq!(counted + estimates, product, "point {}", p.index);
        assert!(hill <= estimates + 1, "point {}", p.index);
        if hill != estimates {
            differ += 1;
        }
        compared += 1;
    }
    // where they differ, Hill's coupled pair (or its two real exponents) stands for a
    // frozen real pair of which the product has one multiplier outside the circle and one
    // inside (docs/stability.md)
    eprintln!("{compared} points compared; in the disk, Hill and the product differ at {differ}");
    assert!(
        compared >= 20 && differ <= compared / 2,
        "{compared} / {differ}"
    );
}
