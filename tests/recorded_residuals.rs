//! Every recorded point meets the convergence test, checked from the recording alone: the
//! residual of its recorded coefficients, evaluated again on the model and settings the
//! recording embeds, is the recorded `residual_mech` / `residual_therm` (absolute 2-norms,
//! N and W) and, divided by the load's norm at that speed, within the tolerances 1e-8
//! (mechanical) and 1e-3 (thermal) of the paper's convergence test (docs/user-guide.md,
//! "A point's residuals").

use std::process::Command;

use tmrotor::derive::coupled::CoupledRederive;
use tmrotor::hb::HarmonicBalance;
use tmrotor::hb::newton::reference_norms;
use tmrotor::record::read_recording;

#[test]
fn every_recorded_point_is_within_its_tolerances() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("r.mcap");
    let o = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep",
            "--omega",
            "480:530",
            "--order",
            "2",
            "--no-stability",
            "--no-verify",
            "-q",
            "-o",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rec = read_recording(&out).expect("recording");
    let rederive = CoupledRederive::from_run(&rec.run).expect("rederive");
    let problem = rederive.problem();
    let hb = HarmonicBalance::new(
        &problem.system,
        &problem.basis,
        problem.settings.harmonic.aft_samples,
    )
    .expect("hb");
    assert!(rec.points.len() > 10, "{} points", rec.points.len());
    let (mut worst_mech, mut worst_therm) = (0.0f64, 0.0f64);
    for p in &rec.points {
        let sol = rederive.solution(p);
        let coeffs: Vec<f64> = sol.mech.iter().chain(&sol.therm).copied().collect();
        let mut r = vec![0.0; coeffs.len()];
        hb.residual(&coeffs, sol.omega, &mut r).expect("residual");
        let abs = hb.norms(&r);
        let load = reference_norms(&hb, sol.omega);
        // the recorded norms are these
        for (what, recorded, again) in [
            ("mechanical", p.residual_mech, abs.mech),
            ("thermal", p.residual_therm, abs.therm),
        ] {
            assert!(
                (recorded - again).abs() <= 1e-6 * again.max(1e-300) + 1e-18,
                "point {} {what}: recorded {recorded:e}, again {again:e}",
                p.index
            );
        }
        let (em, et) = (abs.mech / load.mech, abs.therm / load.therm);
        worst_mech = worst_mech.max(em);
        worst_therm = worst_therm.max(et);
        assert!(em <= 1e-8, "point {} ε_mech {em:e}", p.index);
        assert!(et <= 1e-3, "point {} ε_therm {et:e}", p.index);
    }
    eprintln!(
        "{} points: largest ε_mech {worst_mech:.2e}, ε_therm {worst_therm:.2e}",
        rec.points.len()
    );
}
