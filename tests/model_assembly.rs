//! Properties of the assembled built-in dual rotor, against sums computed here from the
//! model data, and of the bearing linearisation.

#![allow(clippy::needless_range_loop)] // index loops read like the matrix algebra

use std::collections::BTreeMap;
use std::f64::consts::PI;

use tmrotor::bearing::{ContactLaw, HertzLaw};
use tmrotor::linear;
use tmrotor::model::{Assembly, Dir, Model, dof};
use tmrotor::system::DenseMatrix;

fn builtin() -> (Model, Assembly) {
    let model = Model::builtin().expect("built-in model is valid");
    let asm = Assembly::new(&model).expect("assembles");
    (model, asm)
}

fn max_abs(m: &DenseMatrix) -> f64 {
    m.data.iter().fold(0.0, |a, v| a.max(v.abs()))
}

#[test]
fn builtin_has_paper_layout() {
    let (model, asm) = builtin();
    assert_eq!(asm.n_dof, 72);
    assert_eq!(model.node_ids(), (1..=18).collect::<Vec<u32>>());
    assert_eq!(model.dof(1, Dir::X), Some(0));
    assert_eq!(model.dof(18, Dir::ThetaY), Some(71));
    assert_eq!(dof(7, Dir::Y), 29);
    let ratios: Vec<String> = model.speed_ratios().iter().map(|r| r.to_string()).collect();
    assert_eq!(ratios, vec!["1/1", "6/5"]);
    // ζ = 0.0325 at 300 and 700 rad/s: a0 = 2ζω1ω2/(ω1+ω2), a1 = 2ζ/(ω1+ω2)
    let (a0, a1) = model.rayleigh();
    assert!(
        (a0 - 13.65).abs() < 1e-12 && (a1 - 6.5e-5).abs() < 1e-18,
        "{a0} {a1}"
    );
    // the literature values: ζ = 0.02 (SPEC §2.1: a0 ≈ 8.4 1/s, a1 ≈ 4e-5 s)
    let (a0, a1) = tmrotor::model::Model::literature()
        .expect("literature model")
        .rayleigh();
    assert!((a0 - 8.4).abs() < 1e-12 && (a1 - 4e-5).abs() < 1e-18);
    assert_eq!(asm.bearings.len(), 4);
    assert_eq!(asm.unbalances.len(), 4);
}

#[test]
fn matrices_have_the_right_symmetry_and_definiteness() {
    let (_, asm) = builtin();
    let n = asm.n_dof;
    for (name, m, sign) in [
        ("M", &asm.mass, 1.0),
        ("K", &asm.stiffness, 1.0),
        ("C", &asm.damping, 1.0),
        ("K_b", &asm.bearing_stiffness, 1.0),
        ("G_LP", &asm.gyro[0].matrix, -1.0),
        ("G_HP", &asm.gyro[1].matrix, -1.0),
    ] {
        let scale = max_abs(m);
        assert!(scale > 0.0, "{name} is empty");
        for i in 0..n {
            for j in 0..n {
                assert!(
                    (m.get(i, j) - sign * m.get(j, i)).abs() <= 1e-12 * scale,
                    "{name} ({i},{j})"
                );
            }
        }
    }
    // M positive definite: all eigenvalues of the symmetric matrix positive.
    let mm = faer::Mat::from_fn(n, n, |i, j| asm.mass.get(i, j));
    let ev = mm
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .expect("eigenvalues");
    assert!(ev.iter().all(|&v| v > 0.0), "min eigenvalue {:e}", ev[0]);
    // K + K_b positive definite too (the rotors are supported).
    let kk = faer::Mat::from_fn(n, n, |i, j| {
        asm.stiffness.get(i, j) + asm.bearing_stiffness.get(i, j)
    });
    let ev = kk
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .expect("eigenvalues");
    assert!(ev[0] > 0.0);
    // Shafts and the node-4 support alone leave the HP rotor free: K is singular there.
    let k0 = faer::Mat::from_fn(n, n, |i, j| asm.stiffness.get(i, j));
    let ev = k0
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .expect("eigenvalues");
    assert!(ev[0].abs() < 1e-6 * ev[n - 1]);
}

