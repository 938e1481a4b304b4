use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use tmrotor::hb::{Basis, HarmonicBalance, NewtonOptions, Ratio, newton};
use tmrotor::model::Model;
fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let thermal = args.get(1).map(|s| s != "mech").unwrap_or(true);
    let order: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(3);
    let omega: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(300.0);
    let nsamp: Option<usize> = args.get(4).and_then(|s| s.parse().ok());
    let model = Model::builtin()?;
    let sys = CoupledRotor::new(
        &model,
        &StudyOverrides::default(),
        CouplingOptions {
            thermal,
            frozen_clearance: false,
        },
    )?;
    let basis = Basis::paper(order, Ratio::new(6, 5)?)?;
    let hb = HarmonicBalance::new(&sys, &basis, nsamp)?;
    eprintln!("samples {}", hb.aft().n_samples());
    let mut a = sys.initial_guess(basis.n_coeffs());
    for max_it in [1usize, 2, 3, 5, 8, 12, 20, 40] {
        let opts = NewtonOptions {
            max_iterations: max_it,
            condense: std::env::var("NOCOND").is_err(),
            ..Default::default()
        };
        match newton::solve_fixed(&hb, omega, &a, &opts) {
            Ok((sol, st)) => {
                eprintln!("converged {st:?}");
                a = sol;
                break;
            }
            Err(e) => eprintln!("max_it {max_it}: {e}"),
        }
    }
    let nc = basis.n_coeffs();
    for node in [1u32, 8, 11, 12, 18] {
        let d = model.dof(node, tmrotor::model::Dir::X).unwrap();
        eprintln!(
            "node {node}: x0 {:.3e} y0 {:.3e}",
            a[d * nc],
            a[(d + 1) * nc]
        );
    }
    Ok(())
}
