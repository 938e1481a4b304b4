//! The coupled dual rotor's pointwise Jacobian (bearing forces with thermal clearance,
//! thermal forces chained through the radial loads) against central finite differences.

use tmrotor::coupled::{CoupledRotor, StudyOverrides};
use tmrotor::system::{NonlinearEval, System};

fn state(sys: &CoupledRotor) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let nl = sys.nonlinear_dofs();
    // Displacements of a few tens of µm (bearings loaded, several elements in contact),
    // temperatures spread over 30–60 °C.
    let x: Vec<f64> = (0..nl.mech.len())
        .map(|i| -3.0e-5 + 1.3e-5 * ((i as f64) * 1.7).sin())
        .collect();
    let v = vec![0.0; nl.mech.len()];
    let t: Vec<f64> = (0..nl.therm.len())
        .map(|i| 45.0 + 15.0 * ((i as f64) * 0.9).cos())
        .collect();
    (x, v, t)
}

#[test]
fn coupled_jacobian_matches_finite_differences() {
    let sys = CoupledRotor::dual_rotor(&StudyOverrides::default()).expect("built-in model");
    let nl = sys.nonlinear_dofs().clone();
    let (p, q) = (nl.mech.len(), nl.therm.len());
    assert_eq!(p, 10, "x, y of the five bearing nodes");
    assert!(q >= 16, "at least b, i, o, L of four bearings");
    let (x, v, t) = state(&sys);
    let (omega, time) = (500.0, 0.0123);
    let mut e0 = NonlinearEval::new(p, q);
    sys.eval_nonlinear(omega, time, &x, &v, &t, &mut e0);
    assert!(
        e0.f.iter().any(|f| f.abs() > 100.0),
        "bearings carry load: {:?}",
        e0.f
    );

    let mut ep = NonlinearEval::new(p, q);
    let mut em = NonlinearEval::new(p, q);
    let mut worst: f64 = 0.0;
    let mut check = |analytic: f64, fd: f64, scale: f64, what: &str| {
        let err = (analytic - fd).abs() / scale;
        worst = worst.max(err);
        assert!(err < 1e-5, "{what}: analytic {analytic:e} vs fd {fd:e}");
    };
    // Columns: mechanical displacements.
    let fscale = e0.f.iter().map(|v| v.abs()).fold(1.0, f64::max);
    let gscale = e0.g.iter().map(|v| v.abs()).fold(1.0, f64::max);
    for c in 0..p {
        let h = 1e-10;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[c] += h;
        xm[c] -= h;
        sys.eval_nonlinear(omega, time, &xp, &v, &t, &mut ep);
        sys.eval_nonlinear(omega, time, &xm, &v, &t, &mut em);
        for r in 0..p {
            let fd = (ep.f[r] - em.f[r]) / (2.0 * h);
            check(
                e0.df_dx[r * p + c],
                fd,
                fscale / 1e-5,
                &format!("df{r}/dx{c}"),
            );
        }
        for r in 0..q {
            let fd = (ep.g[r] - em.g[r]) / (2.0 * h);
            check(
                e0.dg_dx[r * p + c],
                fd,
                gscale / 1e-5,
                &format!("dg{r}/dx{c}"),
            );
        }
    }
    // Columns: temperatures.
    for c in 0..q {
        let h = 1e-4;
        let (mut tp, mut tm) = (t.clone(), t.clone());
        tp[c] += h;
        tm[c] -= h;
        sys.eval_nonlinear(omega, time, &x, &v, &tp, &mut ep);
        sys.eval_nonlinear(omega, time, &x, &v, &tm, &mut em);
        for r in 0..p {
            let fd = (ep.f[r] - em.f[r]) / (2.0 * h);
            check(
                e0.df_dt[r * q + c],
                fd,
                fscale / 10.0,
                &format!("df{r}/dT{c}"),
            );
        }
        for r in 0..q {
            let fd = (ep.g[r] - em.g[r]) / (2.0 * h);
            check(
                e0.dg_dt[r * q + c],
                fd,
                gscale / 10.0,
                &format!("dg{r}/dT{c}"),
            );
        }
    }
    eprintln!("worst scaled Jacobian error {worst:e}");
}

#[test]
fn values_alone_equal_the_full_evaluation() {
    // The residual's evaluation without derivatives must give the same `f` and `g` to the
    // bit, from buffers that still hold another state's derivatives; also with the
    // clearance frozen and without the thermal network.
    let full = CoupledRotor::dual_rotor(&StudyOverrides::default()).expect("built-in model");
    let nl = full.nonlinear_dofs().clone();
    let (p, q) = (nl.mech.len(), nl.therm.len());
    let (x, v, t) = state(&full);
    for (omega, time) in [(300.0, 0.0), (500.0, 0.0123), (700.0, 0.031)] {
        let mut e_full = NonlinearEval::new(p, q);
        full.eval_nonlinear(omega, time, &x, &v, &t, &mut e_full);
        // a buffer last used at another state, with derivatives
        let mut e_vals = NonlinearEval::new(p, q);
        let x2: Vec<f64> = x.iter().map(|xi| 0.5 * xi).collect();
        full.eval_nonlinear(omega, 0.5 * time, &x2, &v, &t, &mut e_vals);
        full.eval_nonlinear_values(omega, time, &x, &v, &t, &mut e_vals);
        assert_eq!(e_vals.f, e_full.f, "f at ω = {omega}");
        assert_eq!(e_vals.g, e_full.g, "g at ω = {omega}");
        assert!(e_full.g.iter().any(|g| *g != 0.0));
    }
}
