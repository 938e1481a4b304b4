//! Two masses with a unilateral spring (NLvib's example 3, `tmrotor::systems::contact`),
//! Ω from 0.8 down to 0.5, H = 21 harmonics, 1024 AFT samples, as CSV on stdout (columns of
//! `tmrotor::continuation::csv`; amplitude = max |q₁| over one period).
//!
//! `cargo run --release --example contact > contact.csv` (`SAMPLES=2048` for other AFT
//! sample counts)
//!
//! Measured 2026-12-03 (stability by the variational equations, `stability::Variational`):
//! the physical folds at Ω = 0.6534401 and 0.7556642 (reference 0.6534401, 0.755664), but
//! also 320 more saddle-nodes in tiny fold pairs on the upper branch between 0.736 and
//! 0.755, which come from sampling the contact force (208 of them with 2048 samples); a
//! Neimark–Sacker point at 0.61150 (reference 0.618354) and period doublings at 0.7260 and
//! 0.6780. Reporting only the physical folds (exact Fourier coefficients of the
//! piecewise-linear force from its switching times) is not done yet.

use tmrotor::continuation::{Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{BifurcationKind, Variational};
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
    let method = Variational::default();
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
        "{} points, {} saddle-nodes, {} Neimark–Sacker, {} period doubling",
        branch.points.len(),
        kinds(BifurcationKind::SaddleNode),
        kinds(BifurcationKind::NeimarkSacker),
        kinds(BifurcationKind::PeriodDoubling)
    );
    for b in &branch.bifurcations {
        eprintln!("  {:?} at {:.7}", b.bifurcation, b.solution.omega);
    }
    print!("{}", branch_csv(&branch, 0)?);
    Ok(())
}
