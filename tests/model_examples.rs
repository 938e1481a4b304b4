//! The hand-written rotor files in `examples/rotors/` against the analytic frequencies
//! written in their headers (recomputed here from the formulas).

use std::f64::consts::PI;

use tmrotor::linear::{self, Whirl};
use tmrotor::model::{Assembly, Model};

const E: f64 = 210e9;
const NU: f64 = 0.3;

fn load(name: &str) -> Assembly {
    let path = format!("{}/examples/rotors/{name}", env!("CARGO_MANIFEST_DIR"));
    let model = Model::from_file(&path).expect("example model is valid");
    Assembly::new(&model).expect("assembles")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Jeffcott rotor: translation √(k/m) at every speed; tilt
/// ν = (±Ω J_p + √((Ω J_p)² + 4 J_d k_θ)) / (2 J_d), forward above backward.
#[test]
fn jeffcott_disk_gyroscopic_split_matches_analytic() {
    let asm = load("jeffcott_midspan_disk.toml");
    let (len, d) = (1.0_f64, 0.01_f64);
    let a = PI / 4.0 * d * d;
    let i = PI / 64.0 * d.powi(4);
    let kga = 6.0 * (1.0 + NU) / (7.0 + 6.0 * NU) * E / (2.0 * (1.0 + NU)) * a;
    let k = 1.0 / (len.powi(3) / (48.0 * E * i) + len / (4.0 * kga));
    let k_theta = 1.0 / (len / (12.0 * E * i) + 1.0 / (kga * len));
    let (m, jd, jp) = (10.0_f64, 0.05_f64, 0.1_f64);
    let w_t = (k / m).sqrt();
    for speed in [0.0_f64, 300.0, 1000.0] {
        let root = ((speed * jp).powi(2) + 4.0 * jd * k_theta).sqrt();
        let fwd = (speed * jp + root) / (2.0 * jd);
        let bwd = (-speed * jp + root) / (2.0 * jd);
        let modes = linear::modes(&asm, speed, 4).expect("modes");
        let mut f: Vec<(f64, Whirl)> = modes.iter().map(|m| (m.frequency_rad_s, m.whirl)).collect();
        f.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut expected = vec![w_t, w_t, fwd, bwd];
        expected.sort_by(f64::total_cmp);
        for (got, want) in f.iter().zip(&expected) {
            assert!(
                rel(got.0, *want) < 1e-3,
                "Ω = {speed}: {} vs analytic {want}",
                got.0
            );
        }
        if speed > 0.0 {
            let tilt_f = f
                .iter()
                .find(|x| rel(x.0, fwd) < 1e-3)
                .expect("forward tilt");
            let tilt_b = f
                .iter()
                .find(|x| rel(x.0, bwd) < 1e-3)
                .expect("backward tilt");
            assert_eq!(tilt_f.1, Whirl::Forward, "Ω = {speed}");
            assert_eq!(tilt_b.1, Whirl::Backward, "Ω = {speed}");
        }
    }
}

/// Pinned–pinned hollow shaft: exact Timoshenko frequencies (and ≈ Euler–Bernoulli).
#[test]
fn uniform_shaft_example_matches_timoshenko_within_1_percent() {
    let asm = load("uniform_shaft_pinned.toml");
    let (len, d_out, d_in, rho) = (1.0_f64, 0.05_f64, 0.03_f64, 7850.0);
    let a = PI / 4.0 * (d_out * d_out - d_in * d_in);
    let i = PI / 64.0 * (d_out.powi(4) - d_in.powi(4));
    let m2 = (d_in / d_out).powi(2);
    let kappa = 6.0 * (1.0 + NU) * (1.0 + m2).powi(2)
        / ((7.0 + 6.0 * NU) * (1.0 + m2).powi(2) + (20.0 + 12.0 * NU) * m2);
    let kga = kappa * E / (2.0 * (1.0 + NU)) * a;
    let modes = linear::modes(&asm, 0.0, 6).expect("modes");
    for n in 1..=3 {
        let k = n as f64 * PI / len;
        let c2 = rho * a * rho * i;
        let c1 = -(kga * k * k * rho * i + rho * a * (E * i * k * k + kga));
        let c0 = kga * k * k * (E * i * k * k + kga) - kga * kga * k * k;
        let exact = ((-c1 - (c1 * c1 - 4.0 * c2 * c0).sqrt()) / (2.0 * c2)).sqrt();
        for m in &modes[2 * (n - 1)..2 * n] {
            assert!(
                rel(m.frequency_rad_s, exact) < 1e-3,
                "mode {n}: {} vs {exact}",
                m.frequency_rad_s
            );
        }
        let eb = k * k * (E * i / (rho * a)).sqrt();
        assert!(rel(modes[2 * (n - 1)].frequency_rad_s, eb) < 0.06);
    }
}

/// Overhung disk on a massless cantilever: roots of
/// (k11 − mν²)(k22 − J_d ν² + J_p Ω ν) − k12² = 0, found here by scanning and bisection;
/// positive roots are forward whirl, negative roots backward.
#[test]
fn overhung_disk_coupled_gyroscopic_modes_match_analytic() {
    let asm = load("overhung_disk.toml");
    let (len, d) = (0.5_f64, 0.03_f64);
    let a = PI / 4.0 * d * d;
    let i = PI / 64.0 * d.powi(4);
    let kga = 6.0 * (1.0 + NU) / (7.0 + 6.0 * NU) * E / (2.0 * (1.0 + NU)) * a;
    let (f11, f12, f22) = (
        len.powi(3) / (3.0 * E * i) + len / kga,
        len * len / (2.0 * E * i),
        len / (E * i),
    );
    let det = f11 * f22 - f12 * f12;
    let (k11, k12, k22) = (f22 / det, -f12 / det, f11 / det);
    let (m, jd, jp) = (5.0_f64, 0.05_f64, 0.1_f64);
    for speed in [0.0_f64, 500.0, 1500.0] {
        let p = |v: f64| (k11 - m * v * v) * (k22 - jd * v * v + jp * speed * v) - k12 * k12;
        let mut roots = Vec::new();
        let (lo, hi, n) = (-20_000.0, 20_000.0, 400_000);
        let h = (hi - lo) / n as f64;
        for k in 0..n {
            let (mut x0, mut x1) = (lo + k as f64 * h, lo + (k + 1) as f64 * h);
            if p(x0) * p(x1) < 0.0 {
                for _ in 0..100 {
                    let mid = 0.5 * (x0 + x1);
                    if p(x0) * p(mid) <= 0.0 {
                        x1 = mid;
                    } else {
                        x0 = mid;
                    }
                }
                roots.push(0.5 * (x0 + x1));
            }
        }
        assert_eq!(roots.len(), 4, "Ω = {speed}: {roots:?}");
        let modes = linear::modes(&asm, speed, 4).expect("modes");
        for r in &roots {
            let got = modes
                .iter()
                .find(|md| rel(md.frequency_rad_s, r.abs()) < 1e-3)
                .unwrap_or_else(|| panic!("Ω = {speed}: root {r} not found"));
            if speed > 0.0 {
                let want = if *r > 0.0 {
                    Whirl::Forward
                } else {
                    Whirl::Backward
                };
                assert_eq!(got.whirl, want, "Ω = {speed}, root {r}");
            }
        }
    }
}
