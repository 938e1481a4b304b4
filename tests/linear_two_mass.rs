//! Two lumped disks on two rotors, coupled by a support between their nodes: the
//! classic two-mass oscillator, checked against its closed-form frequencies.

use tmrotor::linear;
use tmrotor::model::{Assembly, Model};

const TEXT: &str = r#"
name = "two_mass"
[gravity]
enabled = false
[[rotors]]
id = "A"
speed_ratio = 1
nodes = [1]
[[rotors]]
id = "B"
speed_ratio = "3/2"
nodes = [2]
[[disks]]
id = "a"
node = 1
mass_kg = 2.0
polar_inertia_kg_m2 = 0.02
diametral_inertia_kg_m2 = 0.01
[[disks]]
id = "b"
node = 2
mass_kg = 1.0
polar_inertia_kg_m2 = 0.04
diametral_inertia_kg_m2 = 0.02
[[supports]]
id = "ground"
node = 1
stiffness_n_m = 1000.0
rotational_stiffness_n_m_rad = 30.0
[[supports]]
id = "coupling"
node = 1
to_node = 2
stiffness_n_m = 500.0
rotational_stiffness_n_m_rad = 10.0
"#;

/// Eigenfrequencies of m1 ẍ1 + (k1+k2) x1 − k2 x2 = 0, m2 ẍ2 − k2 x1 + k2 x2 = 0.
fn two_mass(m1: f64, m2: f64, k1: f64, k2: f64) -> [f64; 2] {
    let b = (k1 + k2) / m1 + k2 / m2;
    let c = k1 * k2 / (m1 * m2);
    let d = (b * b - 4.0 * c).sqrt();
    [((b - d) / 2.0).sqrt(), ((b + d) / 2.0).sqrt()]
}

#[test]
fn support_between_two_nodes_couples_them() {
    let model = Model::from_str(TEXT, "two_mass").expect("valid");
    let asm = Assembly::new(&model).expect("assembles");
    assert_eq!(asm.n_dof, 8);
    let modes = linear::modes(&asm, 0.0, 8).expect("modes");
    let mut got: Vec<f64> = modes.iter().map(|m| m.frequency_rad_s).collect();
    got.sort_by(f64::total_cmp);
    let t = two_mass(2.0, 1.0, 1000.0, 500.0);
    let r = two_mass(0.01, 0.02, 30.0, 10.0);
    let mut want = vec![t[0], t[0], t[1], t[1], r[0], r[0], r[1], r[1]];
    want.sort_by(f64::total_cmp);
    assert_eq!(got.len(), 8);
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-9 * w, "{g} vs {w}");
    }
}

/// Spinning, the tilt of a single free-standing disk on a rotational spring splits into
/// ν = (±Ω J_p + √((Ω J_p)² + 4 J_d k_θ)) / (2 J_d) with Ω its own rotor's speed.
#[test]
fn each_rotor_spins_at_its_own_ratio() {
    // Decouple the disks to test each rotor alone.
    let text = TEXT.replace(
        "stiffness_n_m = 500.0\nrotational_stiffness_n_m_rad = 10.0",
        "stiffness_n_m = 0.0\nrotational_stiffness_n_m_rad = 0.0",
    ) + "[[supports]]\nid = \"g2\"\nnode = 2\nstiffness_n_m = 800.0\nrotational_stiffness_n_m_rad = 20.0\n";
    let model = Model::from_str(&text, "two_mass").expect("valid");
    let asm = Assembly::new(&model).expect("assembles");
    let w = 40.0;
    let modes = linear::modes(&asm, w, 8).expect("modes");
    let got: Vec<f64> = modes.iter().map(|m| m.frequency_rad_s).collect();
    for (jd, jp, kt, ratio) in [(0.01, 0.02, 30.0, 1.0), (0.02, 0.04, 20.0, 1.5)] {
        let om: f64 = ratio * w;
        let root = ((om * jp).powi(2) + 4.0 * jd * kt).sqrt();
        for nu in [
            (om * jp + root) / (2.0 * jd),
            (-om * jp + root) / (2.0 * jd),
        ] {
            assert!(
                got.iter().any(|g| (g - nu).abs() < 1e-9 * nu),
                "{nu} not in {got:?}"
            );
        }
    }
}

/// A disk on an anisotropic, damped support: √(k_xx/m) and √(k_yy/m), each with
/// ζ = c/(2√(k m)); the rotor's speed ratio defaults to 1.
#[test]
fn anisotropic_damped_support() {
    let text = r#"
name = "aniso"
[gravity]
enabled = false
[[rotors]]
id = "r"
nodes = [1]
[[disks]]
id = "d"
node = 1
mass_kg = 4.0
polar_inertia_kg_m2 = 0.02
diametral_inertia_kg_m2 = 0.01
[[supports]]
id = "s"
node = 1
stiffness_xx_n_m = 4.0e4
stiffness_yy_n_m = 9.0e4
damping_xx_n_s_m = 20.0
damping_yy_n_s_m = 6.0
rotational_stiffness_n_m_rad = 1000.0
"#;
    let model = Model::from_str(text, "aniso").expect("valid");
    assert_eq!(model.speed_ratio(0).value(), 1.0);
    let asm = Assembly::new(&model).expect("assembles");
    let modes = linear::modes(&asm, 0.0, 2).expect("modes");
    for (m, (k, c)) in modes.iter().zip([(4.0e4_f64, 20.0), (9.0e4, 6.0)]) {
        let wn = (k / 4.0).sqrt();
        let zeta = c / (2.0 * (k * 4.0).sqrt());
        assert!(
            (m.undamped_rad_s - wn).abs() < 1e-9 * wn,
            "{} vs {wn}",
            m.undamped_rad_s
        );
        assert!(
            (m.damping_ratio - zeta).abs() < 1e-9,
            "{} vs {zeta}",
            m.damping_ratio
        );
        assert_eq!(m.whirl, linear::Whirl::Planar);
    }
}