#[test]
fn total_mass_and_polar_inertia_equal_sum_of_parts() {
    let (model, asm) = builtin();
    let spec = &model.spec;
    let n = asm.n_dof;
    let rho = |id: &str| {
        spec.materials
            .iter()
            .find(|m| m.id == id)
            .expect("material")
            .density_kg_m3
    };
    // Sums over parts, per rotor.
    let mut mass = [0.0; 2];
    let mut polar = [0.0; 2];
    let rotor_of = |node: u32| usize::from(node >= 12);
    for s in &spec.shafts {
        let (d, di, l) = (s.outer_diameter_m, s.inner_diameter_m, s.length_m);
        let r = rotor_of(s.nodes[0]);
        mass[r] += rho(&s.material) * PI / 4.0 * (d * d - di * di) * l;
        polar[r] += rho(&s.material) * PI / 32.0 * (d.powi(4) - di.powi(4)) * l;
    }
    for d in &spec.disks {
        mass[rotor_of(d.node)] += d.mass_kg;
        polar[rotor_of(d.node)] += d.polar_inertia_kg_m2;
    }
    // Axial positions along each rotor from the element lengths.
    let mut z: BTreeMap<u32, f64> = BTreeMap::new();
    z.insert(1, 0.0);
    z.insert(12, 0.0);
    for s in &spec.shafts {
        let za = z[&s.nodes[0]];
        z.insert(s.nodes[1], za + s.length_m);
    }
    for r in 0..2 {
        let nodes: Vec<u32> = if r == 0 {
            (1..=11).collect()
        } else {
            (12..=18).collect()
        };
        // Rigid translation along x: e_xᵀ M e_x = mass.
        let mut ex = vec![0.0; n];
        for &k in &nodes {
            ex[dof(k as usize - 1, Dir::X)] = 1.0;
        }
        let mut m_rigid = 0.0;
        for i in 0..n {
            for j in 0..n {
                m_rigid += ex[i] * asm.mass.get(i, j) * ex[j];
            }
        }
        assert!(
            (m_rigid - mass[r]).abs() < 1e-9 * mass[r],
            "rotor {r}: {m_rigid} vs {}",
            mass[r]
        );
        // Rigid tilts a (x = zα, θx = α) and b (y = zβ, θy = β): aᵀ G_r b = J_p total.
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        for &k in &nodes {
            let i = k as usize - 1;
            a[dof(i, Dir::X)] = z[&k];
            a[dof(i, Dir::ThetaX)] = 1.0;
            b[dof(i, Dir::Y)] = z[&k];
            b[dof(i, Dir::ThetaY)] = 1.0;
        }
        let g = &asm.gyro[r].matrix;
        let mut jp = 0.0;
        for i in 0..n {
            for j in 0..n {
                jp += a[i] * g.get(i, j) * b[j];
            }
        }
        assert!(
            (jp - polar[r]).abs() < 1e-9 * polar[r],
            "rotor {r}: {jp} vs {}",
            polar[r]
        );
    }
    // Gravity: total vertical load = −g × total mass, no horizontal load.
    let fx: f64 = (0..18).map(|i| asm.gravity[dof(i, Dir::X)]).sum();
    let fy: f64 = (0..18).map(|i| asm.gravity[dof(i, Dir::Y)]).sum();
    let total = mass[0] + mass[1];
    assert!((fx + 9.81 * total).abs() < 1e-9 * total);
    assert_eq!(fy, 0.0);
}

