//! Cost of harmonic-balance Newton iterations with and without condensation of the linear
//! DoFs ("speed by structure").
//!
//! * `chain120`: 120-DoF spring–mass chain with one cubic contact, 5 integer harmonics
//!   (11 coefficients per DoF, 1320 unknowns): one Newton iteration (residual, exact
//!   Jacobian, linear solve) condensed vs full, and one converged point (Newton from the
//!   solution at a neighbouring ω).
//! * `dual_rotor_size`: the size of the dual rotor — 72 mechanical DoFs (10 nonlinear) and
//!   66 thermal DoFs (20 nonlinear), paper basis k = 3, λ = 6/5 (17 coefficients per DoF,
//!   2346 unknowns) — one condensed Newton iteration (the full dense solve is not benched:
//!   a 2346² LU per iteration).
//!
//! Measured (release, 2 shared cores): `chain120` one iteration 5–7.5 ms condensed vs
//! 350 ms full, one point 12–21 ms vs 590 ms; `dual_rotor_size` one condensed iteration
//! 15–25 ms (residual + Jacobian 2–6 ms; the dense LU of the 511×511 condensed system
//! ~8–11 ms of the solve), against ~0.8 s for one full 2346×2346 solve.
//!
//! `cargo bench --bench engine`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use tmrotor::hb::newton::{NewtonOptions, solve_fixed};
use tmrotor::hb::{Basis, HarmonicBalance, LinearSolver, Ratio};
use tmrotor::systems::chain::Chain;

fn iteration(hb: &HarmonicBalance<'_>, a: &[f64], omega: f64, condense: bool) -> Vec<f64> {
    let mut r = vec![0.0; hb.n_unknowns()];
    let parts = hb.residual_jacobian(a, omega, &mut r).expect("jacobian");
    r.iter_mut().for_each(|v| *v = -*v);
    LinearSolver { condense }
        .solve(hb, &parts, None, &r, 0.0)
        .expect("solve")
        .0
}

fn chain(c: &mut Criterion) {
    let n = if cfg!(debug_assertions) { 12 } else { 120 };
    let sys = Chain::new(n, 0);
    let basis = Basis::integer(5).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let omega = 1.0;
    let (a, _) = solve_fixed(
        &hb,
        omega,
        &vec![0.0; hb.n_unknowns()],
        &NewtonOptions::default(),
    )
    .expect("start");
    let mut g = c.benchmark_group("chain120");
    g.sample_size(10);
    for condense in [true, false] {
        let tag = if condense { "condensed" } else { "full" };
        g.bench_function(format!("iteration/{tag}"), |b| {
            b.iter(|| iteration(&hb, black_box(&a), omega, condense))
        });
        let opts = NewtonOptions {
            condense,
            ..NewtonOptions::default()
        };
        g.bench_function(format!("point/{tag}"), |b| {
            b.iter(|| solve_fixed(&hb, black_box(1.01), &a, &opts).expect("point"))
        });
    }
    g.finish();
}

fn dual_rotor_size(c: &mut Criterion) {
    let (nm, nt, p, q) = if cfg!(debug_assertions) {
        (12, 10, 2, 3)
    } else {
        (72, 66, 10, 20)
    };
    let sys = Chain::with_contacts(nm, nt, p, q);
    let basis = Basis::paper(3, Ratio::new(6, 5).expect("ratio")).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let omega = 1.0;
    let a = vec![0.01; hb.n_unknowns()];
    let mut g = c.benchmark_group("dual_rotor_size");
    g.sample_size(10);
    g.bench_function("iteration/condensed", |b| {
        b.iter(|| iteration(&hb, black_box(&a), omega, true))
    });
    g.bench_function("residual_jacobian", |b| {
        b.iter(|| {
            let mut r = vec![0.0; hb.n_unknowns()];
            hb.residual_jacobian(black_box(&a), omega, &mut r)
                .expect("jacobian")
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // plots need system fonts that minimal machines lack; the numbers are what matter
    config = Criterion::default().without_plots();
    targets = chain, dual_rotor_size
}
criterion_main!(benches);
