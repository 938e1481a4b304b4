//! Jeffcott rotor on a Hertzian ball bearing with clearance: harmonic-balance orbits
//! against RK4 time integration run to steady state.
//!
//! The ball passage (16/5 ω) and its harmonics excite the journal near its own resonance
//! on the bearing contact stiffness (~9e3 rad/s), so the journal motion carries harmonics
//! up to ~30ω: with multiples of ω/5 up to 4ω (20 harmonics) the maxima differ from time
//! integration by ~0.5 %, up to 20ω by ~1e-3, up to 32ω (160 harmonics) by ~3e-5. The test
//! uses 160 harmonics, started from the solution with 20, below (300 rad/s) and above
//! (550 rad/s) the primary resonance (~488 rad/s).

mod engine_support;

use engine_support::steady_max_abs;
use tmrotor::hb::newton::{NewtonOptions, solve_fixed};
use tmrotor::hb::{HarmonicBalance, HbSolution};
use tmrotor::system::PeriodicOrbit;
use tmrotor::systems::jeffcott::Jeffcott;

#[test]
fn harmonic_balance_orbits_match_time_integration() {
    let sys = Jeffcott::default();
    let basis = sys.basis(160).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    for omega in [300.0, 550.0] {
        // coarse solve (up to 4ω), embedded as the start of the fine one
        let coarse = sys.basis(20).expect("basis");
        let hb_c = HarmonicBalance::new(&sys, &coarse, None).expect("hb");
        let opts = NewtonOptions::default();
        let (ac, _) =
            solve_fixed(&hb_c, omega, &sys.start_guess(&coarse, omega), &opts).expect("coarse");
        let (ncc, nf) = (coarse.n_coeffs(), basis.n_coeffs());
        let (hc, hf) = (coarse.n_harmonics(), basis.n_harmonics());
        let mut guess = vec![0.0; 4 * nf];
        for d in 0..4 {
            guess[d * nf] = ac[d * ncc];
            for h in 0..hc {
                guess[d * nf + 1 + h] = ac[d * ncc + 1 + h];
                guess[d * nf + 1 + hf + h] = ac[d * ncc + 1 + hc + h];
            }
        }
        let (a, stats) = solve_fixed(&hb, omega, &guess, &opts).expect("newton");
        let sol = HbSolution::from_unknowns(omega, &basis, 4, &a, &stats);
        let period = sol.period();
        let (mut x, mut v) = ([0.0; 4], [0.0; 4]);
        sol.state_at(0.0, &mut x, &mut v, &mut []);
        let y0: Vec<f64> = x.iter().chain(&v).map(|s| 1.01 * s).collect();
        for dof in [0, 2] {
            let (ti, _) = steady_max_abs(&sys, omega, period, &y0, 30, 8192, dof);
            let hbv = sol.max_abs(dof);
            let rel = (hbv - ti).abs() / ti;
            eprintln!("ω = {omega}, DoF {dof}: HB {hbv:e}, time integration {ti:e}, rel {rel:e}");
            assert!(rel < 2e-4, "ω = {omega}, DoF {dof}: HB {hbv:e} vs {ti:e}");
        }
    }
}
