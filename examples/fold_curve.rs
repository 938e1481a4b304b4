//! The fold curve of the Duffing oscillator `ẍ + 0.05ẋ + x + 0.1x³ = F cos Ωt` in (Ω, F),
//! continued from a saddle-node of the sweep at F = 0.18 (`continuation::fold`), printed as
//! CSV: `omega,force,amplitude` per point, then the located cusp as a `#` line on stderr.
//!
//! ```sh
//! cargo run --release --example fold_curve [-- ORDER] > fold_curve.csv
//! ```
//!
//! With ORDER = 1 (the default) the curve is the closed form of the one-harmonic balance
//! (`tests/fold_curves.rs` checks it to 3e-15) and the cusp lies at Ω = 1.044238,
//! F = 0.054054.

use tmrotor::continuation::fold::{FoldOptions, continue_fold};
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::BifurcationKind;
use tmrotor::systems::duffing::Duffing;

fn main() -> anyhow::Result<()> {
    let order: u32 = match std::env::args().nth(1) {
        Some(a) => a
            .parse()
            .map_err(|_| anyhow::anyhow!("ORDER {a:?}: expected a positive integer"))?,
        None => 1,
    };
    let family = |f: f64| -> Result<Duffing, String> {
        if f > 0.0 {
            Ok(Duffing::new(1.0, 0.05, 1.0, 0.1, f))
        } else {
            Err("the forcing amplitude must be positive".into())
        }
    };
    // a saddle-node of the one-parameter sweep at F = 0.18
    let basis = Basis::integer(order)?;
    let system = family(0.18).map_err(anyhow::Error::msg)?;
    let hb = HarmonicBalance::new(&system, &basis, None)?;
    let mut opts = ContinuationOptions::new(0.5, 1.8);
    opts.ds_max = 0.02;
    let branch = Continuation::new(hb, opts, None)?.run(|_| {})?;
    let fold = branch
        .bifurcations
        .iter()
        .find(|b| b.bifurcation == Some(BifurcationKind::SaddleNode))
        .ok_or_else(|| anyhow::anyhow!("the sweep at F = 0.18 has no saddle-node"))?;

    // steps of at most 0.02 (scaled): the cusp is located on the points around it, and
    // coarser steps place it less exactly (0.05: 1e-4 off)
    let mut fold_opts = FoldOptions::new((0.02, 0.4), (0.5, 2.5));
    fold_opts.ds_max = 0.02;
    let curve = continue_fold(
        &family,
        &basis,
        &fold.solution.unknowns(),
        fold.solution.omega,
        0.18,
        &fold_opts,
    )?;
    println!("omega,force,amplitude");
    for p in &curve.points {
        // first-harmonic amplitude: coefficients [c0, a1.., b1..]
        let h = basis.n_harmonics();
        let amplitude = p.unknowns[1].hypot(p.unknowns[1 + h]);
        println!("{},{},{}", p.omega, p.p, amplitude);
    }
    for c in &curve.cusps {
        eprintln!("# cusp at omega = {:.6}, force = {:.6}", c.omega, c.p);
    }
    eprintln!("# {} points, ended: {:?}", curve.points.len(), curve.finish);
    Ok(())
}
