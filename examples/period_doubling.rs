//! First period doubling of the forced double-well Duffing oscillator
//! `ẍ + 0.3ẋ − x + x³ = γ cos(1.2 t)` (`tmrotor::systems::period_doubling`): the period-1
//! orbit in the right-hand well continued in the forcing amplitude γ from 0.20 to 0.28, as
//! CSV on stdout.
//!
//! Columns as in `tmrotor::continuation::csv`, except that the first column is `gamma`
//! (the continuation parameter; the forcing frequency stays 1.2 rad/s, so there is no
//! `omega` column): amplitude = max |x(t)| over one period (x measured from the saddle
//! `x = 0`, so the right-hand well's orbit has amplitudes above 1). Stability from the
//! paper's SIP product (Eqs. 30–33), Richardson-extrapolated; the period doubling (a real
//! multiplier through −1) is located by bisection in arclength and labelled
//! `period-doubling` (γ* = 0.26558, see `tests/stability_period_doubling.rs`, which checks
//! this example's located point against shooting).
//!
//! The engine continues in the base frequency of the orbit; the continuation in γ uses the
//! rescaled time of `GammaParametrized` (the system's docs explain it), which leaves
//! amplitudes and multipliers unchanged.
//!
//! `cargo run --release --example period_doubling > period_doubling.csv`

use tmrotor::continuation::{
    Branch, Continuation, ContinuationOptions, csv::branch_csv_with_parameter,
};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::integrate::{SteadyStateOptions, steady_state_with};
use tmrotor::stability::Sip;
use tmrotor::systems::period_doubling::{
    DoubleWellDuffing, GAMMA_BRACKET, GammaParametrized, OMEGA,
};

/// Harmonics of the forcing frequency in the basis (the orbit is analytic; see the test
/// for the effect on the located point).
pub const HARMONICS: u32 = 16;

/// The continued branch over the literature bracket `GAMMA_BRACKET` (0.20–0.28).
pub fn branch() -> anyhow::Result<Branch> {
    let system = GammaParametrized::reference();
    let basis = Basis::integer(HARMONICS)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let (g0, g1) = GAMMA_BRACKET;
    let mut opts = ContinuationOptions::new(g0, g1);
    // at most 2 % of the range per step: a curve of about 50 points
    opts.ds_max = 0.02;
    // Start: the attractor of time integration from the right-hand well's bottom (x = 1) at
    // γ = 0.20, sampled at the AFT instants and projected on the basis. (The linear
    // response about x = 1 is too far from this orbit for Newton: the softening well bends
    // the resonance past the forcing frequency.)
    let aft = hb.aft();
    let settled = steady_state_with(
        &DoubleWellDuffing::reference(g0),
        OMEGA,
        &[1.0, 0.0],
        2.0 * std::f64::consts::PI / OMEGA,
        300,
        &SteadyStateOptions {
            samples_per_period: aft.n_samples(),
            ..SteadyStateOptions::default()
        },
    )?;
    let x: Vec<f64> = settled.samples.iter().map(|y| y[0]).collect();
    let mut guess = vec![0.0; basis.n_coeffs()];
    aft.project(&x, &mut guess, &mut Vec::new());
    opts.initial_guess = Some(guess);
    // Floquet multipliers by the SIP product, Richardson-extrapolated (safe for this small,
    // low-frequency system; see `tmrotor::stability::sip`)
    let sip = Sip {
        extrapolate: true,
        ..Sip::default()
    };
    let mut cont = Continuation::new(hb, opts, Some(&sip))?;
    Ok(cont.run(|_| {})?)
}

fn main() -> anyhow::Result<()> {
    let branch = branch()?;
    eprintln!(
        "{} points, {} rejected steps, finished: {:?} (the engine's ω is γ here)",
        branch.points.len(),
        branch.rejected_steps,
        branch.finish
    );
    for b in &branch.bifurcations {
        eprintln!(
            "{} at γ = {:.6}",
            b.bifurcation.map_or("?", |k| k.label()),
            b.solution.omega
        );
    }
    eprintln!("{}", tmrotor::continuation::csv::COLUMNS_NOTE);
    print!("{}", branch_csv_with_parameter(&branch, 0, "gamma")?);
    Ok(())
}