#[test]
fn gyroscopic_terms_scale_with_each_rotors_speed() {
    let (_, asm) = builtin();
    let w = 500.0;
    let v = asm.velocity_matrix(w);
    // HPC disk (node 14) on the HP rotor: +λω J_p coupling θx→θy (paper Eq. 6, plane x).
    let (tx, ty) = (dof(13, Dir::ThetaX), dof(13, Dir::ThetaY));
    let g_hp = asm.gyro[1].matrix.get(tx, ty);
    assert!(g_hp >= 2.900985, "includes the disk J_p");
    assert_eq!(asm.gyro[0].matrix.get(tx, ty), 0.0);
    let expected = asm.damping.get(tx, ty) + 1.2 * w * g_hp;
    assert!((v.get(tx, ty) - expected).abs() < 1e-12 * expected.abs());
    // LPC disk (node 3) on the LP rotor: ω J_p.
    let (tx, ty) = (dof(2, Dir::ThetaX), dof(2, Dir::ThetaY));
    let g_lp = asm.gyro[0].matrix.get(tx, ty);
    assert!(g_lp >= 6.4725);
    assert!((v.get(tx, ty) - asm.damping.get(tx, ty) - w * g_lp).abs() < 1e-9);
    // linear_part carries the same matrix and empty thermal blocks.
    let lp = asm.linear_part(w);
    assert_eq!(lp.damping, v);
    assert_eq!(lp.thermal_capacity.n, 0);
}

#[test]
fn unbalance_force_uses_each_disks_own_speed() {
    let (_, asm) = builtin();
    let w = 400.0;
    let t = 0.0123;
    let mut f = vec![0.0; asm.n_dof];
    asm.add_unbalance_force(w, t, &mut f);
    // HPC disk at node 14: m e (λω)², rotating at λω from +x towards +y.
    let (m, e, om) = (94.2194, 1e-6, 1.2 * w);
    let (fx, fy) = (f[dof(13, Dir::X)], f[dof(13, Dir::Y)]);
    assert!((fx - m * e * om * om * (om * t).cos()).abs() < 1e-12);
    assert!((fy - m * e * om * om * (om * t).sin()).abs() < 1e-12);
    // LPT disk at node 9 at ω.
    let (m, e) = (73.115, 14e-6);
    assert!((f[dof(8, Dir::X)] - m * e * w * w * (w * t).cos()).abs() < 1e-12);
    // forcing = gravity + unbalance.
    let mut total = vec![0.0; asm.n_dof];
    asm.forcing(w, t, &mut total);
    for i in 0..asm.n_dof {
        assert!((total[i] - asm.gravity[i] - f[i]).abs() < 1e-9);
    }
}

/// Without clearance the averaged Hertz law is homogeneous of degree n, so the tangent
/// stiffness along the load is n times the secant stiffness across it.
#[test]
fn hertz_linearisation_without_clearance_has_ratio_n() {
    for (law, n, count) in [
        (ContactLaw::Ball, 1.5, 22),
        (ContactLaw::Roller, 10.0 / 9.0, 28),
    ] {
        let law = HertzLaw {
            stiffness: 1.45e9,
            law,
            count,
            clearance_m: 0.0,
        };
        let k = law.tangent_matrix([0.0, -2000.0]);
        assert!((k[1][1] / k[0][0] - n).abs() < 1e-9, "{k:?}");
        assert!(k[0][1].abs() < 1e-9 * k[1][1]);
        // The force at the solved displacement is the load.
        let r = law.displacement_for_load(2000.0);
        assert!((law.force_and_slope(r).0 - 2000.0).abs() < 1e-6);
        // Slope against a central difference.
        let h = r * 1e-6;
        let fd = (law.force_and_slope(r + h).0 - law.force_and_slope(r - h).0) / (2.0 * h);
        assert!((law.force_and_slope(r).1 - fd).abs() < 1e-6 * fd);
    }
}

