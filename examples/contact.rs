//! Two masses with a unilateral spring (NLvib's example 3, `tmrotor::systems::contact`),
//! Ω from 0.8 down to 0.5, H = 21 harmonics, 1024 AFT samples, as CSV on stdout (columns of
//! `tmrotor::continuation::csv`; amplitude = max |q₁| over one period).
//!
//! `cargo run --release --example contact > contact.csv` (`SAMPLES=2048` for other AFT
//! sample counts)
//!
//! Stability by shooting from the balance's orbit (`stability::Shooting`): the variational
//! equations around the truncated orbit put the Neimark–Sacker point at 0.6115, the shot
//! orbit at 0.6186 (reference 0.618354). Saddle-nodes are kept when the shot orbits'
//! count of real multipliers above +1 changes across them (the audit rule of the sweeps):
//! sampling the contact force puts 320 more, in tiny fold pairs on the upper branch between
//! Ω = 0.736 and 0.7557 (208 with 2048 samples), which this rule drops.
//!
//! The stable flags are the shot orbits' own (the dropped folds' parity is not counted).
//!
//! Measured 2026-12-03: folds at 0.6534401 and 0.7556594 (reference 0.6534401, 0.755664),
//! Neimark–Sacker at 0.6186068 and 0.5819007 (where contact is lost), period doublings at
//! 0.7556 and 0.7388 on the upper branch (unstable between them by a multiplier below −1);
//! the flags still flicker within 1e-4 of the upper fold, inside the sampling cluster.
//! Exact Fourier coefficients of the piecewise-linear force (from its switching times)
//! would remove the cluster itself.

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{BifurcationKind, Shooting};
use tmrotor::systems::contact::UnilateralContact;

fn main() -> anyhow::Result<()> {
    let system = UnilateralContact::default();
    let basis = Basis::integer(21)?;
    let samples: usize = std::env::var("SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1024);
    let hb = HarmonicBalance::new(&system, &basis, Some(samples))?;
    let (w0, w1) = UnilateralContact::OMEGA_RANGE;
    let mut opts = ContinuationOptions::new(w0, w1);
    opts.ds_max = 0.05;
    let method = Shooting::default();
    let mut cont = Continuation::new(hb, opts, Some(&method))?;
    let mut branch = cont.run(|_| {})?;
    let kinds = |k| {
        branch
            .bifurcations
            .iter()
            .filter(|b| b.bifurcation == Some(k))
            .count()
    };
    eprintln!(
        "{} points, {} saddle-nodes, {} Neimark–Sacker, {} period doubling",
        branch.points.len(),
        kinds(BifurcationKind::SaddleNode),
        kinds(BifurcationKind::NeimarkSacker),
        kinds(BifurcationKind::PeriodDoubling)
    );
    // a fold is confirmed when the shot orbits' count of real multipliers above +1
    // changes between the points around it
    let confirmed: Vec<bool> = branch
        .bifurcations
        .iter()
        .map(|b| branch.confirmed(b))
        .collect();
    // the verdicts are the shot orbits' own: the dropped folds' parity is not counted
    for p in &mut branch.points {
        if let Some(f) = p.stability.as_mut().filter(|f| f.fold_parity_mismatch) {
            *f = tmrotor::stability::FloquetResult::new(f.multipliers.clone());
        }
    }
    let mut keep = confirmed.iter();
    branch
        .bifurcations
        .retain(|_| *keep.next().unwrap_or(&true));
    eprintln!(
        "{} saddle-nodes not confirmed by the shot orbits' multipliers dropped",
        confirmed.iter().filter(|c| !**c).count()
    );
    for b in &branch.bifurcations {
        eprintln!("  {:?} at {:.7}", b.bifurcation, b.solution.omega);
    }
    eprintln!("{}", tmrotor::continuation::csv::COLUMNS_NOTE);
    print!("{}", branch_csv(&branch, 0)?);
    Ok(())
}
