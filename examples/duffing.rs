//! Frequency response of the Duffing oscillator `ẍ + 0.05ẋ + x + 0.1x³ = 0.18 cos Ωt`,
//! Ω from 0.5 to 1.6, as CSV on stdout (see `tmrotor::continuation::csv` for the columns;
//! amplitude = max |x| over one period).
//!
//! `cargo run --release --example duffing > duffing.csv`

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::Sip;
use tmrotor::systems::duffing::Duffing;

fn main() -> anyhow::Result<()> {
    let system = Duffing::default();
    // odd harmonics up to 9 carry the response to ~1e-6; 11 integer harmonics for margin
    let basis = Basis::integer(11)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let (w0, w1) = Duffing::OMEGA_RANGE;
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