/// A symmetric, statically determinate rotor: a disk at mid-span between two identical
/// ball bearings carries half its weight (plus half the shaft's) on each bearing.
#[test]
fn static_bearing_loads_of_a_symmetric_rotor_are_half_the_weight() {
    let mut text = String::from(
        "name = \"sym\"\n[[materials]]\nid = \"steel\"\nyoungs_modulus_pa = 2.1e11\n\
         poisson_ratio = 0.3\ndensity_kg_m3 = 7850\n\
         [[rotors]]\nid = \"r\"\nspeed_ratio = 1\nnodes = [1, 2, 3, 4, 5]\n",
    );
    for i in 1..=4 {
        text += &format!(
            "[[shafts]]\nnodes = [{i}, {}]\nlength_m = 0.2\ninner_diameter_m = 0.02\n\
             outer_diameter_m = 0.05\nmaterial = \"steel\"\n",
            i + 1
        );
    }
    text += "[[disks]]\nid = \"d\"\nnode = 3\nmass_kg = 20\npolar_inertia_kg_m2 = 0.2\n\
             diametral_inertia_kg_m2 = 0.1\n";
    for (id, node) in [("A", 1), ("B", 5)] {
        text += &format!(
            "[[bearings]]\nid = \"{id}\"\nkind = \"ball\"\ninner_node = {node}\n\
             material = \"steel\"\nbore_diameter_m = 0.05\noutside_diameter_m = 0.09\n\
             inner_race_diameter_m = 0.058\nouter_race_diameter_m = 0.082\n\
             pitch_diameter_m = 0.07\nelement_count = 12\nelement_diameter_m = 0.012\n\
             width_m = 0.02\nhertz_stiffness = 1e9\ninitial_clearance_m = 1e-6\n\
             shaft_inner_radius_m = 0.01\n"
        );
    }
    let model = Model::from_str(&text, "sym").expect("valid");
    let asm = Assembly::new(&model).expect("assembles");
    let shaft_mass = 7850.0 * PI / 4.0 * (0.05f64.powi(2) - 0.02f64.powi(2)) * 0.8;
    let half_weight = 0.5 * 9.81 * (20.0 + shaft_mass);
    for b in &asm.bearings {
        assert!(
            (b.load_n[0].abs() - half_weight).abs() < 1e-6 * half_weight,
            "{}: {:?} vs {half_weight}",
            b.id,
            b.load_n
        );
        assert!(b.load_n[1].abs() < 1e-9 * half_weight);
        let law = HertzLaw {
            stiffness: 1e9,
            law: ContactLaw::Ball,
            count: 12,
            clearance_m: 1e-6,
        };
        let k = law.tangent_matrix([half_weight, 0.0]);
        assert!((b.stiffness_n_m[0][0] - k[0][0]).abs() < 1e-5 * k[0][0]);
    }
}

/// Proportional damping gives every mode ζ = a0/(2ω_n) + a1 ω_n/2 (a second, modal,
/// route to the damping ratios the state-space solver reports).
#[test]
fn rayleigh_damping_ratios_follow_the_modal_formula() {
    let path = format!(
        "{}/examples/rotors/uniform_shaft_pinned.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).expect("example file")
        + "\n[damping]\ndamping_ratio = 0.02\nfrequencies_rad_s = [700.0, 3000.0]\n";
    let model = Model::from_str(&text, "damped").expect("valid");
    let (a0, a1) = model.rayleigh();
    assert!((a0 - 2.0 * 0.02 * 700.0 * 3000.0 / 3700.0).abs() < 1e-12);
    let asm = Assembly::new(&model).expect("assembles");
    let modes = linear::modes(&asm, 0.0, 6).expect("modes");
    for m in &modes {
        let wn = m.undamped_rad_s;
        let zeta = a0 / (2.0 * wn) + a1 * wn / 2.0;
        assert!(
            (m.damping_ratio - zeta).abs() < 1e-6,
            "{} vs {zeta}",
            m.damping_ratio
        );
        assert!((m.frequency_rad_s - wn * (1.0 - zeta * zeta).sqrt()).abs() < 1e-6 * wn);
    }
    // At the two matching frequencies ζ is 0.02 (the first mode is near 740 rad/s).
    assert!((modes[0].damping_ratio - 0.02).abs() < 1e-3);
}
