//! SIP settings: the plain product never amplifies an undamped fast mode, extrapolation
//! can (why it is off by default), and invalid settings are rejected with their name.

use tmrotor::stability::{Sip, StabilityError, StabilityMethod};
use tmrotor::system::{
    DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, PeriodicOrbit, System,
};

/// `ẍ + ω_m² x = 0`, `ω_m = 20 rad/s`: both exact multipliers on the unit circle.
struct Undamped {
    dofs: NonlinearDofs,
}

impl System for Undamped {
    fn n_mech(&self) -> usize {
        1
    }
    fn linear(&self, _omega: f64) -> LinearPart {
        let s = |v: f64| DenseMatrix {
            n: 1,
            data: vec![v],
        };
        LinearPart {
            mass: s(1.0),
            damping: s(0.0),
            stiffness: s(400.0),
            thermal_capacity: DenseMatrix::zeros(0),
            thermal_conductance: DenseMatrix::zeros(0),
        }
    }
    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }
    fn eval_nonlinear(
        &self,
        _omega: f64,
        _t: f64,
        _x: &[f64],
        _v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        out.clear();
    }
    fn forcing(&self, _omega: f64, _t: f64, out: &mut [f64]) {
        out[0] = 0.0;
    }
}

struct Rest;

impl PeriodicOrbit for Rest {
    fn omega(&self) -> f64 {
        1.0
    }
    fn period(&self) -> f64 {
        2.0 * std::f64::consts::PI
    }
    fn state_at(&self, _t: f64, x: &mut [f64], v: &mut [f64], _temp: &mut [f64]) {
        x[0] = 0.0;
        v[0] = 0.0;
    }
}

fn system() -> Undamped {
    Undamped {
        dofs: NonlinearDofs::default(),
    }
}

#[test]
fn plain_product_does_not_amplify_an_undamped_fast_mode() {
    // ω_m·P = 126 rad. The plain order-4 product is dissipative on the imaginary axis:
    // |μ| ≤ 1 at any interval count.
    for intervals in [128, 256, 1024] {
        let r = Sip::fixed(intervals, 4)
            .multipliers(&system(), &Rest)
            .expect("SIP");
        let rho = r.spectral_radius();
        println!("plain, {intervals} intervals: |μ|max = {rho:.9}");
        assert!(rho <= 1.0 && r.stable);
    }
}

#[test]
fn extrapolation_can_push_an_undamped_fast_mode_outside() {
    // With 1024 intervals (Δω_m = 0.12), fine and coarse products differ in phase by
    // ~1e-2 rad, and (4a − b)/3 leaves the circle by more than the 1e-6 tolerance.
    let sip = Sip {
        intervals: 1024,
        max_step_norm: f64::INFINITY,
        extrapolate: true,
        ..Sip::default()
    };
    let r = sip.multipliers(&system(), &Rest).expect("SIP");
    println!("extrapolated: |μ|max = {:.9}", r.spectral_radius());
    assert!(!r.stable, "spurious instability expected");
}

#[test]
fn invalid_settings_are_named() {
    for (sip, field) in [
        (Sip::fixed(0, 4), "sip.intervals"),
        (Sip::fixed(10, 0), "sip.series_order"),
        (
            Sip {
                gauss_points: 7,
                ..Sip::default()
            },
            "sip.gauss_points",
        ),
    ] {
        match sip.multipliers(&system(), &Rest) {
            Err(StabilityError::Setting { field: f, .. }) => assert_eq!(f, field),
            other => panic!("expected a setting error for {field}, got {other:?}"),
        }
    }
}
