//! Branch switching at a period doubling (`continuation::switch`) on the forced
//! double-well Duffing oscillator `ẍ + 0.3ẋ − x + x³ = γ cos(1.2 t)`, continued in γ
//! (`examples/period_doubling.rs`): from the located period doubling (γ* ≈ 0.2656) the
//! switch finds the period-doubled orbit, its continuation on the doubled basis follows it,
//! and at γ = 0.275 its two stroboscopic samples are those of direct time integration
//! (which alternates between two points there): measured 1e-10 apart, asserted to 1e-7.

#[path = "../examples/period_doubling.rs"]
#[allow(dead_code)]
mod example;

use tmrotor::continuation::switch::{SwitchOptions, switch_at_period_doubling};
use tmrotor::continuation::{Continuation, ContinuationOptions};
use tmrotor::hb::newton::{NewtonOptions, solve_fixed};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::integrate::{Dopri5Options, poincare_samples};
use tmrotor::stability::BifurcationKind;
use tmrotor::systems::period_doubling::{DoubleWellDuffing, GammaParametrized, OMEGA};

#[test]
fn the_period_doubled_branch_from_the_switch_matches_time_integration() {
    let branch = example::branch().expect("primary branch");
    let pd = branch
        .bifurcations
        .iter()
        .find(|b| b.bifurcation == Some(BifurcationKind::PeriodDoubling))
        .expect("a located period doubling");
    let gamma_pd = pd.solution.omega;
    let system = GammaParametrized::reference();
    let basis = Basis::integer(example::HARMONICS).expect("basis");
    let start = switch_at_period_doubling(&system, &basis, &pd.solution, &SwitchOptions::default())
        .expect("switch");
    eprintln!(
        "period doubling at γ = {gamma_pd:.6}; start at γ = {:.6}, half-order share {:.3e}, {} harmonics",
        start.omega,
        start.half_order_share,
        start.basis.n_harmonics()
    );
    assert!(start.omega > gamma_pd, "the doubled branch lies above γ*");

    // the doubled branch by continuation, then solved at γ = 0.275
    let hb = HarmonicBalance::new(&system, &start.basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(start.omega, 0.276);
    opts.initial_guess = Some(start.unknowns.clone());
    opts.ds_max = 0.02;
    let doubled = Continuation::new(hb, opts, None)
        .expect("continuation")
        .run(|_| {})
        .expect("doubled branch");
    let last = doubled.points.last().expect("points");
    assert!(
        last.solution.omega >= 0.275,
        "reached {}",
        last.solution.omega
    );
    let hb = HarmonicBalance::new(&system, &start.basis, None).expect("hb");
    let (a, _) = solve_fixed(
        &hb,
        0.275,
        &last.solution.unknowns(),
        &NewtonOptions::default(),
    )
    .expect("solve at 0.275");

    // stroboscopic samples: the rescaled time s = γ t / Ω has the forcing period 2π/γ
    let g = 0.275;
    let period_s = 2.0 * std::f64::consts::PI / g;
    let mut hb_samples = [
        start.basis.eval(&a, g, 0.0).0,
        start.basis.eval(&a, g, period_s).0,
    ];
    hb_samples.sort_by(f64::total_cmp);
    let strobes = poincare_samples(
        &DoubleWellDuffing::reference(g),
        OMEGA,
        &[1.0, 0.0],
        2.0 * std::f64::consts::PI / OMEGA,
        400,
        4,
        &Dopri5Options::default(),
    )
    .expect("time integration");
    let xs: Vec<f64> = strobes.iter().map(|y| y[0]).collect();
    let mut ti = [xs[0], xs[1]];
    ti.sort_by(f64::total_cmp);
    eprintln!("γ = 0.275: HB samples {hb_samples:?}, time integration {xs:?}");
    assert!(
        (xs[0] - xs[2]).abs() < 1e-6,
        "time integration is period 2: {xs:?}"
    );
    assert!(
        (ti[1] - ti[0]).abs() > 0.05,
        "the two samples differ: {ti:?}"
    );
    for k in 0..2 {
        assert!(
            (hb_samples[k] - ti[k]).abs() < 1e-7,
            "HB {hb_samples:?} against time integration {ti:?}"
        );
    }
}
