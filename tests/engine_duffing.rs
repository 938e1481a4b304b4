//! Duffing reference problem `ẍ + 0.05ẋ + x + 0.1x³ = 0.18 cos Ωt`, Ω ∈ [0.5, 1.6]:
//! folds against the single-harmonic frequency-response equation, stability against
//! Floquet multipliers of the variational equations, amplitudes against RK4 time
//! integration.

mod engine_support;

use engine_support::{VariationalFloquet, steady_max_abs};
use tmrotor::continuation::{Branch, Continuation, ContinuationOptions, csv::branch_csv};
use tmrotor::hb::{Basis, HarmonicBalance};
use tmrotor::stability::{BifurcationKind, StabilityMethod};
use tmrotor::system::PeriodicOrbit;
use tmrotor::systems::duffing::Duffing;

fn trace(order: u32, ds_max: f64, stability: Option<&dyn StabilityMethod>) -> Branch {
    let sys = Duffing::default();
    let basis = Basis::integer(order).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.5, 1.6);
    opts.ds_max = ds_max;
    opts.ds_initial = ds_max.min(0.02);
    opts.max_points = 100_000;
    let mut cont = Continuation::new(hb, opts, stability).expect("continuation");
    cont.run(|_| {}).expect("run")
}

/// ω at the folds of a branch: the vertex of the parabola ω(s) through each local extremum
/// and its two neighbours.
fn fold_frequencies(branch: &Branch) -> Vec<f64> {
    let p = &branch.points;
    let mut out = Vec::new();
    for i in 1..p.len() - 1 {
        let (w0, w1, w2) = (
            p[i - 1].solution.omega,
            p[i].solution.omega,
            p[i + 1].solution.omega,
        );
        if (w1 - w0) * (w2 - w1) < 0.0 {
            let (s0, s1, s2) = (p[i - 1].arclength, p[i].arclength, p[i + 1].arclength);
            // Lagrange parabola, vertex
            let d01 = (w1 - w0) / (s1 - s0);
            let d12 = (w2 - w1) / (s2 - s1);
            let c2 = (d12 - d01) / (s2 - s0);
            let c1 = d01 - c2 * (s0 + s1);
            let sv = -c1 / (2.0 * c2);
            out.push(w0 + d01 * (sv - s0) + c2 * (sv - s0) * (sv - s1));
        }
    }
    out
}

/// Fold frequencies of the single-harmonic frequency-response equation
/// `a²[(1 − Ω² + ¾k₃a²)² + (cΩ)²] = F²`: interior extrema of `Ω(a)` on both roots.
fn analytic_folds() -> Vec<f64> {
    analytic_fold_points().into_iter().map(|(w, _)| w).collect()
}

/// The folds of the single-harmonic frequency-response equation as points `(Ω, a)`.
fn analytic_fold_points() -> Vec<(f64, f64)> {
    let (c, k3, f) = (0.05_f64, 0.1_f64, 0.18_f64);
    let omega_of = |a: f64, sign: f64| -> Option<f64> {
        let kap = 1.0 + 0.75 * k3 * a * a;
        let b = 2.0 * kap - c * c;
        let cc = kap * kap - f * f / (a * a);
        let disc = b * b - 4.0 * cc;
        if disc < 0.0 {
            return None;
        }
        let u = 0.5 * (b + sign * disc.sqrt());
        (u > 0.0).then(|| u.sqrt())
    };
    let mut folds = Vec::new();
    for sign in [-1.0, 1.0] {
        let n = 200_000;
        let grid: Vec<(f64, Option<f64>)> = (1..n)
            .map(|i| {
                let a = 0.01 + 5.0 * i as f64 / n as f64;
                (a, omega_of(a, sign))
            })
            .collect();
        for w in grid.windows(3) {
            if let (Some(o0), Some(o1), Some(o2)) = (w[0].1, w[1].1, w[2].1)
                && (o1 - o0) * (o2 - o1) < 0.0
            {
                // golden-section refinement of the extremum in [a0, a2]
                let is_max = o1 > o0;
                let (mut lo, mut hi) = (w[0].0, w[2].0);
                let g = 0.5 * (5f64.sqrt() - 1.0);
                let val =
                    |a: f64| omega_of(a, sign).unwrap_or(o1) * if is_max { 1.0 } else { -1.0 };
                for _ in 0..100 {
                    let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
                    if val(m1) > val(m2) {
                        hi = m2;
                    } else {
                        lo = m1;
                    }
                }
                let a = 0.5 * (lo + hi);
                folds.push((omega_of(a, sign).unwrap_or(o1), a));
            }
        }
    }
    folds.sort_by(|x, y| x.0.total_cmp(&y.0));
    folds
}

