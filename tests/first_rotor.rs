//! The first rotor of docs/first-rotor.md (`examples/rotors/two_disk_ball_bearings.toml`):
//! its first critical speeds by hand, beside `tmrotor modes`.
//!
//! The hand calculation is independent of tmrotor's assembly: Stribeck's load sharing
//! (continuous form) gives each gravity-loaded ball bearing's static deflection and its
//! linearised stiffness, vertical `k_v = 3W/(2δ_r)` and horizontal `k_h = 2/3 k_v`; the
//! shaft is an Euler–Bernoulli beam of the main tube's bending stiffness on those springs,
//! its mass lumped at the nodes; Rayleigh's quotient on the static deflection shape gives
//! the first bending frequency in each plane. It neglects shear, the disks' rotary inertia,
//! the 1 µm clearance and the end sleeves' thicker wall, all of which make the structure
//! softer or heavier, and Rayleigh's quotient bounds the frequency from above: so it may
//! only lie above tmrotor's, by a few per cent.

use std::f64::consts::PI;
use std::process::Command;

const G: f64 = 9.81;

/// By hand: `(vertical, horizontal)` first critical speeds (rad/s), and the bearings'
/// load (N) and linearised stiffnesses `k_v`, `k_h` (N/m).
fn by_hand() -> ((f64, f64), (f64, f64, f64)) {
    let (e, rho) = (210e9_f64, 7890.0_f64);
    let (d_out, d_in, d_end) = (0.14_f64, 0.10_f64, 0.106_f64);
    let ei = e * PI / 64.0 * (d_out.powi(4) - d_in.powi(4));
    let xs = [0.0, 0.024, 0.274, 0.524, 0.774, 0.798];
    let span = xs[5];
    // shaft segments (from node, to node, bore, length) lumped half to each end
    let mut m = [0.0_f64; 6];
    for (a, b, bore, len) in [
        (0, 1, d_end, 0.024),
        (1, 2, d_in, 0.25),
        (2, 3, d_in, 0.25),
        (3, 4, d_in, 0.25),
        (4, 5, d_end, 0.024),
    ] {
        let ms = rho * PI / 4.0 * (d_out * d_out - bore * bore) * len;
        m[a] += ms / 2.0;
        m[b] += ms / 2.0;
    }
    m[2] += 94.2194;
    m[3] += 94.2194;
    let weight_per_bearing = m.iter().sum::<f64>() * G / 2.0;
    // Stribeck, continuous: W = K_h δ_r^{3/2} (Z/2π) ∫cos^{5/2}φ dφ over the loaded half,
    // ∫cos^{5/2} = 3/5 ∫cos^{1/2} = 3/5 B(1/2, 3/4)
    let (z, k_hertz) = (22.0_f64, 1.45e9_f64);
    let j_half = 2.396_280_469_471_184; // B(1/2, 3/4) = √π Γ(3/4)/Γ(5/4)
    let j_five_halves = 0.6 * j_half;
    let delta_r = (weight_per_bearing * 2.0 * PI / (z * k_hertz * j_five_halves)).powf(2.0 / 3.0);
    let k_v = 1.5 * weight_per_bearing / delta_r;
    let k_h = k_v * 2.0 / 3.0;
    let rayleigh = |k: f64| {
        let f: Vec<f64> = m.iter().map(|mi| mi * G).collect();
        let r0: f64 = f.iter().zip(xs).map(|(fi, x)| fi * (span - x)).sum::<f64>() / span;
        let r1 = f.iter().sum::<f64>() - r0;
        let y: Vec<f64> = xs
            .iter()
            .map(|&x| {
                let beam: f64 = f
                    .iter()
                    .zip(xs)
                    .map(|(fi, a)| {
                        let b = span - a;
                        if x <= a {
                            fi * b * x * (span * span - b * b - x * x) / (6.0 * ei * span)
                        } else {
                            let xr = span - x;
                            fi * a * xr * (span * span - a * a - xr * xr) / (6.0 * ei * span)
                        }
                    })
                    .sum();
                beam + r0 / k * (span - x) / span + r1 / k * x / span
            })
            .collect();
        let num: f64 = m.iter().zip(&y).map(|(mi, yi)| mi * yi).sum();
        let den: f64 = m.iter().zip(&y).map(|(mi, yi)| mi * yi * yi).sum();
        (G * num / den).sqrt()
    };
    (
        (rayleigh(k_v), rayleigh(k_h)),
        (weight_per_bearing, k_v, k_h),
    )
}

/// `tmrotor args`, which must succeed: its stdout and stderr, one after the other.
fn tmrotor(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(args)
        .output()
        .expect("tmrotor runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
}

/// `model check`'s linearised bearings: `(load, kxx, kyy)` of each.
fn checked_bearings(model: &str) -> Vec<(f64, f64, f64)> {
    let text = tmrotor(&["model", "check", model]);
    let number = |line: &str, key: &str| -> f64 {
        let rest = &line[line.find(key).expect(key) + key.len()..];
        rest.split_whitespace()
            .next()
            .and_then(|v| v.trim_end_matches(',').parse().ok())
            .expect("a number")
    };
    text.lines()
        .filter(|l| l.contains("linearised kxx"))
        .map(|l| (number(l, "load "), number(l, "kxx = "), number(l, "kyy = ")))
        .collect()
}

#[test]
fn first_critical_speeds_agree_with_a_hand_calculation() {
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/rotors/two_disk_ball_bearings.toml"
    );
    let text = tmrotor(&[
        "modes", "--model", model, "--speed", "0", "--count", "2", "--csv",
    ]);
    let freqs: Vec<f64> = text
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .filter_map(|l| l.split(',').nth(1)?.parse().ok())
        .collect();
    assert_eq!(freqs.len(), 2, "{text}");
    // the gravity-loaded bearings are stiffer vertically: the higher one is vertical
    let (fe_h, fe_v) = (freqs[0].min(freqs[1]), freqs[0].max(freqs[1]));
    let ((hand_v, hand_h), (load, k_v, k_h)) = by_hand();
    // the bearings: Stribeck's continuous load sharing against the 22 discrete elements
    // (with the 1 µm clearance, which unloads those near the horizontal: kyy lower)
    let bearings = checked_bearings(model);
    assert_eq!(bearings.len(), 2, "{bearings:?}");
    for (w, kxx, kyy) in bearings {
        assert!((w - load).abs() < 1e-3 * load, "load {w} against {load}");
        assert!(
            (kxx - k_v).abs() < 0.01 * k_v,
            "kxx {kxx:e} against {k_v:e}"
        );
        assert!(
            (0.0..0.06).contains(&((k_h - kyy) / kyy)),
            "kyy {kyy:e} against {k_h:e}"
        );
    }
    for (what, hand, fe) in [("vertical", hand_v, fe_v), ("horizontal", hand_h, fe_h)] {
        let above = (hand - fe) / fe;
        assert!(
            (0.0..0.05).contains(&above),
            "{what}: by hand {hand:.1} rad/s, tmrotor {fe:.1} rad/s ({:+.1} %)",
            100.0 * above
        );
    }
    // the split between the planes comes from the bearings alone: 2/3 of the stiffness
    let ratio_hand = hand_h / hand_v;
    let ratio_fe = fe_h / fe_v;
    assert!(
        (ratio_hand - ratio_fe).abs() < 0.02,
        "{ratio_hand} {ratio_fe}"
    );
}
