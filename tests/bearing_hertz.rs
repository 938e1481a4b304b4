//! Checks of the Hertzian bearing force (Eqs. 3–5) and the thermal clearance (Eqs. 1–2).

use std::f64::consts::PI;
use tmrotor::bearing::{ContactLaw, ExpansionGeometry, HertzBearing, cage_speed_rad_s};

fn ball_1() -> HertzBearing {
    // Table A.1, 1# ball bearing.
    HertzBearing {
        law: ContactLaw::Ball,
        n_elements: 22,
        stiffness: 1.45e9,
        clearance_m: 1e-6,
        inner_raceway_m: 150.95e-3,
        outer_raceway_m: 189.05e-3,
    }
}

fn roller_3() -> HertzBearing {
    // Table A.2, 3# roller bearing.
    HertzBearing {
        law: ContactLaw::Roller,
        n_elements: 28,
        stiffness: 1.89e8,
        clearance_m: 5e-6,
        inner_raceway_m: 128e-3,
        outer_raceway_m: 152e-3,
    }
}

#[test]
fn single_loaded_ball_equals_k_delta_pow_n_by_hand() {
    // One element only, at angle 0: δ = dx − δ0 − δv = 20 µm − 1 µm − 0 = 19 µm.
    let b = HertzBearing {
        n_elements: 1,
        ..ball_1()
    };
    let f = b.force(20e-6, 0.0, 0.0, 0.0);
    // By hand: 1.45e9 · (19e-6)^1.5 = 1.45e9 · 8.2819e-8 = 120.09 N.
    let by_hand = 1.45e9 * 19e-6 * (19e-6_f64).sqrt();
    assert!((by_hand - 120.087).abs() < 1e-2, "hand value {by_hand}");
    assert!((f.fx - by_hand).abs() < 1e-9 * by_hand);
    assert!(f.fy.abs() < 1e-12);
    assert!((f.fb - by_hand).abs() < 1e-9 * by_hand);
    assert_eq!(f.n_loaded, 1);
    // Same for a roller: 1.89e8 · (15e-6)^(10/9) with δ0 = 5 µm, dx = 20 µm.
    let r = HertzBearing {
        n_elements: 1,
        ..roller_3()
    };
    let f = r.force(20e-6, 0.0, 0.0, 0.0);
    let by_hand = 1.89e8 * (15e-6_f64).powf(10.0 / 9.0);
    assert!((f.fb - by_hand).abs() < 1e-9 * by_hand);
    // Displacement opposite to the element: no contact, no force.
    let f = r.force(-20e-6, 0.0, 0.0, 0.0);
    assert_eq!(f.n_loaded, 0);
    assert_eq!(f.fb, 0.0);
}

#[test]
fn symmetric_load_gives_force_along_displacement() {
    // Displacement along x with an element at θ = 0: the pattern is symmetric about the
    // x axis, so Fy = 0 and Fx > 0; rotated displacement gives the rotated force.
    let b = ball_1();
    let f = b.force(15e-6, 0.0, 0.0, 0.0);
    assert!(f.fy.abs() < 1e-9 * f.fx, "fy {} fx {}", f.fy, f.fx);
    assert!(f.fx > 0.0);
    // Loaded elements: cos θ_k > 1/15 → |θ| < acos(1/15) = 86.2° → k = 0, ±1..±5 (11).
    assert_eq!(f.n_loaded, 11);
    // Rotate the displacement and the cage by the same angle: same magnitude, rotated.
    let phi: f64 = 0.37;
    let g = b.force(15e-6 * phi.cos(), 15e-6 * phi.sin(), 0.0, phi);
    assert!((g.fx - f.fx * phi.cos()).abs() < 1e-9 * f.fx);
    assert!((g.fy - f.fx * phi.sin()).abs() < 1e-9 * f.fx);
    // Fully symmetric (zero displacement, negative clearance = preload): zero net force,
    // every element loaded, Fb = N k |δe|^n.
    let pre = HertzBearing {
        clearance_m: -2e-6,
        ..b.clone()
    };
    let f = pre.force(0.0, 0.0, 0.0, 0.123);
    assert!(f.fx.abs() < 1e-9 * f.fb && f.fy.abs() < 1e-9 * f.fb);
    assert_eq!(f.n_loaded, 22);
    let expect = 22.0 * 1.45e9 * (2e-6_f64).powf(1.5);
    assert!((f.fb - expect).abs() < 1e-12 * expect);
}