/// A located saddle-node is the fold as a point on the branch, not only its speed: on
/// the single-harmonic balance (HB-1, which is the frequency-response equation exactly)
/// its amplitude equals the amplitude at the extremum of Ω(a) of that equation, found by
/// golden section without the continuation.
#[test]
fn located_saddle_nodes_carry_the_branch_point_at_the_fold() {
    let analytic = analytic_fold_points();
    assert_eq!(analytic.len(), 2);
    let branch = trace(1, 0.1, None);
    let mut located: Vec<(f64, f64)> = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::SaddleNode))
        .map(|b| {
            let c = b.solution.mech_coeffs(0);
            (b.solution.omega, c[1].hypot(c[2]))
        })
        .collect();
    located.sort_by(|x, y| x.0.total_cmp(&y.0));
    assert_eq!(located.len(), 2);
    for ((w, a), (wf, af)) in located.iter().zip(&analytic) {
        eprintln!("located (Ω, a) = ({w:.12}, {a:.12}), theory ({wf:.12}, {af:.12})");
        assert!((w - wf).abs() < 1e-8 * wf, "Ω {w} vs {wf}");
        assert!((a - af).abs() < 1e-6 * af, "amplitude {a} vs {af}");
    }
}

#[test]
fn branch_passes_both_folds_and_one_harmonic_folds_match_theory() {
    let analytic = analytic_folds();
    assert_eq!(analytic.len(), 2, "analytic folds {analytic:?}");
    // single-harmonic HB is exactly the single-harmonic theory: agreement to fit accuracy
    let b1 = trace(1, 0.01, None);
    assert!(
        matches!(b1.finish, tmrotor::continuation::FinishReason::Bound { omega } if omega == 1.6)
    );
    let mut f1 = fold_frequencies(&b1);
    f1.sort_by(f64::total_cmp);
    assert_eq!(f1.len(), 2, "ω must reverse exactly twice: {f1:?}");
    for (h, a) in f1.iter().zip(&analytic) {
        assert!((h - a).abs() < 1e-6 * a, "HB-1 fold {h} vs theory {a}");
    }
    // converged HB: folds within the error of single-harmonic theory (the third harmonic is
    // a few per cent of the fundamental at the peak)
    let b11 = trace(11, 0.02, None);
    let mut f11 = fold_frequencies(&b11);
    f11.sort_by(f64::total_cmp);
    assert_eq!(f11.len(), 2, "{f11:?}");
    for (h, a) in f11.iter().zip(&analytic) {
        assert!(
            (h - a).abs() < 0.02 * a,
            "HB-11 fold {h} vs 1-harmonic theory {a}"
        );
    }
    eprintln!("analytic {analytic:?}, HB-1 {f1:?}, HB-11 {f11:?}");
}

