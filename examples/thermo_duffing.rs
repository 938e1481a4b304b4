//! The self-heated Duffing oscillator (`tmrotor::systems::thermo_duffing`) along its
//! branch: per point the coupled exponents nearest zero from Hill's eigenproblem, the
//! fast multipliers with the temperature frozen, and the multipliers of the full coupled
//! linearisation by the variational equations (the independent reference), as CSV.
//!
//! `cargo run --release --example thermo_duffing -- [tau_periods] [order]`

use num_complex::Complex64;
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{
    FrozenOrbit, FrozenTemperature, HillOptions, HillPencil, StabilityMethod, Variational,
};
use tmrotor::system::{PeriodicOrbit, System};
use tmrotor::systems::thermo_duffing::ThermoDuffing;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let tau_periods: f64 = args.get(1).map_or(Ok(100.0), |s| s.parse())?;
    let order: u32 = args.get(2).map_or(Ok(7), |s| s.parse())?;
    let mut system = ThermoDuffing::new(tau_periods * std::f64::consts::TAU);
    if let Some(a) = args.get(3) {
        system.heating = a.parse()?;
    }
    let basis = Basis::integer(order)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let mut opts = ContinuationOptions::new(0.5, 1.8);
    opts.ds_max = 0.05;
    opts.scale_mech = Some(1.0);
    opts.scale_therm = Some(1.0);
    opts.scale_omega = Some(1.0);
    let mut cont = Continuation::new(hb, opts, None)?;
    let branch = cont.run(|_| {})?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let var = Variational::default();
    println!("omega,amp,theta,hill_near_zero,frozen_near_one,variational_near_one");
    for p in &branch.points {
        let s = &p.solution;
        let period = s.period();
        let pencil = HillPencil::new(&hb, s, None)?;
        let nz = pencil.near_zero(3, &HillOptions::default())?;
        let frozen = FrozenTemperature::new(&system, s);
        let fm = var.multipliers(&frozen, &FrozenOrbit::new(s, system.n_therm()))?;
        let full = var.multipliers(&system, s)?;
        let fmt = |v: &[Complex64]| {
            v.iter()
                .map(|z| format!("{:.6e}{:+.6e}i", z.re, z.im))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let mut near: Vec<Complex64> = full.multipliers.iter().map(|m| m.ln() / period).collect();
        near.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
        near.truncate(3);
        let mut fr: Vec<Complex64> = fm.multipliers.iter().map(|m| m.ln() / period).collect();
        fr.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
        println!(
            "{:.6},{:.4},{:.4},{},{},{}",
            s.omega,
            s.max_abs(0),
            s.therm_coeffs(0)[0],
            fmt(&nz.exponents),
            fmt(&fr),
            fmt(&near)
        );
    }
    Ok(())
}
