//! Frequency response of the primary mass with a nonlinear tuned vibration absorber
//! (`tmrotor::systems::absorber`), Ω from 0.8 to 1.4, as CSV on stdout (see
//! `tmrotor::continuation::csv` for the columns; amplitude = max |x₁| of the primary mass).
//!
//! `cargo run --release --example absorber > absorber.csv`

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::Sip;
use tmrotor::systems::absorber::Absorber;

fn main() -> anyhow::Result<()> {
    let system = Absorber::default();
    // cubic springs: odd harmonics; 7 integer harmonics resolve them to ~1e-6 of the fundamental
    let basis = Basis::integer(7)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let (w0, w1) = Absorber::OMEGA_RANGE;
    let opts = ContinuationOptions::new(w0, w1);
    // Floquet multipliers by the paper's SIP product (Eqs. 30–33), Richardson-extrapolated
    // (safe for small low-frequency systems, see `tmrotor::stability::sip`)
    let sip = Sip {
        extrapolate: true,
        ..Sip::default()
    };
    let mut cont = Continuation::new(hb, opts, Some(&sip))?;
    let branch = cont.run(|_| {})?;
    eprintln!(
        "{} points, {} rejected steps, finished: {:?}",
        branch.points.len(),
        branch.rejected_steps,
        branch.finish
    );
    eprintln!("{}", tmrotor::continuation::csv::COLUMNS_NOTE);
    print!("{}", branch_csv(&branch, 0)?);
    Ok(())
}