#[test]
fn stability_changes_exactly_at_the_folds_and_stable_amplitudes_match_time_integration() {
    let floquet = VariationalFloquet { steps: 400 };
    let branch = trace(11, 0.1, Some(&floquet));
    let folds = {
        let fine = trace(11, 0.01, None);
        let mut f = fold_frequencies(&fine);
        f.sort_by(f64::total_cmp);
        f
    };
    assert_eq!(folds.len(), 2);
    // two saddle-node points, located on the folds
    let mut sn: Vec<f64> = branch
        .bifurcations
        .iter()
        .map(|b| {
            assert_eq!(b.bifurcation, Some(BifurcationKind::SaddleNode));
            b.solution.omega
        })
        .collect();
    sn.sort_by(f64::total_cmp);
    assert_eq!(sn.len(), 2, "{sn:?}");
    for (s, f) in sn.iter().zip(&folds) {
        assert!((s - f).abs() < 1e-5 * f, "saddle-node at {s}, fold at {f}");
    }
    // the middle branch (between the two saddle-nodes in arclength) is unstable, the rest stable
    let (s_lo, s_hi) = {
        let mut s: Vec<f64> = branch.bifurcations.iter().map(|b| b.arclength).collect();
        s.sort_by(f64::total_cmp);
        (s[0], s[1])
    };
    let mut n_unstable = 0;
    for p in &branch.points {
        let stable = p.stable().expect("stability computed");
        let inside = p.arclength > s_lo && p.arclength < s_hi;
        assert_eq!(stable, !inside, "point at ω = {}", p.solution.omega);
        n_unstable += usize::from(inside);
    }
    assert!(n_unstable >= 3);
    // CSV carries the labels and flags
    let csv = branch_csv(&branch, 0).expect("csv");
    assert_eq!(csv.matches("saddle_node").count(), 2);
    assert!(csv.contains(",false,"));

    // stable amplitudes vs RK4 from a 1 % perturbed start, 400 time units of transient
    // (decay rate c/2 = 0.025: the perturbation falls below 1e-6 of the amplitude)
    let sys = Duffing::default();
    let mut checked = 0;
    // (target ω, on the part before the first saddle-node in arclength?)
    for (target, before) in [(0.8, true), (1.2, true), (1.2, false), (1.5, false)] {
        let Some(p) = branch
            .points
            .iter()
            .filter(|p| p.stable() == Some(true))
            .filter(|p| {
                if before {
                    p.arclength < s_lo
                } else {
                    p.arclength > s_hi
                }
            })
            .min_by(|a, b| {
                (a.solution.omega - target)
                    .abs()
                    .total_cmp(&(b.solution.omega - target).abs())
            })
        else {
            continue;
        };
        let w = p.solution.omega;
        let period = p.solution.period();
        let (mut x, mut v) = ([0.0], [0.0]);
        p.solution.state_at(0.0, &mut x, &mut v, &mut []);
        let y0 = [1.01 * x[0], 0.99 * v[0]];
        let n_tr = (400.0 / period).ceil() as usize;
        let (amp_ti, _) = steady_max_abs(&sys, w, period, &y0, n_tr, 512, 0);
        let amp_hb = p.solution.max_abs(0);
        eprintln!("ω = {w}: HB {amp_hb} vs time integration {amp_ti}");
        assert!(
            (amp_hb - amp_ti).abs() < 1e-4 * amp_ti,
            "ω = {w}: HB {amp_hb} vs time integration {amp_ti}"
        );
        checked += 1;
    }
    assert_eq!(checked, 4);
}