#[test]
fn force_derivatives_match_finite_differences() {
    for b in [ball_1(), roller_3()] {
        for &(dx, dy, dv, ang) in &[
            (12e-6, -7e-6, 0.4e-6, 0.1),
            (-9e-6, 15e-6, -1.3e-6, 1.7),
            (30e-6, 4e-6, 2e-6, 2.9),
        ] {
            let f0 = b.force(dx, dy, dv, ang);
            let h = 1e-10;
            let inputs = [dx, dy, dv];
            for c in 0..3 {
                let mut p = inputs;
                let mut m = inputs;
                p[c] += h;
                m[c] -= h;
                let fp = b.force(p[0], p[1], p[2], ang);
                let fm = b.force(m[0], m[1], m[2], ang);
                let fd = [
                    (fp.fx - fm.fx) / (2.0 * h),
                    (fp.fy - fm.fy) / (2.0 * h),
                    (fp.fb - fm.fb) / (2.0 * h),
                ];
                let scale = f0.jac.iter().flatten().fold(0.0_f64, |a, v| a.max(v.abs()));
                for (r, fd_r) in fd.iter().enumerate() {
                    assert!(
                        (fd_r - f0.jac[r][c]).abs() < 1e-5 * scale,
                        "{:?} r{r} c{c}: fd {} exact {}",
                        b.law,
                        fd_r,
                        f0.jac[r][c]
                    );
                }
            }
        }
    }
}

#[test]
fn cage_speed_of_fixed_outer_ring_and_inter_shaft_bearing() {
    // Outer ring fixed: ω_c = d_i ω/(d_i + d_o) (classical pitch-circle result,
    // ω_c = ω (1 − d/D_m)/2 with d_i = D_m − d, d_o = D_m + d).
    let w = cage_speed_rad_s(150.95e-3, 189.05e-3, 500.0, 0.0);
    let classical = 500.0 * (1.0 - 19.05 / 170.0) / 2.0;
    assert!((w - classical).abs() < 1e-9);
    // Both rings at the same speed: the cage turns with them.
    assert!((cage_speed_rad_s(0.128, 0.152, 600.0, 600.0) - 600.0).abs() < 1e-9);
}

#[test]
fn clearance_variation_by_hand_and_derivatives() {
    // 1# ball bearing, Table A.1/A.5.
    let g = ExpansionGeometry {
        element_diameter_m: 19.05e-3,
        inner_raceway_m: 150.95e-3,
        outer_raceway_m: 189.05e-3,
        seat_diameter_m: 2.0 * 113.891e-3,
        expansion_element_per_k: 12.03e-6,
        expansion_inner_per_k: 12.03e-6,
        expansion_outer_per_k: 12.03e-6,
        poisson: 0.3,
    };
    let (tb, ti, to, th, ta) = (45.0, 40.0, 35.0, 30.0, 25.0);
    let c = g.evaluate(tb, ti, to, th, ta);
    // By hand: u_b = 12.03e-6·19.05e-3·20 = 4.58343e-6 m
    assert!((c.u_b - 4.583_43e-6).abs() < 1e-11);
    // u_i = 12.03e-6·150.95e-3·15 = 27.2389e-6 m
    assert!((c.u_i - 27.238_93e-6).abs() < 1e-10);
    // u_o = 12.03e-6·1.3·0.18905/(3·0.416832)·[10·(2·0.18905+0.227782) + 5·(2·0.227782+0.18905)]
    //     = 2.364357e-6·[6.05882 + 3.22307] = 21.9460e-6 m
    let f = 12.03e-6 * 1.3 * 0.18905 / (3.0 * (0.18905 + 0.227782));
    let uo = f * (10.0 * (2.0 * 0.18905 + 0.227782) + 5.0 * (2.0 * 0.227782 + 0.18905));
    assert!((c.u_o - uo).abs() < 1e-15);
    assert!((uo - 21.946e-6).abs() < 2e-9);
    assert!((c.delta_v + (c.u_b + 0.5 * (c.u_i - c.u_o))).abs() < 1e-18);
    // Derivatives by central differences (exact for a linear map).
    let t = [tb, ti, to, th];
    for k in 0..4 {
        let mut p = t;
        let mut m = t;
        p[k] += 0.5;
        m[k] -= 0.5;
        let fd = g.evaluate(p[0], p[1], p[2], p[3], ta).delta_v
            - g.evaluate(m[0], m[1], m[2], m[3], ta).delta_v;
        assert!((fd - c.d_delta_v_d_temp[k]).abs() < 1e-15, "k {k}");
    }
    // Uniform heating: rolling element and rings expand; no heating, no change.
    assert_eq!(g.evaluate(25.0, 25.0, 25.0, 25.0, 25.0).delta_v, 0.0);
    let _ = PI;
}
