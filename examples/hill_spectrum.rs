//! The coupled Floquet exponents nearest zero (Hill's eigenproblem, shift-invert
//! Arnoldi) at recorded points of a dual-rotor sweep, with their cost, beside the fast
//! multipliers of the frozen-temperature product nearest +1 as recorded.
//!
//!     cargo run --release --example hill_spectrum -- FILE.mcap FROM:TO [EXTRA]
//!
//! With `BETWEEN=I` it instead solves 21 speeds between points I and I + 1 at fixed ω and
//! prints the exponents nearest the imaginary axis there (how a pair crosses inside a
//! step); with `HILL_PROFILE=1` it times the factorization of `T(σ)`, one solve and one
//! product with the linear part at the first point in range, and lists the moduli of the
//! exponents found; `HILL_BLOCK=B` grows the Arnoldi iteration by `B` vectors a step (0,
//! the default, chooses as the sweep does).

use std::time::Instant;

use tmrotor::derive::coupled::CoupledRederive;
use tmrotor::hb::HarmonicBalance;
use tmrotor::record::reader::read_recording;
use tmrotor::stability::{HillOptions, HillPencil};
use tmrotor::system::PeriodicOrbit;

/// The binaries' allocator and settings, so that the cost per point is theirs (the system
/// allocator maps and unmaps the Krylov basis' megabytes at every point).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    tmrotor::keep_freed_memory();
    tmrotor::sequential_dense_kernels();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file = args
        .first()
        .ok_or_else(|| anyhow::anyhow!("usage: hill_spectrum FILE.mcap FROM:TO [EXTRA]"))?;
    let (a, b) = args
        .get(1)
        .and_then(|r| r.split_once(':'))
        .ok_or_else(|| anyhow::anyhow!("range FROM:TO expected"))?;
    let (from, to): (f64, f64) = (a.parse()?, b.parse()?);
    let extra: usize = args.get(2).map_or(Ok(6), |s| s.parse())?;
    let rec = read_recording(file)?;
    let re = CoupledRederive::from_run(&rec.run)?;
    let problem = re.problem();
    let hb = HarmonicBalance::new(
        &problem.system,
        &problem.basis,
        problem.settings.harmonic.aft_samples,
    )?;
    let options = HillOptions {
        extra,
        block: std::env::var("HILL_BLOCK").map_or(Ok(0), |b| b.parse())?,
        ..HillOptions::default()
    };
    if let Ok(i) = std::env::var("BETWEEN") {
        let i: usize = i.parse()?;
        let (pa, pb) = (&rec.points[i], &rec.points[i + 1]);
        let (sa, sb) = (re.solution(pa), re.solution(pb));
        let (ua, ub) = (sa.unknowns(), sb.unknowns());
        for k in 0..=20 {
            let f = k as f64 / 20.0;
            let w = sa.omega + f * (sb.omega - sa.omega);
            let guess: Vec<f64> = ua.iter().zip(&ub).map(|(a, b)| a + f * (b - a)).collect();
            let (a, st) = tmrotor::hb::newton::solve_fixed(&hb, w, &guess, &Default::default())?;
            let sol = tmrotor::hb::HbSolution::from_unknowns(w, hb.basis(), hb.n_mech(), &a, &st);
            let nz = HillPencil::new(&hb, &sol, None)?.near_zero(hb.n_therm() + extra, &options)?;
            let mut top = nz.exponents.clone();
            top.sort_by(|a, b| (b.re / b.norm()).total_cmp(&(a.re / a.norm())));
            let top: Vec<String> = top
                .iter()
                .take(3)
                .map(|l| format!("{:.4e}{:+.4e}i", l.re, l.im))
                .collect();
            println!("ω {w:.6}: {top:?}");
        }
        return Ok(());
    }
    for p in rec
        .points
        .iter()
        .filter(|p| p.omega_rad_s >= from && p.omega_rad_s <= to)
    {
        let sol = re.solution(p);
        if std::env::var("HILL_PROFILE").is_ok() {
            let pencil = HillPencil::new(&hb, &sol, None)?;
            let t = Instant::now();
            let parts = pencil.at(0.01);
            let fact = tmrotor::hb::LinearSolver::default().factor(&hb, &parts, None)?;
            let tf = t.elapsed();
            let rhs: Vec<f64> = (0..hb.n_unknowns()).map(|i| (i as f64).sin()).collect();
            let t = Instant::now();
            for _ in 0..50 {
                let _ = fact.solve(&rhs, 0.0)?;
            }
            let ts = t.elapsed() / 50;
            let t = Instant::now();
            let mut out = vec![0.0; hb.n_unknowns()];
            for _ in 0..50 {
                hb.add_linear(&parts.linear, sol.omega, &rhs, &mut out);
            }
            let tl = t.elapsed() / 50;
            println!(
                "n_unknowns {} n_therm {} factor {:?} solve {:?} add_linear {:?}",
                hb.n_unknowns(),
                hb.n_therm(),
                tf,
                ts,
                tl
            );
            let nz = pencil.near_zero(hb.n_therm() + extra, &options)?;
            let mods: Vec<String> = nz
                .exponents
                .iter()
                .map(|l| format!("{:.2e}", l.norm()))
                .collect();
            println!("{}", mods.join(" "));
            return Ok(());
        }
        let t0 = Instant::now();
        let pencil = HillPencil::new(&hb, &sol, None)?;
        let t1 = Instant::now();
        let nz = pencil.near_zero(hb.n_therm() + extra, &options)?;
        let t2 = Instant::now();
        let top: Vec<String> = nz
            .exponents
            .iter()
            .rev()
            .take(4)
            .map(|l| format!("{:.4e}{:+.4e}i", l.re, l.im))
            .collect();
        let mut near: Vec<_> = p
            .multipliers
            .iter()
            .map(|m| m.ln() / sol.period())
            .collect();
        near.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
        let near: Vec<String> = near
            .iter()
            .take(2)
            .map(|l| format!("{:.4e}{:+.4e}i", l.re, l.im))
            .collect();
        let unstable: Vec<String> = nz
            .exponents
            .iter()
            .filter(|l| l.re > 0.0)
            .map(|l| format!("{:.4e}{:+.4e}i", l.re, l.im))
            .collect();
        println!(
            "{} ω {:.4}: {} exponents, radius {:.3} 1/s, {} steps, setup {:.0} ms, arnoldi {:.0} ms; largest |λ| {:?}; unstable {:?}; recorded fast exponents nearest 0 {:?}",
            p.index,
            p.omega_rad_s,
            nz.exponents.len(),
            nz.radius,
            nz.steps,
            (t1 - t0).as_secs_f64() * 1e3,
            (t2 - t1).as_secs_f64() * 1e3,
            top,
            unstable,
            near
        );
    }
    for b in rec
        .bifurcations
        .iter()
        .filter(|b| b.omega_rad_s >= from && b.omega_rad_s <= to)
    {
        let mut point = rec.points[0].clone();
        point.omega_rad_s = b.omega_rad_s;
        point.coeffs_mech.clone_from(&b.coeffs_mech);
        point.coeffs_therm.clone_from(&b.coeffs_therm);
        let sol = re.solution(&point);
        let nz = HillPencil::new(&hb, &sol, None)?.near_zero(hb.n_therm() + extra, &options)?;
        let mut top = nz.exponents.clone();
        top.sort_by(|a, b| b.re.total_cmp(&a.re));
        let top: Vec<String> = top
            .iter()
            .take(3)
            .map(|l| format!("{:.4e}{:+.4e}i", l.re, l.im))
            .collect();
        println!(
            "bifurcation {} {} at ω {:.5}: exponents with the largest real parts {:?}",
            b.number,
            b.kind.label(),
            b.omega_rad_s,
            top
        );
    }
    Ok(())
}