/// Amplitudes `a` of the single-harmonic frequency-response equation at `Ω`: the positive
/// roots `u = a²` of `(¾k₃)² u³ + 2(1 − Ω²)(¾k₃) u² + ((1 − Ω²)² + (cΩ)²) u − F² = 0`,
/// found by scanning for sign changes and bisecting.
fn analytic_amplitudes(omega: f64) -> Vec<f64> {
    let (c, k3, f) = (0.05_f64, 0.1_f64, 0.18_f64);
    let (g, d) = (0.75 * k3, 1.0 - omega * omega);
    let p = |u: f64| {
        g * g * u.powi(3) + 2.0 * d * g * u * u + (d * d + (c * omega).powi(2)) * u - f * f
    };
    let n = 100_000;
    let u_max = 25.0;
    let mut roots = Vec::new();
    for i in 0..n {
        let (mut lo, mut hi) = (
            u_max * i as f64 / n as f64,
            u_max * (i + 1) as f64 / n as f64,
        );
        if p(lo) * p(hi) > 0.0 {
            continue;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if p(lo) * p(mid) <= 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        roots.push((0.5 * (lo + hi)).sqrt());
    }
    roots
}

/// Inside the hysteresis interval the traced branch crosses a speed three times; the
/// re-solve at exactly that speed between the bracketing points gives the three
/// single-harmonic amplitudes, in the order of the branch (hardening: resonant branch
/// first, then the unstable middle one, then the low one).
#[test]
fn solutions_at_a_speed_inside_the_hysteresis_interval_match_the_three_roots() {
    use tmrotor::continuation::{StepOutcome, crosses};
    use tmrotor::hb::HbSolution;
    let target = 1.2;
    let roots = analytic_amplitudes(target);
    assert_eq!(
        roots.len(),
        3,
        "Ω = {target} must lie in the hysteresis interval"
    );
    let sys = Duffing::default();
    let basis = Basis::integer(1).expect("basis");
    let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.5, 1.6);
    opts.ds_max = 0.05;
    opts.max_points = 100_000;
    let mut cont = Continuation::new(hb, opts, None).expect("continuation");
    let mut prev: Option<HbSolution> = None;
    let mut found = Vec::new();
    loop {
        match cont.step().expect("step") {
            StepOutcome::Accepted { point, .. } => {
                let sol = point.solution;
                if let Some(p) = &prev
                    && crosses(p.omega, sol.omega, target)
                {
                    let s = cont.solve_between(p, &sol, target).expect("re-solves");
                    assert_eq!(s.omega, target);
                    let c = s.mech_coeffs(0);
                    found.push((c[1] * c[1] + c[2] * c[2]).sqrt());
                }
                prev = Some(sol);
            }
            StepOutcome::Rejected(_) => {}
            StepOutcome::Finished(_) => break,
        }
    }
    assert_eq!(found.len(), 3, "crossings {found:?}");
    let mut expected = roots.clone();
    expected.sort_by(|a, b| b.total_cmp(a));
    for (a, b) in found.iter().zip(&expected) {
        assert!(
            (a - b).abs() <= 1e-6 * b,
            "found {found:?}, roots {expected:?}"
        );
    }
}

/// With a stability method the driver computes a point's multipliers alongside the next
/// step's corrector and hands the point out one step later; the branch must be the one
/// traced without stability, every point carrying the multipliers of its own solution,
/// the last one (on the bound) included, and each located bifurcation numbered as the
/// point after it.
#[test]
fn pipelined_stability_belongs_to_its_own_point_and_changes_no_point() {
    let floquet = VariationalFloquet { steps: 400 };
    let with = trace(11, 0.1, Some(&floquet));
    let without = trace(11, 0.1, None);
    assert_eq!(with.points.len(), without.points.len());
    for (i, (p, q)) in with.points.iter().zip(&without.points).enumerate() {
        assert_eq!(p.index, i);
        assert_eq!(p.solution.omega, q.solution.omega, "point {i}");
        assert_eq!(p.arclength, q.arclength, "point {i}");
        let own = floquet
            .multipliers(&Duffing::default(), &p.solution)
            .expect("multipliers");
        assert_eq!(
            p.stability.as_ref().map(|f| &f.multipliers),
            Some(&own.multipliers),
            "point {i} at ω = {}",
            p.solution.omega
        );
    }
    assert_eq!(with.points.last().map(|p| p.solution.omega), Some(1.6));
    assert_eq!(with.finish, without.finish);
    assert_eq!(with.bifurcations.len(), 2);
    for b in &with.bifurcations {
        let after = &with.points[b.index];
        let before = &with.points[b.index - 1];
        assert!(before.arclength < b.arclength && b.arclength < after.arclength);
        assert_ne!(before.stable(), after.stable());
    }
}

