//! Thermal networks generated from the rotor's geometry (`[thermal] generate = true`):
//! the built-in dual rotor's generated network against its hand-written one, a new rotor's
//! network against its geometry and the heat balance, and the errors a user meets.

#![allow(clippy::needless_range_loop)] // node-index loops mirror the matrices

use std::collections::HashMap;
use std::f64::consts::PI;

use tmrotor::model::{BUILTIN_TOML, Model};
use tmrotor::thermal::network::BearingLoad;
use tmrotor::thermal::{ThermalNetwork, ThermalSpec};

fn example(name: &str) -> String {
    let path = format!("{}/examples/rotors/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(path).expect("example file")
}

fn network(text: &str, name: &str) -> (ThermalSpec, ThermalNetwork) {
    let model = Model::from_str(text, name).expect("model");
    let spec = ThermalSpec::of_model(&model)
        .expect("thermal spec")
        .expect("a [thermal] table");
    let net = ThermalNetwork::new(&spec).expect("network");
    (spec, net)
}

/// The mechanical part of a dual-rotor file: from `[gravity]` to the `[thermal]` separator.
fn mechanical(text: &str) -> &str {
    let start = text.find("\n[gravity]").expect("[gravity]");
    let end = text.find("\n# -------").expect("separator");
    &text[start..end]
}

/// Gravity-share loads of the four dual-rotor bearings (those of the network's unit tests).
fn dual_loads() -> Vec<BearingLoad> {
    [500.0, 1200.0, 1500.0, 800.0]
        .iter()
        .map(|&fb_n| BearingLoad {
            fb_n,
            n_loaded: 6.0,
        })
        .collect()
}

/// The generated dual rotor is the built-in with the thermal table replaced: its
/// mechanical part is the built-in's word for word, and its network is the hand-written one
/// up to the node numbering (nodes matched by name) and the cage masses (which enter only
/// the rolling-element heat capacities): the same conductances, loads, steady temperatures
/// and clearance variations.
#[test]
fn generated_dual_rotor_network_is_the_hand_written_one() {
    let generated = example("dual_rotor_generated.toml");
    assert_eq!(
        mechanical(&generated),
        mechanical(BUILTIN_TOML),
        "the mechanical part of examples/rotors/dual_rotor_generated.toml must stay the \
         built-in's"
    );
    let (hs, hand) = network(BUILTIN_TOML, "built-in");
    let (gs, made) = network(&generated, "generated");
    assert_eq!(made.n_nodes(), hand.n_nodes());
    assert_eq!(gs.n_nodes, 66);
    // node of `made` → node of `hand`, by name
    let by_name: HashMap<&str, usize> = hand
        .names()
        .iter()
        .enumerate()
        .map(|(k, n)| (n.as_str(), k))
        .collect();
    let map: Vec<usize> = made
        .names()
        .iter()
        .map(|n| {
            *by_name
                .get(n.as_str())
                .unwrap_or_else(|| panic!("{n} not in the built-in"))
        })
        .collect();
    let omega = 620.0;
    let (kg, kh) = (made.conductance(omega), hand.conductance(omega));
    let scale = kh.data.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let n = made.n_nodes();
    for i in 0..n {
        for j in 0..n {
            let (a, b) = (kg.data[i * n + j], kh.data[map[i] * n + map[j]]);
            assert!(
                (a - b).abs() <= 1e-12 * scale,
                "K_T[{}, {}] ({} / {}): {a} vs {b}",
                i + 1,
                j + 1,
                made.names()[i],
                made.names()[j]
            );
        }
    }
    let (fg, fh) = (made.load(omega), hand.load(omega));
    for i in 0..n {
        assert!((fg[i] - fh[map[i]]).abs() <= 1e-12 * fh[map[i]].abs().max(1.0));
    }
    // heat capacities: equal but at the rolling elements, where the cage mass differs
    for i in 0..n {
        let (a, b) = (made.capacity()[i], hand.capacity()[map[i]]);
        if made.names()[i].ends_with("rolling elements") {
            assert!((a - b).abs() < 0.05 * b, "{}: {a} vs {b}", made.names()[i]);
        } else {
            assert!(
                (a - b).abs() <= 1e-12 * b,
                "{}: {a} vs {b}",
                made.names()[i]
            );
        }
    }
    let loads = dual_loads();
    let (tg, th) = (
        made.steady_state(omega, &loads, 1e-9).expect("steady"),
        hand.steady_state(omega, &loads, 1e-9).expect("steady"),
    );
    for i in 0..n {
        assert!(
            (tg[i] - th[map[i]]).abs() < 1e-8,
            "{}: {} vs {} °C",
            made.names()[i],
            tg[i],
            th[map[i]]
        );
    }
    let nl = |net: &ThermalNetwork, t: &[f64]| -> Vec<f64> {
        net.nonlinear_nodes().iter().map(|&p| t[p]).collect()
    };
    let (ng, nh) = (nl(&made, &tg), nl(&hand, &th));
    for k in 0..4 {
        let (a, b) = (
            made.clearance_variation(k, &ng).delta_v,
            hand.clearance_variation(k, &nh).delta_v,
        );
        assert!((a - b).abs() < 1e-15, "bearing {k}: δv {a} vs {b}");
    }
    // what differs: the cage masses, generated as half the rolling-element set's mass
    for (g, h) in gs.bearings.iter().zip(&hs.bearings) {
        assert_eq!(g.name, h.name);
        assert!((g.cage_mass_kg - h.cage_mass_kg).abs() < 0.02, "{}", g.name);
    }
}

/// A new rotor: the single spool of `examples/rotors/single_spool.toml`. Its network has the
/// nodes the rules give, heat capacities equal to the geometry's (shaft tubes, the disk's
/// mass), and at a steady state the friction heat leaves through the ambient and the
/// lubricant flows, nothing else.
#[test]
fn single_spool_network_follows_its_geometry() {
    let text = example("single_spool.toml");
    let (spec, net) = network(&text, "single_spool");
    // shafts 24 mm, 3 × 250 mm, 24 mm at ≤ 110 mm: 1 + 3·3 + 1 = 11; disk 1; two bearings
    // with housings: 2 × (3 + 4)
    assert_eq!(net.n_nodes(), 11 + 1 + 14);
    assert_eq!(spec.shafts.len(), 5);
    assert!(spec.shafts.iter().all(|s| s.chain == "rotor"));
    // shaft heat capacity: ρ c π/4 (D² − d²) L per element, summed over its segments
    let (rho, c) = (7.89e3, 480.0);
    let tube = |d_o: f64, d_i: f64, l: f64| rho * c * PI / 4.0 * (d_o * d_o - d_i * d_i) * l;
    let expected = 2.0 * tube(0.140, 0.106, 0.024) + 3.0 * tube(0.140, 0.100, 0.250);
    let got: f64 = net
        .names()
        .iter()
        .zip(net.capacity())
        .filter(|(n, _)| n.contains(" shaft "))
        .map(|(_, c)| c)
        .sum();
    assert!(
        (got - expected).abs() < 1e-12 * expected,
        "{got} vs {expected}"
    );
    let disk = net
        .names()
        .iter()
        .position(|n| n == "disk disk")
        .expect("disk node");
    assert!((net.capacity()[disk] - 94.2194 * c).abs() < 1e-9);
    // the disk sits on the first segment of element 3-4, the bearings on the journals
    assert_eq!(spec.disks[0].shaft_node, 5);
    assert_eq!(spec.disks[0].bore_diameter_m, 0.140);
    assert_eq!(spec.bearings[0].inner_shaft_node, 1);
    assert_eq!(spec.bearings[1].inner_shaft_node, 11);
    assert_eq!(spec.bearings[0].seat_diameter_m, 2.0 * 113.891e-3);
    // heat balance at a steady state
    let omega = 500.0;
    let loads = [
        BearingLoad {
            fb_n: 840.0,
            n_loaded: 6.0,
        },
        BearingLoad {
            fb_n: 550.0,
            n_loaded: 6.0,
        },
    ];
    let t = net.steady_state(omega, &loads, 1e-10).expect("steady");
    let q_g: f64 = net
        .bearing_outputs(omega, &t, &loads)
        .iter()
        .map(|b| b.q_g_w)
        .sum();
    let out = net.heat_to_ambient_w(omega, &t) + net.heat_to_lubricant_flow_w(&t);
    assert!(q_g > 100.0, "friction heat {q_g} W");
    assert!((q_g - out).abs() < 1e-8 * q_g, "in {q_g} W, out {out} W");
    // the bearings are the hottest parts
    let hottest = (0..net.n_nodes())
        .max_by(|&a, &b| t[a].total_cmp(&t[b]))
        .expect("nodes");
    assert!(net.names()[hottest].contains("rolling elements"));
}

/// The order of the shaft elements in the file does not change the network: elements are
/// ordered along the axis.
#[test]
fn element_order_does_not_change_the_network() {
    let text = example("single_spool.toml");
    let (a, b) = text.split_once("[[shafts]]").expect("shafts");
    let (shafts, rest) = b.split_once("[[disks]]").expect("disks");
    let mut blocks: Vec<String> = format!("[[shafts]]{shafts}")
        .split("[[shafts]]")
        .filter(|s| !s.trim().is_empty())
        .map(|s| format!("[[shafts]]{s}"))
        .collect();
    blocks.reverse();
    let text2 = format!("{a}{}[[disks]]{rest}", blocks.concat());
    assert_ne!(text2, text);
    let (_, n1) = network(&text, "single_spool");
    let (_, n2) = network(&text2, "shuffled");
    let by_name: HashMap<&str, usize> = n1
        .names()
        .iter()
        .enumerate()
        .map(|(k, n)| (n.as_str(), k))
        .collect();
    let omega = 400.0;
    let (k1, k2) = (n1.conductance(omega), n2.conductance(omega));
    let n = n1.n_nodes();
    for i in 0..n {
        let p = by_name[n2.names()[i].as_str()];
        for j in 0..n {
            let q = by_name[n2.names()[j].as_str()];
            assert!(
                (k2.data[i * n + j] - k1.data[p * n + q]).abs() < 1e-12,
                "{} / {}: {} vs {}",
                n2.names()[i],
                n2.names()[j],
                k2.data[i * n + j],
                k1.data[p * n + q]
            );
        }
    }
}

/// Builds the single spool with `edit` applied to its text and returns the error text.
fn error_of(edit: impl Fn(String) -> String) -> String {
    let text = edit(example("single_spool.toml"));
    let model = match Model::from_str(&text, "spool.toml") {
        Ok(m) => m,
        Err(e) => return e.to_string(),
    };
    match ThermalSpec::of_model(&model) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn generated_table_errors_name_the_field() {
    type Edit = Box<dyn Fn(String) -> String>;
    let cases: Vec<(Edit, &str, &str)> = vec![
        (
            Box::new(|t| t.replacen("specific_heat_j_kg_k = 480.0\n", "", 1)),
            "materials[0].specific_heat_j_kg_k",
            "needs it",
        ),
        (
            Box::new(|t| t + "\n[[thermal.bearings]]\nname = \"middle\"\nf_v = 3.0\n"),
            "thermal.bearings[0].name",
            "no bearing \"middle\"",
        ),
        (
            Box::new(|t| t + "\n[[thermal.bearings]]\nname = \"rear\"\nf_v = -3.0\n"),
            "thermal.bearings[0].f_v",
            "> 0",
        ),
        (
            Box::new(|t| t.replace("generate = true", "generate = false")),
            "thermal.generate",
            "false",
        ),
        (
            Box::new(|t| t.replace("generate = true", "generate = true\nsegment_lenght_m = 0.1")),
            "thermal",
            "segment_lenght_m",
        ),
        (
            Box::new(|t| t.replace("generate = true", "generate = true\nsegment_length_m = 0.0")),
            "thermal.segment_length_m",
            "> 0",
        ),
        (
            Box::new(|t| {
                t + "\n[thermal.ball_bearings]\nheat_split = { elements = 0.5, inner = 0.2 }\n"
            }),
            "thermal.ball_bearings.heat_split",
            "sum to 1",
        ),
        (
            Box::new(|t| t.replacen("housing_radius_m = 113.891e-3\n", "", 1)),
            "bearings[0].housing_radius_m",
            "needs it",
        ),
        (
            Box::new(|t| {
                t.replace(
                    "polar_inertia_kg_m2 = 2.900985",
                    "polar_inertia_kg_m2 = 0.2",
                )
            }),
            "disks[0].polar_inertia_kg_m2",
            "too small",
        ),
    ];
    for (edit, path, reason) in cases {
        let e = error_of(edit);
        assert!(
            e.contains(path) && e.contains(reason),
            "expected {path}: …{reason}…, got\n{e}"
        );
        assert!(e.starts_with("spool.toml:"), "names the file: {e}");
    }
}

/// A disk on a node that no shaft element touches cannot be placed.
#[test]
fn a_part_off_the_shafts_is_refused() {
    let e = error_of(|t| {
        t.replace(
            "nodes = [1, 2, 3, 4, 5, 6]",
            "nodes = [1, 2, 3, 4, 5, 6, 7]",
        )
        .replace(
            "[[disks]]\nid = \"disk\"\nnode = 3",
            "[[disks]]\nid = \"disk\"\nnode = 7",
        ) + "\n[[supports]]\nid = \"s7\"\nnode = 7\nstiffness_n_m = 1e7\n"
    });
    assert!(
        e.contains("disks[0].node") && e.contains("node 7 ends no shaft element"),
        "{e}"
    );
}

/// `tmrotor model thermal FILE` spells a generated network out node by node: the printed
/// table, put in place of the generated one, is read back as the same network.
#[test]
fn model_thermal_prints_a_table_that_reads_back() {
    let path = format!(
        "{}/examples/rotors/single_spool.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(["model", "thermal", &path])
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        printed.contains("#   18  front rolling elements"),
        "{printed}"
    );
    let text = example("single_spool.toml");
    let mech = &text[..text.find("\n[thermal]").expect("[thermal]")];
    let (generated, _) = network(&text, "single_spool");
    let (written, _) = network(&format!("{mech}\n{printed}"), "written");
    assert_eq!(written, generated);
}

/// Geometry the dual rotor does not show: a tapered element's segments take its mean
/// diameters, and an inter-shaft bearing without `outer_shaft_radius_m` sits on the outer
/// rotor's shaft with that shaft's outer diameter as its seat.
#[test]
fn tapered_elements_and_a_default_inter_shaft_seat() {
    // the single spool's middle element tapered from 140/100 mm to 150/110 mm
    let text = example("single_spool.toml").replacen(
        "nodes = [3, 4]\ninner_diameter_m = 100e-3\nouter_diameter_m = 140e-3\n",
        "nodes = [3, 4]\ninner_diameter_m = 100e-3\nouter_diameter_m = 140e-3\n\
         outer_diameter_end_m = 150e-3\ninner_diameter_end_m = 110e-3\n",
        1,
    );
    assert!(text.contains("outer_diameter_end_m"));
    let (spec, _) = network(&text, "tapered");
    let tapered = spec
        .shafts
        .iter()
        .find(|s| s.label == "rotor element 3-4")
        .expect("element 3-4");
    assert!((tapered.outer_diameter_m - 0.145).abs() < 1e-15);
    assert!((tapered.inner_diameter_m - 0.105).abs() < 1e-15);
    // the disk at node 3 sits on element 3-4's first segment; its bore is that element's
    // outer diameter at node 3, the start of the taper
    assert_eq!(spec.disks[0].bore_diameter_m, 0.140);

    // the dual rotor's 3# without outer_shaft_radius_m: seat = HP element 17-18's outer
    // diameter (180 mm), which is what 2 r_HP gives there
    let generated = example("dual_rotor_generated.toml");
    let cut = generated.replacen("outer_shaft_radius_m = 90e-3\n", "", 1);
    assert_ne!(cut, generated);
    let (spec, _) = network(&cut, "no r_HP");
    let b3 = spec.bearings.iter().find(|b| b.name == "3#").expect("3#");
    assert_eq!(b3.seat_diameter_m, 0.180);
    assert!(b3.housing.is_none());
    assert_eq!(b3.outer_speed_ratio, 1.2);
    assert_eq!(b3.inner_speed_ratio, 1.0);
}
