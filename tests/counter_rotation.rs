//! The counter-rotating dual rotor of `examples/counter_rotating.toml` (HP at −6/5 ω):
//! bearing kinematics and friction heat against closed forms.

use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use tmrotor::model::{Model, ModelSet};
use tmrotor::thermal::network::BearingLoad;

/// The model file (relative to `examples/`, `None`: built-in) and `set` table of the
/// example's counter-rotating run.
fn counter_run() -> (Option<String>, ModelSet) {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let text = std::fs::read_to_string(format!("{dir}/counter_rotating.toml")).expect("example");
    let doc: toml::Table = toml::from_str(&text).expect("toml");
    let runs = doc["runs"].as_array().expect("runs");
    let run = runs
        .iter()
        .find(|r| r["name"].as_str() == Some("counter-rotating"))
        .expect("the counter-rotating run");
    let model = run
        .get("model")
        .and_then(|m| m.as_str())
        .map(|m| format!("{dir}/{m}"));
    let set = run["set"]
        .as_table()
        .expect("set table")
        .iter()
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    (model, set)
}

fn rotor((file, set): (Option<String>, ModelSet)) -> CoupledRotor {
    let model = Model::load(file.as_deref().map(std::path::Path::new), &set).expect("model");
    CoupledRotor::new(
        &model,
        &StudyOverrides::default(),
        CouplingOptions::default(),
    )
    .expect("coupled")
}

/// 3# carries LP (inner ring, +ω) inside HP (outer ring, −1.2 ω): the rings' relative
/// speed is 2.2 ω; 2#'s inner ring (HP) turns at −1.2 ω.
#[test]
fn ring_speeds_of_the_counter_rotating_bearings() {
    let counter = rotor(counter_run());
    let net = counter.network().expect("thermal network");
    let w = 500.0;
    let (wi, wo) = net.ring_speeds_rad_s(2, w);
    assert_eq!((wi, wo), (w, -1.2 * w));
    assert!(((wi - wo) - 2.2 * w).abs() < 1e-12 * w);
    let (wi2, wo2) = net.ring_speeds_rad_s(1, w);
    assert_eq!((wi2, wo2), (-1.2 * w, 0.0));
}

/// The friction heat (Palmgren) depends on the rings' relative speed |ω_i − ω_o| only: the
/// counter-rotating 3# at ω (relative 2.2 ω) makes the heat of the co-rotating 3# at 11 ω
/// (relative 0.2 · 11 ω), at the same load and temperatures; its sign does not matter.
#[test]
fn friction_heat_follows_the_relative_speed() {
    let co = rotor((None, ModelSet::new()));
    let counter = rotor(counter_run());
    let (nc, nn) = (co.network().expect("net"), counter.network().expect("net"));
    let temps = vec![60.0; nc.n_nodes()];
    let loads = vec![
        BearingLoad {
            fb_n: 900.0,
            n_loaded: 5.0,
        };
        4
    ];
    let w = 100.0;
    let a = &nn.bearing_outputs(w, &temps, &loads)[2];
    let b = &nc.bearing_outputs(11.0 * w, &temps, &loads)[2];
    assert_eq!(a.name, "3#");
    assert!(a.q_g_w > 0.0);
    for (x, y) in [
        (a.q_gl_w, b.q_gl_w),
        (a.q_gv_w, b.q_gv_w),
        (a.q_g_w, b.q_g_w),
    ] {
        assert!((x - y).abs() < 1e-12 * y.abs(), "{x} against {y}");
    }
    // and not the co-rotating heat at the same ω
    let same = &nc.bearing_outputs(w, &temps, &loads)[2];
    assert!(a.q_g_w > 5.0 * same.q_g_w);
}
