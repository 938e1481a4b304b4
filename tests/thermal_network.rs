//! Checks of the dual-rotor thermal network: spec parsing and errors, a small linear
//! network against its analytic solution, steady-state energy balance, zero speed,
//! derivatives of the nonlinear thermal forces, and the steady temperatures at 620 rad/s.

use std::f64::consts::PI;
use tmrotor::bearing::{ContactLaw, HertzBearing};
use tmrotor::thermal::convection::shaft_ambient_nusselt;
use tmrotor::thermal::spec::HeatSplit;
use tmrotor::thermal::{BearingLoad, ThermalError, ThermalEval, ThermalNetwork, ThermalSpec};

fn spec() -> ThermalSpec {
    ThermalSpec::dual_rotor().expect("built-in thermal spec parses")
}

/// Radial load `W` carried by a bearing with its initial clearance: find the journal
/// displacement along x whose Hertz force equals `W` (bisection), and return the radial
/// load F_b (Eq. 5) and the number of loaded elements there.
fn gravity_share(b: &HertzBearing, w: f64) -> BearingLoad {
    let (mut lo, mut hi) = (0.0, 1e-3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if b.force(mid, 0.0, 0.0, 0.0).fx < w {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let f = b.force(hi, 0.0, 0.0, 0.0);
    BearingLoad {
        fb_n: f.fb,
        n_loaded: f.n_loaded as f64,
    }
}

/// Representative loads: gravity shares of the rotors (LP ≈ 200 kg: disks 174.6 kg plus
/// shaft; HP ≈ 245 kg: disks 172.7 kg plus shaft), split over the supports: 1# 500 N,
/// 2# 1200 N, 3# 1500 N, 4# 800 N (Tables A.1–A.2 for the Hertz data).
fn representative_loads() -> Vec<BearingLoad> {
    let mk = |law, n, k, c, di, d_o| HertzBearing {
        law,
        n_elements: n,
        stiffness: k,
        clearance_m: c,
        inner_raceway_m: di,
        outer_raceway_m: d_o,
    };
    vec![
        gravity_share(
            &mk(ContactLaw::Ball, 22, 1.45e9, 1e-6, 0.15095, 0.18905),
            500.0,
        ),
        gravity_share(
            &mk(ContactLaw::Ball, 20, 1.57e9, 1e-6, 0.144775, 0.189225),
            1200.0,
        ),
        gravity_share(
            &mk(ContactLaw::Roller, 28, 1.89e8, 5e-6, 0.128, 0.152),
            1500.0,
        ),
        gravity_share(
            &mk(ContactLaw::Roller, 30, 1.46e8, 1e-6, 0.143, 0.167),
            800.0,
        ),
    ]
}

#[test]
fn built_in_spec_has_the_papers_node_numbers() {
    let net = ThermalNetwork::new(&spec()).expect("network builds");
    assert_eq!(net.n_nodes(), 66);
    let name = |n: usize| net.names()[n - 1].clone();
    assert_eq!(name(41), "HPC disk");
    for (node, b) in [(52, "1#"), (55, "2#"), (58, "3#"), (61, "4#")] {
        assert_eq!(name(node), format!("{b} rolling elements"));
    }
    for (node, b) in [(63, "1#"), (64, "2#"), (65, "3#"), (66, "4#")] {
        assert_eq!(name(node), format!("{b} lubricant"));
    }
    assert!(net.names().iter().all(|s| !s.is_empty()));
    assert!(net.capacity().iter().all(|&c| c > 0.0));
    // HPC disk: 94.2194 kg × 480 J/(kg K).
    assert!((net.capacity()[40] - 94.2194 * 480.0).abs() < 1e-9);
}

#[test]
fn spec_errors_name_the_field_path() {
    let doc: toml::Table = toml::from_str(tmrotor::model::BUILTIN_TOML).expect("built-in parses");
    let text = toml::to_string(doc.get("thermal").expect("thermal section")).expect("serializes");
    let bad = text.replacen("f_v = 2.0", "f_v = -2.0", 1);
    let err = ThermalSpec::from_toml_str(&bad, "m.toml").expect_err("must be rejected");
    let msg = err.to_string();
    assert!(
        msg.contains("m.toml") && msg.contains("thermal.bearings[0].f_v"),
        "{msg}"
    );

    let bad = text.replacen("flow_l_min = 2.0", "flow_l_min = 2.0\nflow_rate = 3.0", 1);
    let msg = ThermalSpec::from_toml_str(&bad, "m.toml")
        .expect_err("must be rejected")
        .to_string();
    assert!(msg.contains("m.toml") && msg.contains("flow_rate"), "{msg}");

    let bad = text.replacen("node = 41", "node = 40", 1);
    let msg = ThermalSpec::from_toml_str(&bad, "m.toml")
        .expect_err("must be rejected")
        .to_string();
    assert!(
        msg.contains("thermal.disks[3].node") && msg.contains("already used"),
        "{msg}"
    );

    // From a parsed table (the `[thermal]` section of a model file).
    let table: toml::Table = toml::from_str(&text).expect("toml");
    let s = ThermalSpec::from_table(&table, "model.toml").expect("parses from a table");
    assert_eq!(s.bearings.len(), 4);
    // a missing key names its table (here the `[thermal]` table itself)
    match ThermalSpec::from_table(&toml::Table::new(), "model.toml") {
        Err(ThermalError::Invalid { path, reason, .. }) => {
            assert_eq!(path, "thermal");
            assert!(reason.starts_with("missing field"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn small_linear_network_matches_analytic_solution() {
    // One hollow shaft element split into two segments, no bearings, no disks: a linear
    // network. Heat Q into segment 1; each segment convects to ambient (G_a) and they
    // conduct to each other (G_c). Analytic:
    //   θ1 = Q (G_a + G_c)/((G_a + G_c)² − G_c²),  θ2 = Q G_c/((G_a + G_c)² − G_c²).
    let text = r#"
n_nodes = 2
ambient_temp_c = 20.0
cooling_temp_c = 20.0
flow_l_min = 1.0
min_contact_load_n = 1.0
shafts = [{ chain = "A", speed_ratio = 1.0, inner_diameter_m = 0.1, outer_diameter_m = 0.12, length_m = 0.4, nodes = [1, 2] }]
disks = []
housings = []
bearings = []
[viscosity]
nu0_mm2_s = 39.0
ref_temp_c = 25.0
beta_per_k = 0.02339
[lubricant]
density_kg_m3 = 880.0
specific_heat_j_kg_k = 1870.0
conductivity_w_m_k = 0.14
diffusivity_m2_s = 7.38e-8
[air]
kinematic_viscosity_m2_s = 1.57e-5
conductivity_w_m_k = 0.0262
housing_h_w_m2_k = 15.0
[materials.bearing]
density_kg_m3 = 7830.0
specific_heat_j_kg_k = 450.0
conductivity_w_m_k = 45.0
expansion_per_k = 12.03e-6
modulus_pa = 210e9
poisson = 0.3
[materials.shaft]
density_kg_m3 = 7890.0
specific_heat_j_kg_k = 480.0
conductivity_w_m_k = 46.9
expansion_per_k = 12.03e-6
modulus_pa = 210e9
poisson = 0.3
"#;
    let s = ThermalSpec::from_toml_str(text, "small.toml").expect("small spec");
    let net = ThermalNetwork::new(&s).expect("builds");
    let omega = 300.0;
    // Hand values: S = π/4 (0.12² − 0.1²) = 3.4558e-3 m², segment length 0.2 m,
    // centre-to-centre 0.2 m → G_c = 46.9·S/0.2.
    let area = PI / 4.0 * (0.12 * 0.12 - 0.1 * 0.1);
    let g_c = 46.9 * area / 0.2;
    // Re = ω D²/(2 ν) = 300·0.0144/(2·1.57e-5) = 137 580 ≥ 9600 → Nu = 30.5 Re^−0.0042.
    let re: f64 = 300.0 * 0.0144 / (2.0 * 1.57e-5);
    let nu = 30.5 * re.powf(-0.0042);
    assert_eq!(shaft_ambient_nusselt(re), nu);
    let g_a = nu * 0.0262 / 0.12 * PI * 0.12 * 0.2;
    let k = net.conductance(omega);
    assert!((k.get(0, 1) + g_c).abs() < 1e-12 * g_c);
    assert!((k.get(0, 0) - (g_a + g_c)).abs() < 1e-12 * g_c);
    // Solve K θ = F_T − K·T∞ + Q e1 by Cramer's rule and compare.
    let q = 10.0;
    let f = net.load(omega);
    let b = [f[0] + q, f[1]];
    let det = k.get(0, 0) * k.get(1, 1) - k.get(0, 1) * k.get(1, 0);
    let t1 = (b[0] * k.get(1, 1) - k.get(0, 1) * b[1]) / det;
    let t2 = (k.get(0, 0) * b[1] - k.get(1, 0) * b[0]) / det;
    let den = (g_a + g_c).powi(2) - g_c * g_c;
    let th1 = q * (g_a + g_c) / den;
    let th2 = q * g_c / den;
    assert!(
        (t1 - 20.0 - th1).abs() < 1e-9 * th1,
        "{t1} vs {}",
        20.0 + th1
    );
    assert!((t2 - 20.0 - th2).abs() < 1e-9 * th1);
    // Without heat input the network sits at ambient (steady-state solver, no bearings).
    let t = net.steady_state(omega, &[], 1e-9).expect("steady");
    assert!(t.iter().all(|&x| (x - 20.0).abs() < 1e-9));
}

fn steady(net: &ThermalNetwork, omega: f64, loads: &[BearingLoad]) -> Vec<f64> {
    net.steady_state(omega, loads, 1e-9)
        .expect("steady state converges")
}

#[test]
fn steady_state_energy_balance() {
    let loads = representative_loads();
    for flow in [20.0, 2.0, 1.0] {
        let mut s = spec();
        s.flow_l_min = flow;
        let net = ThermalNetwork::new(&s).expect("network");
        let omega = 620.0;
        let t = steady(&net, omega, &loads);
        let out = net.bearing_outputs(omega, &t, &loads);
        let generated: f64 = out.iter().map(|o| o.q_g_w).sum();
        let removed = net.heat_to_lubricant_flow_w(&t) + net.heat_to_ambient_w(omega, &t);
        assert!(generated > 100.0);
        assert!(
            (generated - removed).abs() < 1e-6 * generated,
            "q_l {flow}: generated {generated} W, removed {removed} W"
        );
        // Q_d reported with the paper's sign equals minus the flow removal.
        let qd: f64 = out.iter().map(|o| o.q_d_w).sum();
        assert!((qd + net.heat_to_lubricant_flow_w(&t)).abs() < 1e-9 * generated);
        // Node balances of the generalized forces: F_bear_b = −F_bear_i − F_bear_o etc.
        for o in &out {
            assert!((o.f_bear_b_w + o.f_bear_i_w + o.f_bear_o_w).abs() < 1e-12 * generated);
        }
    }
}

#[test]
fn zero_speed_means_no_heat_and_ambient_temperatures() {
    let net = ThermalNetwork::new(&spec()).expect("network");
    let loads = representative_loads();
    let t = steady(&net, 0.0, &loads);
    assert!(t.iter().all(|&x| (x - 25.0).abs() < 1e-9), "{t:?}");
    let out = net.bearing_outputs(0.0, &t, &loads);
    assert!(out.iter().all(|o| o.q_g_w == 0.0));
}

#[test]
fn nonlinear_thermal_force_derivatives_match_finite_differences() {
    let mut s = spec();
    s.flow_l_min = 1.0;
    check_derivatives(&s);
    // the heat shared between all four nodes of each bearing
    for b in &mut s.bearings {
        b.heat_split = HeatSplit {
            elements: 0.4,
            inner: 0.2,
            outer: 0.3,
            lubricant: 0.1,
        };
    }
    check_derivatives(&s);
}

/// Where the heat enters moves the temperatures but not the balance: with the heat on the
/// rings (Bossmanns and Tu's split) the network still removes exactly what the bearings
/// generate, the rings run hotter and the rolling elements cooler than with the heat at the
/// elements (the default); a split that does not sum to 1 or has a negative share is refused
/// with its path.
#[test]
fn the_heat_split_moves_temperatures_and_keeps_the_balance() {
    let loads = representative_loads();
    let omega = 620.0;
    let mut s = spec();
    s.flow_l_min = 2.0;
    let base = steady(&ThermalNetwork::new(&s).expect("network"), omega, &loads);
    for b in &mut s.bearings {
        b.heat_split = HeatSplit {
            elements: 0.0,
            inner: 0.5,
            outer: 0.5,
            lubricant: 0.0,
        };
    }
    let net = ThermalNetwork::new(&s).expect("network");
    let rings = steady(&net, omega, &loads);
    let out = net.bearing_outputs(omega, &rings, &loads);
    let generated: f64 = out.iter().map(|o| o.q_g_w).sum();
    let removed = net.heat_to_lubricant_flow_w(&rings) + net.heat_to_ambient_w(omega, &rings);
    assert!(
        (generated - removed).abs() < 1e-6 * generated,
        "generated {generated} W, removed {removed} W"
    );
    // elements / inner / outer nodes of 1#, 2#, 4# (3# has no housing; its outer ring sits
    // in the HP shaft)
    for (b, i) in [(52, 50), (55, 53), (61, 59)] {
        assert!(
            rings[b - 1] < base[b - 1],
            "elements {b}: {} vs {}",
            rings[b - 1],
            base[b - 1]
        );
        assert!(
            rings[i - 1] > base[i - 1],
            "inner {i}: {} vs {}",
            rings[i - 1],
            base[i - 1]
        );
    }
    for (split, path) in [
        (
            (0.5, 0.5, 0.5, 0.0),
            "bearings[0].heat_split: the fractions must sum to 1",
        ),
        (
            (1.2, -0.2, 0.0, 0.0),
            "bearings[0].heat_split.elements: must lie in [0, 1]",
        ),
    ] {
        let mut bad = spec();
        bad.bearings[0].heat_split = HeatSplit {
            elements: split.0,
            inner: split.1,
            outer: split.2,
            lubricant: split.3,
        };
        let err = ThermalNetwork::new(&bad).expect_err("refused").to_string();
        assert!(err.contains(path), "{err}");
    }
}

fn check_derivatives(s: &ThermalSpec) {
    let net = ThermalNetwork::new(s).expect("network");
    let omega = 550.0;
    let loads = representative_loads();
    let full = steady(&net, omega, &loads);
    let nl = net.nonlinear_nodes().to_vec();
    // Perturb the steady temperatures so that every difference is non-zero.
    let t0: Vec<f64> = nl
        .iter()
        .enumerate()
        .map(|(k, &p)| full[p] + 0.7 * ((k * 7 % 5) as f64 - 2.0))
        .collect();
    let q = nl.len();
    let m = net.n_bearings();
    let mut e0 = ThermalEval::new(q, m);
    net.eval_nonlinear(omega, &t0, &loads, &mut e0)
        .expect("eval");
    let scale = e0.g.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let mut ep = ThermalEval::new(q, m);
    let mut em = ThermalEval::new(q, m);
    for c in 0..q {
        let h = 1e-4;
        let mut tp = t0.clone();
        let mut tm = t0.clone();
        tp[c] += h;
        tm[c] -= h;
        net.eval_nonlinear(omega, &tp, &loads, &mut ep)
            .expect("eval");
        net.eval_nonlinear(omega, &tm, &loads, &mut em)
            .expect("eval");
        for r in 0..q {
            let fd = (ep.g[r] - em.g[r]) / (2.0 * h);
            let ex = e0.dg_dt[r * q + c];
            assert!((fd - ex).abs() < 1e-6 * scale, "dg{r}/dT{c}: {ex} vs {fd}");
        }
    }
    for k in 0..m {
        for which in 0..2 {
            let mut lp = loads.clone();
            let mut lm = loads.clone();
            let h = if which == 0 { 1e-2 } else { 1e-4 };
            if which == 0 {
                lp[k].fb_n += h;
                lm[k].fb_n -= h;
            } else {
                lp[k].n_loaded += h;
                lm[k].n_loaded -= h;
            }
            net.eval_nonlinear(omega, &t0, &lp, &mut ep).expect("eval");
            net.eval_nonlinear(omega, &t0, &lm, &mut em).expect("eval");
            for r in 0..q {
                let fd = (ep.g[r] - em.g[r]) / (2.0 * h);
                let ex = if which == 0 {
                    e0.dg_dfb[r * m + k]
                } else {
                    e0.dg_dnb[r * m + k]
                };
                assert!(
                    (fd - ex).abs() < 1e-6 * scale.max(1.0) + 1e-6 * ex.abs(),
                    "bearing {k} which {which} row {r}: {ex} vs {fd}"
                );
            }
        }
    }
}

#[test]
fn steady_temperatures_at_620_rad_s() {
    // Prints the bearing temperatures for the report and checks the qualitative findings
    // that the network reproduces with its default parameters (see the report in the
    // thermal module docs for the comparison with the paper).
    let loads = representative_loads();
    let omega = 620.0;
    for (flow, cooling) in [(20.0, 25.0), (2.0, 25.0), (1.0, 25.0), (2.0, 50.0)] {
        let mut s = spec();
        s.flow_l_min = flow;
        s.cooling_temp_c = cooling;
        let net = ThermalNetwork::new(&s).expect("network");
        let t = steady(&net, omega, &loads);
        let out = net.bearing_outputs(omega, &t, &loads);
        let at = |n: usize| t[n - 1];
        println!("q_l = {flow} L/min, T_L∞ = {cooling} °C, ω = {omega} rad/s");
        for (k, (b, i, o, l)) in [
            (52, 50, 51, 63),
            (55, 53, 54, 64),
            (58, 56, 57, 65),
            (61, 59, 60, 66),
        ]
        .into_iter()
        .enumerate()
        {
            println!(
                "  {}#: T_b({b}) = {:.2}  T_i = {:.2}  T_o = {:.2}  T_L({l}) = {:.2} °C   Q_gl = {:.1} W  Q_gv = {:.1} W  n_b = {}",
                k + 1,
                at(b),
                at(i),
                at(o),
                at(l),
                out[k].q_gl_w,
                out[k].q_gv_w,
                loads[k].n_loaded
            );
        }
        let (tmax, tmin) = t
            .iter()
            .fold((f64::MIN, f64::MAX), |(a, b), &v| (a.max(v), b.min(v)));
        let hottest =
            t.iter().enumerate().fold(
                (0, f64::MIN),
                |a, (k, &v)| if v > a.1 { (k + 1, v) } else { a },
            );
        println!("  max {tmax:.2} °C (node {}), min {tmin:.2} °C", hottest.0);
        // Friction heat enters the rolling elements: for the ball bearings they are the
        // hottest node of the bearing (paper Fig. 14c: T_b highest for 1# and 2#). (For 3#
        // the shaft can feed heat into the inner ring at low flow, as the paper's sign
        // change of F_beari3 shows, so no such check there.)
        for (b, i, o, l) in [(52, 50, 51, 63), (55, 53, 54, 64)] {
            assert!(
                at(b) > at(i) && at(b) > at(o) && at(b) > at(l),
                "q_l {flow}: node {b}"
            );
        }
        // 3# (inter-shaft, relative speed 0.2 ω) is the coolest bearing (paper Fig. 14d–e).
        for b in [52, 55, 61] {
            assert!(at(58) < at(b), "q_l {flow}: 58 vs {b}");
        }
        for l in [63, 64, 66] {
            assert!(at(65) < at(l), "q_l {flow}: 65 vs {l}");
        }
        // Everything above the coldest boundary temperature.
        assert!(tmin >= 25.0 - 1e-9);
    }
}

#[test]
fn clearance_variation_follows_the_network_temperatures() {
    // Uniform heating by 10 K of every node: δv from the network equals Eqs. 1–2 by hand
    // for the 1# bearing (seat = housing seat node 42).
    let net = ThermalNetwork::new(&spec()).expect("network");
    let nl = net.nonlinear_nodes().to_vec();
    let t: Vec<f64> = nl.iter().map(|_| 35.0).collect();
    let c = net.clearance_variation(0, &t);
    let g = 12.03e-6;
    let u_b = g * 19.05e-3 * 10.0;
    let u_i = g * 150.95e-3 * 10.0;
    let (d_o, d_h) = (189.05e-3, 227.782e-3);
    let u_o = g * 1.3 * d_o / (3.0 * (d_o + d_h)) * 10.0 * (3.0 * d_o + 3.0 * d_h);
    assert!((c.delta_v + u_b + 0.5 * (u_i - u_o)).abs() < 1e-15);
    assert_eq!(net.expansion_nodes(0), [51, 49, 50, 41]);
    assert!(
        net.expansion_nodes(2)[3] == 36,
        "3# outer ring sits in HP shaft node 37"
    );
    for p in net.expansion_nodes(3) {
        assert!(net.nonlinear_index(p).is_some());
    }
}

#[test]
fn conductance_matrix_is_symmetric_and_conserves_heat() {
    // K_T (Eq. C.2) is symmetric; each row sums to the node's conductance to the fixed
    // temperatures (ambient or lubricant cooling), so K_T·1 = F_T/T when T_∞ = T_L∞ = T.
    let s = spec().with_study(5.0, 30.0, 30.0);
    let net = ThermalNetwork::new(&s).expect("network");
    for omega in [0.0, 400.0, 700.0] {
        let k = net.conductance(omega);
        let f = net.load(omega);
        for (i, fi) in f.iter().enumerate() {
            let row: f64 = (0..66).map(|j| k.get(i, j)).sum();
            assert!((row * 30.0 - fi).abs() < 1e-9 * (1.0 + fi.abs()), "row {i}");
            for j in 0..66 {
                assert!((k.get(i, j) - k.get(j, i)).abs() < 1e-12 * (1.0 + k.get(i, i).abs()));
            }
        }
    }
    // Speed-dependent convection: faster rotation cools better (Table 1 correlation rises
    // with Re below 9600 and is flat above).
    let k0 = net.conductance(0.0);
    let k1 = net.conductance(700.0);
    assert!(k1.get(0, 0) >= k0.get(0, 0));
}

/// `[thermal.air] rotor_convection_factor` scales the shafts' and disks' convection to
/// ambient and nothing else: the ambient conductance of a node is its row sum of K_T
/// minus its lubricant-flow term (zero off the lubricant nodes), checked against Table 1's
/// correlation by hand for one LP shaft segment.
#[test]
fn the_rotor_convection_factor_scales_only_the_rotor_surfaces() {
    let omega = 620.0;
    let rows = |factor: f64| {
        let mut s = spec();
        s.air.rotor_convection_factor = factor;
        let net = ThermalNetwork::new(&s).expect("network");
        let k = net.conductance(omega);
        let sums: Vec<f64> = (0..66)
            .map(|i| (0..66).map(|j| k.get(i, j)).sum())
            .collect();
        (sums, net.names().to_vec())
    };
    let (one, names) = rows(1.0);
    let (half, _) = rows(0.5);
    let (zero, _) = rows(0.0);
    for i in 0..66 {
        let rotor = names[i].contains("shaft") || names[i].contains("disk");
        let tol = 1e-12 * one[i].abs().max(1.0);
        if rotor {
            assert!(one[i] > 0.0, "{}: convects at factor 1", names[i]);
            assert!((half[i] - 0.5 * one[i]).abs() < tol, "{}", names[i]);
            assert!(zero[i].abs() < tol, "{}: {}", names[i], zero[i]);
        } else {
            assert!((half[i] - one[i]).abs() < tol, "{}", names[i]);
            assert!((zero[i] - one[i]).abs() < tol, "{}", names[i]);
        }
    }
    // LP shaft segment 10 (element 4-5, 3 segments): OD 120 mm, length 316.5125/3 mm,
    // Re = ω D²/(2 ν_air), h = Nu k_air / D, conductance h π D L.
    assert!(names[9].starts_with("LP shaft"), "{}", names[9]);
    let s = spec();
    let (d, l) = (0.120, 0.3165125 / 3.0);
    let re = omega * d * d / (2.0 * s.air.kinematic_viscosity_m2_s);
    let h = shaft_ambient_nusselt(re) * s.air.conductivity_w_m_k / d;
    let by_hand = h * PI * d * l;
    assert!(
        (one[9] - by_hand).abs() < 1e-9 * by_hand,
        "{} vs {by_hand}",
        one[9]
    );
}

#[test]
fn a_rotor_convection_factor_outside_0_to_1_is_refused_by_path() {
    for bad in [-0.5, 1.5] {
        let mut s = spec();
        s.air.rotor_convection_factor = bad;
        let err = ThermalNetwork::new(&s)
            .map(|_| ())
            .expect_err("refused")
            .to_string();
        assert!(err.contains("air.rotor_convection_factor"), "{err}");
        assert!(err.contains("must lie in [0, 1]"), "{err}");
    }
}
