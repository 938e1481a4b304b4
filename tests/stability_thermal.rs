//! Thermo-mechanical coupling in the linearised equations: the state matrix against
//! finite differences of the right-hand side (all blocks, including the thermal block and
//! both coupling blocks), SIP vs variational vs shooting multipliers with a slow thermal
//! DoF, and the split of the near-+1 thermal multiplier.

use num_complex::Complex64;
use tmrotor::integrate::{ShootingOptions, StateSpace, shoot_periodic, steady_state};
use tmrotor::stability::{
    Sip, StabilityMethod, Variational, split_thermal, thermal_multiplier_estimates,
};
use tmrotor::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};

/// Two masses (DoF 0 nonlinear, DoF 1 linear) and two thermal nodes (node 0 coupled):
///
/// ```text
///   x0'' + c x0' + k x0 − k x1 + k3 x0³ + a T0 x0 = F cos Ωt
///   x1'' + c x1' + 2k x1 − k x0 = 0
///   Ct T0' + Kt (T0 − T1) + Kt T0 − h x0'² − e T0² = 0  (heat from friction, T-dependent)
///   Ct T1' + Kt (T1 − T0) + Kt T1 = Kt · 1
/// ```
/// Thermal time constant `Ct/Kt` = 1e3 s against a period of ~5 s: thermal multipliers
/// `≈ exp(−P·Kt/Ct·{1, 3})`, within 1.6e-2 of +1.
struct ThermoOscillator {
    dofs: NonlinearDofs,
}

const C: f64 = 0.05;
const K: f64 = 1.0;
const K3: f64 = 0.1;
const A: f64 = 0.05;
const CT: f64 = 1000.0;
const KT: f64 = 1.0;
const H: f64 = 0.5;
const E: f64 = 0.01;
const F: f64 = 0.2;

impl System for ThermoOscillator {
    fn n_mech(&self) -> usize {
        2
    }
    fn n_therm(&self) -> usize {
        2
    }
    fn linear(&self, _omega: f64) -> LinearPart {
        let d = |n: usize, v: &[f64]| DenseMatrix {
            n,
            data: v.to_vec(),
        };
        LinearPart {
            mass: d(2, &[1.0, 0.0, 0.0, 1.0]),
            damping: d(2, &[C, 0.0, 0.0, C]),
            stiffness: d(2, &[K, -K, -K, 2.0 * K]),
            thermal_capacity: d(2, &[CT, 0.0, 0.0, CT]),
            thermal_conductance: d(2, &[2.0 * KT, -KT, -KT, 2.0 * KT]),
        }
    }
    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }
    fn eval_nonlinear(
        &self,
        _omega: f64,
        _t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        out.f[0] = K3 * x[0].powi(3) + A * temp[0] * x[0];
        out.df_dx[0] = 3.0 * K3 * x[0] * x[0] + A * temp[0];
        out.df_dv[0] = 0.0;
        out.df_dt[0] = A * x[0];
        out.g[0] = -H * v[0] * v[0] - E * temp[0] * temp[0];
        out.dg_dx[0] = 0.0;
        out.dg_dv[0] = -2.0 * H * v[0];
        out.dg_dt[0] = -2.0 * E * temp[0];
    }
    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out[0] = F * (omega * t).cos();
        out[1] = 0.0;
    }
    fn thermal_load(&self, _omega: f64, out: &mut [f64]) {
        out[0] = 0.0;
        out[1] = KT;
    }
}

fn system() -> ThermoOscillator {
    ThermoOscillator {
        dofs: NonlinearDofs {
            mech: vec![0],
            therm: vec![0],
        },
    }
}

#[test]
fn state_matrix_matches_finite_differences_of_the_right_hand_side() {
    let sys = system();
    let space = StateSpace::new(&sys, 1.1).expect("state space");
    let mut ws = space.workspace();
    let d = space.dim();
    let y = [0.3, -0.2, 0.7, 0.1, 0.8, 0.4];
    let t = 0.37;
    space.eval_nonlinear_at(t, &y[..2], &y[2..4], &y[4..], &mut ws);
    let derivs = ws.eval.clone();
    let b = space.linearization_dense(&derivs, &mut ws);
    let (mut fp, mut fm) = (vec![0.0; d], vec![0.0; d]);
    let h = 1e-6;
    for j in 0..d {
        let (mut yp, mut ym) = (y, y);
        yp[j] += h;
        ym[j] -= h;
        space.rhs(t, &yp, &mut fp, &mut ws);
        space.rhs(t, &ym, &mut fm, &mut ws);
        for i in 0..d {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            assert!(
                (fd - b[(i, j)]).abs() < 1e-8,
                "B[{i},{j}] = {} vs finite difference {fd}",
                b[(i, j)]
            );
        }
    }
}