/// Saddle-nodes are located as folds of the branch (the zero of the tangent's
/// ω-component), not by the multiplier through +1: a crude Floquet method (RK4 with few
/// steps per period, whose multipliers near +1 are off) puts them on the same speeds as
/// an accurate one, and both on the folds of a finely traced branch without stability.
#[test]
fn saddle_nodes_sit_on_the_folds_whatever_the_multiplier_accuracy() {
    let folds = {
        let fine = trace(11, 0.005, None);
        let mut f = fold_frequencies(&fine);
        f.sort_by(f64::total_cmp);
        f
    };
    assert_eq!(folds.len(), 2);
    let sn = |steps: usize| {
        let floquet = VariationalFloquet { steps };
        let branch = trace(11, 0.1, Some(&floquet));
        let w = saddle_nodes(&branch);
        let flips: Vec<f64> = branch
            .points
            .windows(2)
            .filter(|p| p[0].stable() != p[1].stable())
            .map(|p| p[1].solution.omega)
            .collect();
        eprintln!("{steps} steps: saddle-nodes {w:?}, stable flag changes before {flips:?}");
        (w, flips)
    };
    let (accurate, flips_accurate) = sn(400);
    let (crude, flips_crude) = sn(12);
    eprintln!("folds {folds:?}");
    // the crude multipliers do move the stability changes
    assert_ne!(flips_accurate, flips_crude);
    assert_eq!(accurate.len(), 2);
    assert_eq!(crude.len(), 2);
    for ((a, c), f) in accurate.iter().zip(&crude).zip(&folds) {
        assert!((a - c).abs() < 1e-9 * f, "{a} vs {c}");
        assert!((a - f).abs() < 1e-7 * f, "saddle-node at {a}, fold at {f}");
    }
}

/// ω of a branch's located saddle-nodes, ascending.
fn saddle_nodes(branch: &Branch) -> Vec<f64> {
    let mut w: Vec<f64> = branch
        .bifurcations
        .iter()
        .filter(|b| b.bifurcation == Some(BifurcationKind::SaddleNode))
        .map(|b| b.solution.omega)
        .collect();
    w.sort_by(f64::total_cmp);
    w
}

/// Corrector iterations summed over a branch's points.
fn total_iterations(branch: &Branch) -> usize {
    branch.points.iter().map(|p| p.solution.iterations).sum()
}

#[test]
fn the_curved_predictor_saves_corrector_iterations_and_finds_the_same_folds() {
    // HB-1 is the single-harmonic theory exactly: the located saddle-nodes are checked
    // against its folds, with the tangent-only predictor and with the curved one
    let analytic = analytic_folds();
    let run = |curved: bool| {
        let sys = Duffing::default();
        let basis = Basis::integer(1).expect("basis");
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let mut opts = ContinuationOptions::new(0.5, 1.6);
        opts.ds_max = 0.05;
        opts.curved_predictor = curved;
        let mut cont = Continuation::new(hb, opts, None).expect("continuation");
        cont.run(|_| {}).expect("run")
    };
    let (linear, curved) = (run(false), run(true));
    for branch in [&linear, &curved] {
        let folds = saddle_nodes(branch);
        assert_eq!(folds.len(), 2, "{folds:?}");
        for (h, a) in folds.iter().zip(&analytic) {
            assert!((h - a).abs() < 1e-4 * a, "located fold {h} vs theory {a}");
        }
    }
    // per point: the curved predictor starts closer, so its correctors iterate less
    let per_point = |b: &Branch| total_iterations(b) as f64 / b.points.len() as f64;
    let (il, ic) = (per_point(&linear), per_point(&curved));
    eprintln!(
        "iterations per point: tangent predictor {il:.2} ({} points), curved {ic:.2} ({} points)",
        linear.points.len(),
        curved.points.len()
    );
    assert!(ic < il, "curved {ic} against tangent-only {il}");
}

