//! Uniform hollow shafts, free–free and pinned–pinned, against analytic beam theory, with
//! mesh convergence.

use std::f64::consts::PI;

use tmrotor::linear;
use tmrotor::model::{Assembly, Model};

const E: f64 = 210e9;
const NU: f64 = 0.3;
const RHO: f64 = 7850.0;

fn shaft_toml(len: f64, d_out: f64, d_in: f64, n: usize, pinned: bool) -> String {
    let mut s = format!(
        "name = \"shaft\"\n[gravity]\nenabled = false\n[[materials]]\nid = \"steel\"\n\
         youngs_modulus_pa = {E:e}\npoisson_ratio = {NU}\ndensity_kg_m3 = {RHO}\n\
         [[rotors]]\nid = \"r\"\nspeed_ratio = 1\nnodes = [{}]\n",
        (1..=n + 1)
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    for i in 1..=n {
        s += &format!(
            "[[shafts]]\nnodes = [{i}, {}]\nlength_m = {:e}\ninner_diameter_m = {d_in:e}\n\
             outer_diameter_m = {d_out:e}\nmaterial = \"steel\"\n",
            i + 1,
            len / n as f64
        );
    }
    if pinned {
        for (id, node) in [("a", 1), ("b", n + 1)] {
            s += &format!("[[supports]]\nid = \"{id}\"\nnode = {node}\nstiffness_n_m = 1e15\n");
        }
    }
    s
}

/// Distinct bending frequencies (rad/s): each appears once per plane; rigid-body
/// eigenvalues (below `floor`) are dropped.
fn frequencies(text: &str, count: usize, floor: f64) -> Vec<f64> {
    let model = Model::from_str(text, "test").expect("valid model");
    let asm = Assembly::new(&model).expect("assembles");
    let modes = linear::modes(&asm, 0.0, 2 * count + 8).expect("modes");
    let f: Vec<f64> = modes
        .iter()
        .map(|m| m.frequency_rad_s)
        .filter(|&w| w > floor)
        .collect();
    // Pairs (x and y planes) must coincide.
    let mut out = Vec::new();
    for pair in f.chunks(2).take(count) {
        assert_eq!(pair.len(), 2);
        assert!(
            (pair[0] - pair[1]).abs() <= 1e-7 * pair[0],
            "planes differ: {pair:?}"
        );
        out.push(pair[0]);
    }
    out
}

struct Section {
    a: f64,
    i: f64,
    kga: f64,
}

fn section(d_out: f64, d_in: f64) -> Section {
    let a = PI / 4.0 * (d_out * d_out - d_in * d_in);
    let i = PI / 64.0 * (d_out.powi(4) - d_in.powi(4));
    let m2 = (d_in / d_out).powi(2);
    // Cowper (1966), hollow circle.
    let kappa = 6.0 * (1.0 + NU) * (1.0 + m2).powi(2)
        / ((7.0 + 6.0 * NU) * (1.0 + m2).powi(2) + (20.0 + 12.0 * NU) * m2);
    let g = E / (2.0 * (1.0 + NU));
    Section {
        a,
        i,
        kga: kappa * g * a,
    }
}

/// Exact Timoshenko frequency of mode `n` of a pinned–pinned beam: with
/// `w = W sin kz`, `ψ = Ψ cos kz`, `k = nπ/L`, the equations
/// `κGA(w'' − ψ') + ρAω² w = 0`, `EIψ'' + κGA(w' − ψ) + ρIω² ψ = 0` give
/// `(κGA k² − ρAω²)(EI k² + κGA − ρIω²) − (κGA k)² = 0`; the lower root.
fn timoshenko_pinned(n: usize, len: f64, s: &Section) -> f64 {
    let k = n as f64 * PI / len;
    let (a, rho_a, rho_i, ei) = (s.kga, RHO * s.a, RHO * s.i, E * s.i);
    let c2 = rho_a * rho_i;
    let c1 = -(a * k * k * rho_i + rho_a * (ei * k * k + a));
    let c0 = a * k * k * (ei * k * k + a) - a * a * k * k;
    let x = (-c1 - (c1 * c1 - 4.0 * c2 * c0).sqrt()) / (2.0 * c2);
    x.sqrt()
}

fn euler_bernoulli(beta_l: f64, len: f64, s: &Section) -> f64 {
    (beta_l / len).powi(2) * (E * s.i / (RHO * s.a)).sqrt()
}

#[test]
fn pinned_pinned_thick_shaft_converges_to_timoshenko_not_euler_bernoulli() {
    // L/D = 6: shear and rotary inertia lower the modes by 1–7 %.
    let (len, d_out, d_in) = (0.6, 0.1, 0.06);
    let s = section(d_out, d_in);
    let exact: Vec<f64> = (1..=3).map(|n| timoshenko_pinned(n, len, &s)).collect();
    let mut prev_err = [f64::INFINITY; 3];
    let mut prev_f = vec![0.0; 3];
    for n_el in [4, 8, 16, 32] {
        let f = frequencies(&shaft_toml(len, d_out, d_in, n_el, true), 3, 1.0);
        for m in 0..3 {
            let err = (f[m] - exact[m]).abs() / exact[m];
            assert!(
                err < prev_err[m] || err < 1e-5,
                "mode {m}: no convergence at {n_el} elements ({err:e} after {:e})",
                prev_err[m]
            );
            prev_err[m] = err;
            if n_el == 32 {
                // 32 elements: within 0.2 %. For this shear-dominated shaft the error of
                // the consistent-mass element falls as h² (ratio ≈ 4 per halving; checked
                // by hand against shape-function integrals of the interdependent
                // interpolation element), so the Richardson extrapolation
                // f₃₂ + (f₃₂ − f₁₆)/3 lands on the exact value.
                assert!(err < 2e-3, "mode {m}: {err:e}");
                let extrapolated = f[m] + (f[m] - prev_f[m]) / 3.0;
                let e_ext = (extrapolated - exact[m]).abs() / exact[m];
                assert!(
                    e_ext < 2e-5,
                    "mode {m}: extrapolated {extrapolated} vs {}",
                    exact[m]
                );
                let eb = euler_bernoulli((m + 1) as f64 * PI, len, &s);
                assert!(
                    (eb - exact[m]) / exact[m] > 0.01,
                    "the test must distinguish the theories"
                );
            }
        }
        prev_f = f;
    }
}

#[test]
fn pinned_pinned_slender_shaft_is_euler_bernoulli_with_small_correction() {
    // L/D = 60: the Timoshenko corrections are 0.06 % (mode 1) and 0.25 % (mode 2).
    let (len, d_out, d_in) = (3.0, 0.05, 0.03);
    let s = section(d_out, d_in);
    let f = frequencies(&shaft_toml(len, d_out, d_in, 30, true), 2, 1.0);
    for (m, &w) in f.iter().enumerate() {
        let eb = euler_bernoulli((m + 1) as f64 * PI, len, &s);
        let t = timoshenko_pinned(m + 1, len, &s);
        assert!((w - t).abs() / t < 1e-4, "mode {m}: {w} vs Timoshenko {t}");
        // Below E–B by about the first-order correction ½(kr)²(1 + E/κG), k = nπ/L.
        let corr =
            0.5 * ((m + 1) as f64 * PI / len).powi(2) * (s.i / s.a) * (1.0 + E * s.a / s.kga);
        assert!(corr < 3e-3);
        let drop = (eb - w) / eb;
        assert!(
            (drop - corr).abs() < 0.1 * corr,
            "mode {m}: drop {drop:e} vs {corr:e}"
        );
    }
}

#[test]
fn free_free_shaft_matches_beam_theory_and_converges() {
    // Free–free Euler–Bernoulli roots of cos βL cosh βL = 1.
    let beta_l = [4.730_040_745, 7.853_204_624, 10.995_607_838];
    // Slender (L/D = 100), so the Timoshenko correction is small; its first-order value
    // for mode n is −½ (β r)² (1 + E/(κG)) (Rayleigh–Timoshenko), r² = I/A.
    let (len, d_out, d_in) = (5.0, 0.05, 0.03);
    let s = section(d_out, d_in);
    let r2 = s.i / s.a;
    let e_over_kg = E * s.a / s.kga;
    let mut prev = [f64::INFINITY; 3];
    for n_el in [5, 10, 20, 40] {
        let f = frequencies(&shaft_toml(len, d_out, d_in, n_el, false), 3, 1.0);
        for m in 0..3 {
            let eb = euler_bernoulli(beta_l[m], len, &s);
            let corr = 0.5 * (beta_l[m] / len).powi(2) * r2 * (1.0 + e_over_kg);
            let reference = eb * (1.0 - corr);
            let err = (f[m] - reference).abs() / reference;
            assert!(err <= prev[m] || err < 1e-4, "mode {m} at {n_el}: {err:e}");
            prev[m] = err;
            if n_el == 40 {
                // Within a fifth of the correction itself, and below E–B.
                assert!(
                    err < 0.2 * corr + 1e-5,
                    "mode {m}: {err:e} vs corr {corr:e}"
                );
                assert!(f[m] < eb);
            }
        }
    }
}
