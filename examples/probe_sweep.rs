use std::time::Instant;
use tmrotor::continuation::{Continuation, ContinuationOptions, StepOutcome};
use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use tmrotor::hb::{Basis, HarmonicBalance, Ratio};
use tmrotor::model::Model;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let thermal = args.get(1).map(|s| s != "mech").unwrap_or(true);
    let q: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2.0);
    let order: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let model = Model::builtin()?;
    let sys = CoupledRotor::new(
        &model,
        &StudyOverrides {
            flow_l_min: Some(q),
            ..Default::default()
        },
        CouplingOptions {
            thermal,
            frozen_clearance: false,
        },
    )?;
    let basis = Basis::paper(order, Ratio::new(6, 5)?)?;
    let hb = HarmonicBalance::new(&sys, &basis, None)?;
    let mut opts = ContinuationOptions::new(300.0, 700.0);
    opts.initial_guess = Some(sys.initial_guess(basis.n_coeffs()));
    let mut cont = Continuation::new(hb, opts, None)?;
    let t0 = Instant::now();
    let n8 = model.dof(8, tmrotor::model::Dir::X).unwrap();
    let branch = cont.run(|o| match o {
        StepOutcome::Accepted { point, .. } => {
            let s = &point.solution;
            let a = s.rms_amplitude(n8, Some(n8 + 1));
            let tmax = (0..s.n_therm())
                .map(|p| s.therm_coeffs(p)[0])
                .fold(f64::MIN, f64::max);
            eprintln!(
                "{:8.3} {:.4e} it={} Tmax={:.2} t={:.1}s",
                s.omega,
                a,
                s.iterations,
                tmax,
                t0.elapsed().as_secs_f64()
            );
        }
        StepOutcome::Rejected(r) => eprintln!("rejected: {r:?}"),
        StepOutcome::Finished(f) => eprintln!("finished: {f:?}"),
    })?;
    eprintln!(
        "{} points in {:.1}s",
        branch.points.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
