//! Costs on the built-in dual rotor (72 mechanical DoFs, 66 thermal nodes, order 3: 17
//! coefficients per DoF), at ω = 400 rad/s, q_l = 2 L/min:
//!
//! * `newton_iteration`: residual + exact Jacobian through the AFT + condensed solve;
//! * `stability/*`: one Floquet evaluation of a solution: exponential-split SIP on the
//!   Craig–Bampton reduction (the sweep default), and on the full model;
//! * `continuation_step`: one predictor–corrector step of the sweep with stability off
//!   and on (the step includes the tangent, the corrector and the step control), the
//!   third of a continuation from 400 rad/s (the second and later steps start their
//!   corrector from the previous point's factorization).
//!
//! Run: `cargo bench --bench dual_rotor`.

use criterion::{Criterion, criterion_group, criterion_main};

/// The allocator of the `tmrotor` binary, so the figures are the ones a sweep sees.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;
use std::hint::black_box;
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::{HarmonicBalance, HbSolution, LinearSolver, NewtonOptions, newton};
use tmrotor::stability::{ExpSip, StabilityMethod};
use tmrotor::sweep::{StudySettings, SweepProblem, stability_method};
use tmrotor::system::System;

const OMEGA: f64 = 400.0;

fn bench(c: &mut Criterion) {
    // as the binaries run them
    tmrotor::sequential_dense_kernels();
    let settings = StudySettings::default();
    let problem = SweepProblem::new(&settings).expect("problem");
    let sys = &problem.system;
    let basis = &problem.basis;
    let hb = HarmonicBalance::new(sys, basis, None).expect("hb");
    let a0 = sys.initial_guess(basis.n_coeffs());
    let (a, stats) =
        newton::solve_fixed(&hb, OMEGA, &a0, &NewtonOptions::default()).expect("solution");
    let orbit = HbSolution::from_unknowns(OMEGA, basis, sys.n_mech(), &a, &stats);

    let mut g = c.benchmark_group("dual_rotor");
    g.sample_size(10);
    g.bench_function("newton_iteration", |b| {
        b.iter(|| {
            let mut r = vec![0.0; hb.n_unknowns()];
            let parts = hb
                .residual_jacobian(black_box(&a), OMEGA, &mut r)
                .expect("jacobian");
            let neg: Vec<f64> = r.iter().map(|v| -v).collect();
            LinearSolver::default()
                .solve(&hb, &parts, None, &neg, 0.0)
                .expect("solve")
        })
    });
    let reduced = stability_method(&settings, sys, OMEGA).expect("method");
    g.bench_function("stability/exp_sip_reduced", |b| {
        b.iter(|| {
            reduced
                .multipliers(sys, black_box(&orbit))
                .expect("multipliers")
        })
    });
    let full = ExpSip {
        intervals: settings.floquet.sip_intervals,
        ..ExpSip::default()
    };
    g.bench_function("stability/exp_sip_full", |b| {
        b.iter(|| {
            full.multipliers(sys, black_box(&orbit))
                .expect("multipliers")
        })
    });
    for with_stability in [false, true] {
        let name = if with_stability {
            "continuation_step/with_stability"
        } else {
            "continuation_step/no_stability"
        };
        g.bench_function(name, |b| {
            b.iter_batched(
                || {
                    let mut opts = ContinuationOptions::new(OMEGA, 700.0);
                    opts.ds_max = settings.sweep.ds_max;
                    opts.initial_guess = Some(a.clone());
                    let hb = HarmonicBalance::new(sys, basis, None).expect("hb");
                    let stab: Option<&dyn StabilityMethod> = if with_stability {
                        Some(reduced.as_ref())
                    } else {
                        None
                    };
                    let mut cont = Continuation::new(hb, opts, stab).expect("continuation");
                    // the start point, then one step: the measured step is a later one,
                    // which corrects from its start point's factorization (Keller)
                    cont.step().expect("first point");
                    cont.step().expect("second point");
                    cont
                },
                |mut cont| cont.step().expect("step"),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    // plots need system fonts that minimal machines lack; the numbers are what matter
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
