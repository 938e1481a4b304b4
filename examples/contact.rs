//! Two masses with a unilateral spring (NLvib's example 3, `tmrotor::systems::contact`),
//! Ω from 0.8 down to 0.5, H = 21 harmonics, as CSV on stdout (columns of
//! `tmrotor::continuation::csv`; amplitude = max |q₁| over one period).
//!
//! `cargo run --release --example contact > contact.csv`
//!
//! The contact force `100 (q₁ − 1)⁺` has a kink where the contact closes and opens. The
//! harmonic balance finds those instants on the orbit and integrates the pieces between
//! them exactly (`hb::events`), so its residual is differentiable and the branch has only
//! its two folds. `SAMPLED=1` samples the force on the AFT's uniform grid instead
//! (`SAMPLES=1024` points by default, and the step cap of 0.05 that sampling needs): each
//! time a contact instant crosses a sample the residual's derivative jumps, and the
//! continuation meets hundreds of tiny artefact fold pairs near the upper fold.
//!
//! Stability by shooting from the balance's orbit (`stability::Shooting`): the variational
//! equations around the truncated orbit put the Neimark–Sacker point at 0.6115, the shot
//! orbit at 0.6186 (reference 0.618354).
//!
//! Measured results and timings: docs/validation.md and docs/performance.md.

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{BifurcationKind, Shooting};
use tmrotor::systems::contact::UnilateralContact;

fn main() -> anyhow::Result<()> {
    let system = UnilateralContact::default();
    let basis = Basis::integer(21)?;
    let sampled = std::env::var("SAMPLED").is_ok_and(|v| v != "0");
    let samples: usize = std::env::var("SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1024);
    let hb = HarmonicBalance::new(&system, &basis, Some(samples))?.with_event_refinement(!sampled);
    let (w0, w1) = UnilateralContact::OMEGA_RANGE;
    let mut opts = ContinuationOptions::new(w0, w1);
    opts.ds_max = if sampled { 0.05 } else { 0.3 };
    let method = Shooting::default();
    let mut cont = Continuation::new(hb, opts, Some(&method))?;
    let branch = cont.run(|_| {})?;
    let kinds = |k| {
        branch
            .bifurcations
            .iter()
            .filter(|b| b.bifurcation == Some(k))
            .count()
    };
    eprintln!(
        "{} points, {} saddle-nodes, {} Neimark–Sacker, {} period doubling ({})",
        branch.points.len(),
        kinds(BifurcationKind::SaddleNode),
        kinds(BifurcationKind::NeimarkSacker),
        kinds(BifurcationKind::PeriodDoubling),
        if sampled {
            "force sampled"
        } else {
            "force integrated between its switching instants"
        }
    );
    // a guard, not a filter: a fold whose two neighbours' shot multipliers do not show a
    // real multiplier passing +1 (a sampling artefact, or a point next to the fold where
    // shooting did not converge)
    let unconfirmed = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::SaddleNode) && !branch.confirmed(b))
        .count();
    eprintln!("{unconfirmed} saddle-nodes without a real shot multiplier through +1 beside them");
    if branch.bifurcations.len() <= 20 {
        for b in &branch.bifurcations {
            eprintln!("  {:?} at {:.7}", b.bifurcation, b.solution.omega);
        }
    }
    eprintln!("{}", tmrotor::continuation::csv::COLUMNS_NOTE);
    print!("{}", branch_csv(&branch, 0)?);
    Ok(())
}
