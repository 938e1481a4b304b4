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
//! * `condensed_lu/*`: one LU factorization (faer's partial pivoting on one thread, the
//!   call the condensation makes, as the binaries run it) of a dense matrix of the
//!   condensed size the dual rotor has at orders 3, 4, 5, 7, 8 and 9, at orders 3, 4 and 5
//!   without half orders, and on the doubled basis of a switched branch (order 3 without
//!   half orders): the kernel that bounds the fixed workloads' cost from below
//!   (docs/performance.md, the eighth-session entry, "the floor of the method").
//!
//! Run: `cargo bench --bench dual_rotor` (`-- condensed_lu` for the factorizations alone).

use criterion::{Criterion, criterion_group, criterion_main};

/// The allocator of the `tmrotor` binary, so the figures are the ones a sweep sees.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;
use faer::Mat;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::factor as lu;
use std::hint::black_box;
use tmrotor::continuation::switch::doubled_basis;
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance, HbSolution, LinearSolver, NewtonOptions, newton};
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
    condensed_lu(c);
}

/// The condensed system's size (nonlinear DoFs × coefficients) of `problem`'s system on
/// `basis`.
fn condensed_size(problem: &SweepProblem, basis: &Basis) -> usize {
    let hb = HarmonicBalance::new(&problem.system, basis, None).expect("hb");
    hb.nonlinear_global().len() * basis.n_coeffs()
}

fn condensed_lu(c: &mut Criterion) {
    let mut cases: Vec<(String, usize)> = Vec::new();
    for (half_orders, orders) in [(true, &[3, 4, 5, 7, 8, 9][..]), (false, &[3, 4, 5][..])] {
        for &order in orders {
            let mut s = StudySettings::default();
            s.harmonic.order = order;
            s.harmonic.half_orders = half_orders;
            let problem = SweepProblem::new(&s).expect("problem");
            let prefix = if half_orders { "" } else { "no_half_orders_" };
            cases.push((
                format!("{prefix}order_{order}"),
                condensed_size(&problem, &problem.basis),
            ));
            // the switched branches of W5 (order 3 without half orders)
            if !half_orders && order == 3 {
                let doubled = doubled_basis(&problem.basis).expect("doubled basis");
                cases.push((
                    "doubled_no_half_orders".to_string(),
                    condensed_size(&problem, &doubled),
                ));
            }
        }
    }
    let mut g = c.benchmark_group("condensed_lu");
    g.sample_size(10);
    for (name, n) in cases {
        // dense and well conditioned; the factorization's cost does not depend on the
        // entries (partial pivoting, no sparsity)
        let a = Mat::<f64>::from_fn(n, n, |i, j| {
            ((i * 7 + j * 13) % 101) as f64 / 101.0 + if i == j { 3.0 } else { 0.0 }
        });
        let par = faer::Par::Seq;
        let mut mem = MemBuffer::new(lu::lu_in_place_scratch::<usize, f64>(
            n,
            n,
            par,
            Default::default(),
        ));
        let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
        g.bench_function(format!("{name}_n{n}"), |b| {
            b.iter_batched(
                || a.clone(),
                |mut m| {
                    lu::lu_in_place(
                        m.as_mut(),
                        &mut perm,
                        &mut perm_inv,
                        par,
                        MemStack::new(&mut mem),
                        Default::default(),
                    );
                    m
                },
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
