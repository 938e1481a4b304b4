//! Frequency response of the Jeffcott rotor on a Hertzian ball bearing with radial
//! clearance (`tmrotor::systems::jeffcott`), ω from 300 to 700 rad/s, as CSV on stdout (see
//! `tmrotor::continuation::csv` for the columns); amplitude = max |x_d| of the disk's
//! vertical displacement in m (DoF 1, gravity offset included). Stability from the
//! paper's SIP product (Eqs. 30–33); bifurcations located and labelled.
//!
//! Basis: multiples of ω/5 up to 32ω (160 harmonics; the ball passage is at 16/5 ω). Above
//! ~555 rad/s the journal loses contact with all balls for part of each period, and the
//! impacts excite its mode on the contact stiffness (~8–9·10³ rad/s): the response then
//! carries harmonics up to ~30ω, and the branch has narrow super-harmonic resonances with
//! ~35 fold pairs, period doublings and Neimark–Sacker points between 560 and 640 rad/s
//! (an unstable window also at 394–398 rad/s). Where the branch is unstable, time
//! integration settles on period-2, -4, -5 or non-periodic responses, or on a periodic orbit
//! of an isolated branch (646–652 rad/s); where it is stable, it settles on this branch
//! (checked at 300, 550, 580, 660 and 700 rad/s in `tests/engine_jeffcott.rs`). See the
//! module docs of `tmrotor::systems::jeffcott` for the measurements.
//!
//! The continuation scales each DoF by its own size (`scale_per_dof`): the folds live in the
//! journal's high harmonics, ~1e-7 m, next to the disk's static sag of ~5e-5 m, and with
//! one scale for all DoFs the steps grow across them and the corrector lands on
//! neighbouring segments of the branch.
//!
//! The environment variable `JC_H` sets the number of harmonics. 20 (up to 4ω) is fast and
//! agrees with time integration to ~0.5 % up to ~550 rad/s, but misses the journal's
//! resonance: above, its branch is smooth and wrong (journal maxima ~10 % low, stability
//! wrong). With 160 the run takes about 4 CPU-minutes (~730 points).
//!
//! `cargo run --release --example jeffcott > jeffcott.csv`

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::HarmonicBalance;
use tmrotor::stability::Sip;
use tmrotor::systems::jeffcott::Jeffcott;

/// Harmonics (multiples of ω/5) unless `JC_H` says otherwise.
pub const HARMONICS: u32 = 160;

/// The example's continuation settings from `omega_start` to `omega_end` (also used by
/// `tests/engine_jeffcott.rs`).
pub fn options(omega_start: f64, omega_end: f64) -> ContinuationOptions {
    let mut opts = ContinuationOptions::new(omega_start, omega_end);
    // each DoF in its own units (see the header); steps on smooth parts may then be long
    opts.scale_per_dof = true;
    opts.ds_max = 1.0;
    opts
}

fn main() -> anyhow::Result<()> {
    let system = Jeffcott::default();
    let harmonics = match std::env::var("JC_H") {
        Ok(s) => s
            .parse()
            .map_err(|e| anyhow::anyhow!("JC_H = {s:?}: {e}"))?,
        Err(_) => HARMONICS,
    };
    let basis = system.basis(harmonics)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let (w0, w1) = Jeffcott::OMEGA_RANGE;
    let mut opts = options(w0, w1);
    opts.initial_guess = Some(system.start_guess(&basis, w0));
    // Floquet multipliers by the paper's SIP product (Eqs. 30–33) with default settings
    let sip = Sip::default();
    let mut cont = Continuation::new(hb, opts, Some(&sip))?;
    let branch = cont.run(|_| {})?;
    eprintln!(
        "{} points, {} rejected steps, {} bifurcations, finished: {:?}",
        branch.points.len(),
        branch.rejected_steps,
        branch.bifurcations.len(),
        branch.finish
    );
    eprintln!("{}", tmrotor::continuation::csv::COLUMNS_NOTE);
    print!("{}", branch_csv(&branch, 0)?);
    Ok(())
}
