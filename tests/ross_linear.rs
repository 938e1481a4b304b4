//! Linear analyses against ROSS (ross-rotordynamics 2.3.0, an independent rotordynamics
//! code): damped eigenvalues and unbalance responses of a six-element Timoshenko rotor with
//! two disks on (a) a cross-coupled bearing with cross-coupled damping and an orthotropic
//! one, (b) the same with the second bearing's eight coefficients tabulated over speed.
//! The models and ROSS's numbers in `tests/fixtures/ross/` were written by
//! `tools/ross_reference.py`; the script says how to rerun it.

use num_complex::Complex;
use serde_json::Value;
use tmrotor::linear;
use tmrotor::model::{Assembly, Model};

fn load(case: &str) -> (Assembly, Value) {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/ross");
    let model = Model::from_file(format!("{dir}/{case}.toml")).expect("model");
    let asm = Assembly::new(&model).expect("assembly");
    let text = std::fs::read_to_string(format!("{dir}/{case}.json")).expect("reference");
    (asm, serde_json::from_str(&text).expect("json"))
}

fn c(v: &Value) -> Complex<f64> {
    Complex::new(
        v[0].as_f64().expect("a number"),
        v[1].as_f64().expect("a number"),
    )
}

/// Every one of the eight lowest lateral modes matches one of ROSS's eigenvalues (ROSS's
/// list also holds axial and torsional modes, which tmrotor does not model) to `tol`
/// relative, and the log decrements agree.
fn modes_match(case: &str, tol: f64) {
    let (asm, reference) = load(case);
    let mut worst: f64 = 0.0;
    for entry in reference["modes"].as_array().expect("a list") {
        let w = entry["speed_rad_s"].as_f64().expect("a number");
        let ross: Vec<Complex<f64>> = entry["eigenvalues"]
            .as_array()
            .expect("a list")
            .iter()
            .map(c)
            .collect();
        let ours = linear::modes(&asm, w, 8).expect("modes");
        assert_eq!(ours.len(), 8);
        for m in &ours {
            let near = ross
                .iter()
                .min_by(|a, b| {
                    (*a - m.eigenvalue)
                        .norm()
                        .total_cmp(&(*b - m.eigenvalue).norm())
                })
                .expect("a reference eigenvalue");
            let rel = (near - m.eigenvalue).norm() / near.norm();
            worst = worst.max(rel);
            assert!(
                rel < tol,
                "{case} at {w} rad/s: mode {} rad/s, ROSS {near}, relative {rel:e}",
                m.eigenvalue
            );
            let dec = linear::log_decrement(*near);
            assert!(
                (m.log_decrement() - dec).abs() < 1e-6 * dec.abs().max(1e-3),
                "{case} at {w} rad/s: log decrement {} against ROSS {dec}",
                m.log_decrement()
            );
        }
    }
    eprintln!("{case}: worst relative eigenvalue difference {worst:e}");
}

#[test]
fn eigenvalues_with_cross_coupled_supports_match_ross() {
    modes_match("cross_coupled", 1e-8);
}

#[test]
fn eigenvalues_with_speed_dependent_supports_match_ross() {
    modes_match("speed_table", 1e-8);
}

fn unbalance_matches(case: &str, tol: f64) {
    let (asm, reference) = load(case);
    let rows = reference["unbalance"]["response"]
        .as_array()
        .expect("a list");
    let speeds: Vec<f64> = rows
        .iter()
        .map(|r| r["speed_rad_s"].as_f64().expect("a number"))
        .collect();
    let ours = linear::unbalance_response(&asm, &speeds).expect("response");
    assert_eq!(
        ours.len(),
        speeds.len(),
        "one rotor, one response per speed"
    );
    let mut worst: f64 = 0.0;
    for (row, resp) in rows.iter().zip(&ours) {
        let nodes = row["nodes"].as_array().expect("a list");
        let scale = nodes
            .iter()
            .flat_map(|n| [c(&n["x"]).norm(), c(&n["y"]).norm()])
            .fold(0.0, f64::max);
        for (k, n) in nodes.iter().enumerate() {
            let o = resp.node(k);
            for (got, want) in [(o.x, c(&n["x"])), (o.y, c(&n["y"]))] {
                let rel = (got - want).norm() / scale;
                worst = worst.max(rel);
                assert!(
                    rel < tol,
                    "{case} at {} rad/s, node {}: {got} against ROSS {want} ({rel:e} of the largest)",
                    resp.speed_rad_s,
                    k + 1
                );
            }
        }
    }
    eprintln!("{case}: worst unbalance-response difference {worst:e} of the largest amplitude");
}

#[test]
fn unbalance_response_with_cross_coupled_supports_matches_ross() {
    unbalance_matches("cross_coupled", 1e-8);
}

#[test]
fn unbalance_response_with_speed_dependent_supports_matches_ross() {
    unbalance_matches("speed_table", 1e-8);
}

/// Conical shaft elements (two of the six tapered, 0.05 ↔ 0.06 m outer diameter), one
/// element per taper and each taper cut into four: ROSS's conical element (Genta &
/// Gugliotta 1988) against tmrotor's integration of the Timoshenko interpolation over the
/// varying section.
#[test]
fn eigenvalues_with_tapered_elements_match_ross() {
    modes_match("tapered_1", 1e-8);
    modes_match("tapered_4", 1e-8);
}
