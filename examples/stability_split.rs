//! Measures the slow/fast split of the Floquet stability on a recording of the dual rotor:
//! per point, the product over the whole coupled state (mechanical and thermal, as
//! versions before the split computed it) beside the split (fast multipliers of the
//! frozen-temperature problem, slow exponents of the quasi-static reduction), and the
//! recorded folds.
//!
//!     cargo run --release --example stability_split -- FILE.mcap [FROM:TO]
//!
//! Columns: index, ω (rad/s), the coupled product's count outside the unit circle and its
//! real multiplier nearest +1 (minus 1), the split's fast count, slow count, the slow
//! exponent with the largest real part (1/s), the split ratio, and the located folds.

use tmrotor::derive::StabilityRederive;
use tmrotor::derive::coupled::CoupledRederive;
use tmrotor::record::reader::read_recording;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let file = args
        .next()
        .ok_or_else(|| anyhow::anyhow!("usage: stability_split FILE.mcap [FROM:TO]"))?;
    let range = match args.next() {
        Some(r) => {
            let (a, b) = r
                .split_once(':')
                .ok_or_else(|| anyhow::anyhow!("range {r:?}: expected FROM:TO"))?;
            (a.parse::<f64>()?, b.parse::<f64>()?)
        }
        None => (f64::NEG_INFINITY, f64::INFINITY),
    };
    let rec = read_recording(&file)?;
    if std::env::var("TIME_PARTS").is_ok() {
        return time_parts(&rec);
    }
    let folds_only = std::env::var("FOLDS_ONLY").is_ok();
    let near_fold = |i: u64| {
        rec.bifurcations
            .iter()
            .any(|b| b.after_point == i || b.after_point + 1 == i)
    };
    let re = CoupledRederive::from_run(&rec.run)?;
    println!(
        "index,omega,coupled_outside,coupled_real_nearest_one_minus_1,fast_outside,slow_outside,slow_top_re,slow_top_im,split_ratio,fast_nearest_one,fast_max_modulus,intervals,fold_after"
    );
    for p in rec
        .points
        .iter()
        .filter(|p| p.omega_rad_s >= range.0 && p.omega_rad_s <= range.1)
        .filter(|p| !folds_only || near_fold(p.index))
    {
        let coupled = re.coupled_product(p)?;
        let nearest = coupled
            .multipliers
            .iter()
            .filter(|m| m.im.abs() < 1e-12 && m.re > 0.0)
            .map(|m| m.re - 1.0)
            .fold(f64::INFINITY, |a, b| if b.abs() < a.abs() { b } else { a });
        let split = re.floquet(p)?;
        let top = split
            .slow_exponents
            .iter()
            .copied()
            .max_by(|a, b| a.re.total_cmp(&b.re))
            .unwrap_or_default();
        let fast_outside = split.unstable_count() - split.slow_unstable_count();
        let near = split
            .multipliers
            .iter()
            .copied()
            .min_by(|a, b| (a - 1.0).norm().total_cmp(&(b - 1.0).norm()))
            .unwrap_or_default();
        let maxmod = split.spectral_radius();
        let folds: Vec<String> = rec
            .bifurcations
            .iter()
            .filter(|b| b.after_point == p.index)
            .map(|b| format!("{}@{:.4}", b.kind.abbreviation(), b.omega_rad_s))
            .collect();
        println!(
            "{},{:.4},{},{:.3e},{},{},{:.4e},{:.3e},{:.3e},{:.6}{:+.6}i,{:.6},{},{}",
            p.index,
            p.omega_rad_s,
            coupled.unstable_count(),
            nearest,
            fast_outside,
            split.slow_unstable_count(),
            top.re,
            top.im,
            split.split_ratio().unwrap_or(f64::NAN),
            near.re,
            near.im,
            maxmod,
            split.intervals.unwrap_or(0),
            folds.join(" ")
        );
    }
    Ok(())
}

/// Times the two halves of the split on the first 20 points (with `TIME_PARTS` set).
fn time_parts(rec: &tmrotor::record::reader::Recording) -> anyhow::Result<()> {
    use tmrotor::study::{StudySettings, SweepProblem, stability_method};
    use tmrotor::system::System;
    let settings = StudySettings::from_run(&rec.run)?;
    let model = tmrotor::model::Model::from_str(&rec.run.model_text, &rec.run.model_name)?;
    let problem = SweepProblem::with_model(&settings, model)?;
    let hb = tmrotor::hb::HarmonicBalance::new(
        &problem.system,
        &problem.basis,
        settings.harmonic.aft_samples,
    )?;
    let method = stability_method(&settings, &problem.system, settings.sweep.omega_start)?;
    let (mut t_slow, mut t_fast, mut t_full) = (0.0, 0.0, 0.0);
    for p in rec.points.iter().take(20) {
        let sol = tmrotor::hb::HbSolution {
            omega: p.omega_rad_s,
            basis: problem.basis.clone(),
            mech: p.coeffs_mech.clone(),
            therm: p.coeffs_therm.clone(),
            residual: Default::default(),
            relative_residual: Default::default(),
            iterations: 0,
        };
        let t = std::time::Instant::now();
        tmrotor::stability::slow_exponents(&hb, &sol)?;
        t_slow += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let frozen = tmrotor::stability::FrozenTemperature::new(&problem.system, &sol);
        method.multipliers(
            &frozen,
            &tmrotor::stability::FrozenOrbit::new(&sol, problem.system.n_therm()),
        )?;
        t_fast += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        method.multipliers(&problem.system, &sol)?;
        t_full += t.elapsed().as_secs_f64();
    }
    println!(
        "per point: slow exponents {:.1} ms, frozen product {:.1} ms, coupled product {:.1} ms",
        t_slow * 50.0,
        t_fast * 50.0,
        t_full * 50.0
    );
    Ok(())
}