/// A continuation started at a point in the middle of a branch, oriented along the chord
/// to the next point and measuring arclength in the first branch's scales, retraces that
/// branch (the truncation check refines stretches of a window this way): on the stretch
/// across the upper fold it locates the same fold, its arclength agrees with the first
/// branch's, and `run_until` ends it at the first point past the stretch's end, on the
/// first branch's curve.
#[test]
fn a_continuation_started_mid_branch_retraces_a_stretch_of_it() {
    let sys = Duffing::default();
    let basis = Basis::integer(1).expect("basis");
    let run = |opts: ContinuationOptions, until: f64| {
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let mut c = Continuation::new(hb, opts, None).expect("continuation");
        let branch = c.run_until(|_| {}, |b| b.arclength >= until).expect("run");
        (branch, c.scales().to_vec())
    };
    let mut opts = ContinuationOptions::new(0.5, 1.6);
    opts.ds_max = 0.1;
    let (first, scales) = run(opts, f64::INFINITY);
    assert!(matches!(
        first.finish,
        tmrotor::continuation::FinishReason::Bound { .. }
    ));
    let p = &first.points;
    // the upper fold: the first point where Ω turns back
    let k = (1..p.len() - 1)
        .find(|&k| p[k + 1].solution.omega < p[k].solution.omega)
        .expect("a fold");
    let (i, j) = (k - 2, k + 2);
    let x = |b: &tmrotor::continuation::BranchPoint| -> Vec<f64> {
        b.solution
            .mech
            .iter()
            .copied()
            .chain([b.solution.omega])
            .collect()
    };
    let start = x(&p[i]);
    let span = p[j].arclength - p[i].arclength;
    let segment_opts = |direction: Option<Vec<f64>>| {
        let mut o = ContinuationOptions::new(p[i].solution.omega, 1.6);
        o.omega_bounds = Some((0.5, 1.6));
        o.ds_max = 0.01;
        o.ds_initial = 0.01;
        o.initial_guess = Some(start[..start.len() - 1].to_vec());
        o.scales = Some(scales.clone());
        o.start_direction = direction;
        o
    };
    // along the chord to the next point
    let chord: Vec<f64> = x(&p[i + 1])
        .iter()
        .zip(&start)
        .map(|(b, a)| b - a)
        .collect();
    let (seg, _) = run(segment_opts(Some(chord.clone())), span);
    assert!(matches!(
        seg.finish,
        tmrotor::continuation::FinishReason::Stopped { .. }
    ));
    let q = &seg.points;
    let last = q.last().expect("points");
    assert!(last.arclength >= span && q[q.len() - 2].arclength < span);
    // the same arclength measure: it ends on the first branch's curve, next to the point
    // that far along it (the fine steps follow the curve's bend more closely, so a
    // little short of it)
    let scaled = |a: &[f64], b: &[f64]| -> f64 {
        a.iter()
            .zip(b)
            .zip(&scales)
            .map(|((u, v), s)| ((u - v) / s).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let miss = scaled(&x(last), &x(&p[j]));
    assert!(
        miss < 0.05,
        "ends {miss} (scaled) from the first branch's point"
    );
    // the same fold
    let fold = |b: &Branch| -> Vec<f64> {
        b.bifurcations
            .iter()
            .filter(|f| f.bifurcation == Some(BifurcationKind::SaddleNode))
            .map(|f| f.solution.omega)
            .collect()
    };
    let (f0, f1) = (fold(&first), fold(&seg));
    assert_eq!(f1.len(), 1, "{f1:?}");
    assert!(
        f0.iter().any(|w| (w - f1[0]).abs() < 1e-8),
        "{f0:?} vs {f1:?}"
    );
    // against the chord it runs the other way: away from the fold, down in Ω
    let against: Vec<f64> = chord.iter().map(|v| -v).collect();
    let (back, _) = run(segment_opts(Some(against)), span);
    assert!(back.points[1].solution.omega < back.points[0].solution.omega);
    assert!(fold(&back).is_empty());
    // a direction or scales of the wrong length are refused, naming the setting
    for (direction, scales) in [(Some(vec![1.0]), None), (None, Some(vec![1.0, 2.0]))] {
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let mut o = segment_opts(direction);
        o.scales = scales;
        let mut c = Continuation::new(hb, o, None).expect("continuation");
        let e = c.run(|_| {}).expect_err("refused").to_string();
        assert!(e.contains("start_direction") || e.contains("scales"), "{e}");
    }
}