fn max_pair_distance(a: &[Complex64], b: &[Complex64]) -> f64 {
    let mut used = vec![false; b.len()];
    let mut worst: f64 = 0.0;
    for x in a {
        let (j, d) = b
            .iter()
            .enumerate()
            .filter(|(j, _)| !used[*j])
            .map(|(j, y)| (j, (x - y).norm()))
            .min_by(|p, q| p.1.total_cmp(&q.1))
            .expect("same length");
        used[j] = true;
        worst = worst.max(d);
    }
    worst
}

#[test]
fn coupled_multipliers_agree_and_thermal_ones_split_off() {
    let sys = system();
    let omega = 1.1;
    let period = 2.0 * std::f64::consts::PI / omega;
    // Start near the thermal equilibrium of the linear network (T ≈ 1/3, 2/3 without
    // heat) and shoot: settling would take thousands of thermal time constants' worth of
    // periods.
    let shot = shoot_periodic(
        &sys,
        omega,
        &[0.0, 0.0, 0.0, 0.0, 0.4, 0.7],
        period,
        &ShootingOptions::default(),
    )
    .expect("shooting converges");
    let shoot = shot.phi.eigenvalues().expect("eig");
    let orbit = steady_state(&sys, omega, &shot.y, period, 0)
        .expect("samples")
        .orbit();
    let sip = accurate_sip().multipliers(&sys, &orbit).expect("SIP");
    let var = Variational::default()
        .multipliers(&sys, &orbit)
        .expect("variational");
    let (d_sv, d_vs) = (
        max_pair_distance(&sip.multipliers, &var.multipliers),
        max_pair_distance(&var.multipliers, &shoot),
    );
    println!(
        "orbit start {:?}\nSIP {:?}\n|SIP−var| = {d_sv:.2e}, |var−shoot| = {d_vs:.2e}",
        shot.y, sip.multipliers
    );
    assert!(d_sv < 1e-6 && d_vs < 1e-8);
    assert!(sip.stable && var.stable);

    let predicted = thermal_multiplier_estimates(&sys, &orbit).expect("estimates");
    let split = split_thermal(&var.multipliers, &predicted);
    println!(
        "predicted thermal {predicted:?}\nsplit thermal {:?} mechanical {:?} mismatch {:.2e}",
        split.thermal, split.mechanical, split.max_mismatch
    );
    assert_eq!(split.thermal.len(), 2);
    assert_eq!(split.mechanical.len(), 4);
    // Thermal multipliers: real, just below +1 (1 − P/τ with τ = 1000 s and 333 s).
    for m in &split.thermal {
        assert!(
            m.im.abs() < 1e-12 && m.re < 1.0 && m.re > 0.97,
            "thermal {m}"
        );
    }
    // Mechanical ones: damped oscillations, far from +1.
    for m in &split.mechanical {
        assert!((m - 1.0).norm() > 0.1, "mechanical {m}");
    }
    assert!(split.mechanical_stable());
    // The averaged thermal block predicts them to within the (weak) coupling.
    assert!(split.max_mismatch < 1e-3);
    // The plain default SIP resolves the slow thermal multipliers far more finely than
    // the mechanical ones (Δ·ρ_th ≈ 1e-5): their distance to +1 is exact to many digits.
    let plain = Sip::default().multipliers(&sys, &orbit).expect("SIP");
    let split_sip = split_thermal(&plain.multipliers, &predicted);
    let worst = split_sip
        .thermal
        .iter()
        .zip(&split.thermal)
        .map(|(a, b)| (a - b).norm() / (1.0 - b.re))
        .fold(0.0, f64::max);
    println!("thermal multipliers, SIP vs variational, relative to 1 − μ: {worst:.2e}");
    assert!(worst < 1e-6);
}

/// SIP for the small reference oscillators: 512 intervals with Richardson extrapolation
/// (safe here: one or two modes with `ω·P` of a few radians, so the series truncation is
/// negligible; see `tmrotor::stability::sip`). Error O(Δ⁴) instead of O(Δ²).
fn accurate_sip() -> Sip {
    Sip {
        intervals: 512,
        extrapolate: true,
        ..Sip::default()
    }
}
