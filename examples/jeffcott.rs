//! Frequency response of the Jeffcott rotor on a Hertzian ball bearing with radial
//! clearance (`tmrotor::systems::jeffcott`), ω from 300 to 560 rad/s, as CSV on stdout (see
//! `tmrotor::continuation::csv` for the columns); amplitude = max |x_d| of the disk's
//! vertical displacement in m (DoF 1, gravity offset included).
//!
//! Basis: multiples of ω/5 up to 4ω (20 harmonics; the ball passage is at 16/5 ω). The
//! environment variable `JC_H` sets the number of harmonics: the journal maxima differ
//! from time integration by ~0.5 % with 20 and ~3e-5 with 160 (see
//! `tests/engine_jeffcott.rs`); 160 takes about a minute.
//!
//! `cargo run --release --example jeffcott > jeffcott.csv`

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::HarmonicBalance;
use tmrotor::stability::Sip;
use tmrotor::systems::jeffcott::Jeffcott;

fn main() -> anyhow::Result<()> {
    let system = Jeffcott::default();
    let basis = system.basis(
        std::env::var("JC_H")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(20),
    )?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let (w0, w1) = Jeffcott::OMEGA_RANGE;
    let mut opts = ContinuationOptions::new(w0, w1);
    opts.initial_guess = Some(system.start_guess(&basis, w0));
    // Floquet multipliers by the paper's SIP product (Eqs. 30–33) with default settings
    let sip = Sip::default();
    let mut cont = Continuation::new(hb, opts, Some(&sip))?;
    let branch = cont.run(|_| {})?;
    eprintln!(
        "{} points, {} rejected steps, finished: {:?}",
        branch.points.len(),
        branch.rejected_steps,
        branch.finish
    );
    print!("{}", branch_csv(&branch, 0)?);
    Ok(())
}
