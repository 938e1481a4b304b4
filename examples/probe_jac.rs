use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
use tmrotor::hb::{Basis, HarmonicBalance, Ratio};
use tmrotor::model::Model;
fn main() -> anyhow::Result<()> {
    let model = Model::builtin()?;
    let sys = CoupledRotor::new(
        &model,
        &StudyOverrides::default(),
        CouplingOptions {
            thermal: false,
            frozen_clearance: false,
        },
    )?;
    let basis = Basis::paper(1, Ratio::new(6, 5)?)?;
    let hb = HarmonicBalance::new(&sys, &basis, None)?;
    let a = sys.initial_guess(basis.n_coeffs());
    let n = a.len();
    let omega = 300.0;
    let mut r0 = vec![0.0; n];
    let parts = hb.residual_jacobian(&a, omega, &mut r0)?;
    let j = hb.dense_jacobian(&parts);
    let d: Vec<f64> = (0..n).map(|i| 1e-6 * ((i as f64) * 0.37).sin()).collect();
    let jd: Vec<f64> = (0..n)
        .map(|r| (0..n).map(|c| j[r * n + c] * d[c]).sum())
        .collect();
    for h in [1e-1, 1e-2, 1e-3, 1e-4] {
        let ap: Vec<f64> = a.iter().zip(&d).map(|(x, y)| x + h * y).collect();
        let am: Vec<f64> = a.iter().zip(&d).map(|(x, y)| x - h * y).collect();
        let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
        hb.residual(&ap, omega, &mut rp)?;
        hb.residual(&am, omega, &mut rm)?;
        let fd: Vec<f64> = rp
            .iter()
            .zip(&rm)
            .map(|(p, m)| (p - m) / (2.0 * h))
            .collect();
        let err: f64 = fd
            .iter()
            .zip(&jd)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt();
        let nrm: f64 = jd.iter().map(|x| x * x).sum::<f64>().sqrt();
        eprintln!("h {h:e}: |J d| {nrm:e} |fd - J d| {err:e}");
    }
    let r0n: f64 = r0.iter().map(|x| x * x).sum::<f64>().sqrt();
    eprintln!("|r0| = {r0n:e}");
    Ok(())
}
