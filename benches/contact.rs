//! The unilateral-contact benchmark (NLvib's two-mass oscillator, `systems::contact`,
//! H = 21), the workload of `cargo run --release --example contact`:
//!
//! * `contact/residual_jacobian`: one residual and exact Jacobian on an orbit in contact,
//!   the force integrated between its switching instants (`hb::events`) against sampled on
//!   1024 points;
//! * `contact/branch`: the whole continuation from 0.8 down to 0.5 with the events (step
//!   cap 0.3), without stability (the corrector's share) and with shooting (the example).
//!
//! `cargo bench --bench contact`. Figures: docs/performance.md.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{Shooting, StabilityMethod};
use tmrotor::systems::contact::UnilateralContact;

/// An orbit whose first mass enters the contact over part of the period.
fn orbit(nc: usize) -> Vec<f64> {
    let mut c = vec![0.0; 2 * nc];
    c[1] = 1.2;
    c[nc + 1] = 0.4;
    c
}

fn branch(system: &UnilateralContact, stability: Option<&dyn StabilityMethod>) -> usize {
    let basis = Basis::integer(21).expect("basis");
    let hb = HarmonicBalance::new(system, &basis, Some(1024)).expect("hb");
    let (w0, w1) = UnilateralContact::OMEGA_RANGE;
    let mut opts = ContinuationOptions::new(w0, w1);
    opts.ds_max = 0.3;
    let mut cont = Continuation::new(hb, opts, stability).expect("continuation");
    cont.run(|_| {}).expect("run").points.len()
}

fn contact(c: &mut Criterion) {
    let system = UnilateralContact::default();
    let basis = Basis::integer(21).expect("basis");
    let a = orbit(basis.n_coeffs());
    let mut g = c.benchmark_group("contact");
    for (name, exact) in [("events", true), ("sampled_1024", false)] {
        let hb = HarmonicBalance::new(&system, &basis, Some(1024))
            .expect("hb")
            .with_event_refinement(exact);
        let mut r = vec![0.0; hb.n_unknowns()];
        g.bench_function(format!("residual_jacobian/{name}"), |b| {
            b.iter(|| black_box(hb.residual_jacobian(&a, 0.7, &mut r).expect("jacobian")))
        });
    }
    g.sample_size(10);
    g.bench_function("branch/no_stability", |b| {
        b.iter(|| black_box(branch(&system, None)))
    });
    let shooting = Shooting::default();
    g.bench_function("branch/shooting", |b| {
        b.iter(|| black_box(branch(&system, Some(&shooting))))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // criterion's plots need fonts this machine may lack
    config = Criterion::default().without_plots();
    targets = contact
}
criterion_main!(benches);
