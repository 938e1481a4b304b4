//! The coupled exponents nearest zero (Hill's eigenproblem of the harmonic balance) on the
//! self-heated Duffing oscillator (`systems::thermo_duffing`), against a reference that
//! shares nothing with the code under test: the equations written out here, periodic
//! orbits by shooting (Newton on the period map), Floquet multipliers from the variational
//! equations, both integrated by fixed-step RK4, and a long direct integration.
//!
//! ```text
//!   ẍ + c ẋ + x + k₃ x³ − κ θ x = F cos Ωt,      τ θ̇ + θ = α c ẋ²
//! ```
//! c = 0.05, k₃ = 0.1, F = 0.18, κ = 1, α = 2, τ = 100, 1 000 and 10 000 forcing periods.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use tmrotor::continuation::{Branch, Continuation, ContinuationOptions};
use tmrotor::hb::{Basis, HarmonicBalance, HbSolution};
use tmrotor::stability::{BifurcationKind, HillOptions, HillPencil, Variational};
use tmrotor::system::PeriodicOrbit;
use tmrotor::systems::thermo_duffing::ThermoDuffing;

const C: f64 = 0.05;
const K3: f64 = 0.1;
const F: f64 = 0.18;
const KAPPA: f64 = 1.0;
const ALPHA: f64 = 2.0;

/// The reference equations: state `[x, v, θ]`, forcing frequency `w`, time constant `tau`.
struct Reference {
    w: f64,
    tau: f64,
}

impl Reference {
    /// The full exponents of the orbit through `y0` (already periodic) with the thermal
    /// time constant of the variational equations alone changed to `tau_var`: the
    /// linearisation's dependence on the thermal capacity, the orbit held.
    fn exponents_with_capacity(&self, y0: [f64; 3], tau_var: f64) -> Vec<Complex64> {
        let p = std::f64::consts::TAU / self.w;
        let (_, phi) = self.period_map_with(y0, 1600, false, tau_var);
        phi.complex_eigenvalues()
            .iter()
            .map(|mu| mu.ln() / p)
            .collect()
    }
}

impl Reference {
    fn rhs(&self, t: f64, y: &[f64; 3]) -> [f64; 3] {
        let [x, v, th] = *y;
        [
            v,
            F * (self.w * t).cos() - C * v - x - K3 * x * x * x + KAPPA * th * x,
            (ALPHA * C * v * v - th) / self.tau,
        ]
    }

    /// `∂f/∂y` at `y`; with `frozen`, without the couplings to and from `θ` (the
    /// vibration with the temperature held on its course).
    fn jac(&self, y: &[f64; 3], frozen: bool) -> [[f64; 3]; 3] {
        let [x, v, th] = *y;
        let c = if frozen { 0.0 } else { 1.0 };
        [
            [0.0, 1.0, 0.0],
            [-1.0 - 3.0 * K3 * x * x + KAPPA * th, -C, c * KAPPA * x],
            [0.0, c * 2.0 * ALPHA * C * v / self.tau, -1.0 / self.tau],
        ]
    }

    /// State after one period from `y0` (RK4, `n` steps).
    fn advance(&self, y0: [f64; 3], n: usize) -> [f64; 3] {
        let p = std::f64::consts::TAU / self.w;
        let h = p / n as f64;
        let mut y = y0;
        for k in 0..n {
            let t = k as f64 * h;
            let k1 = self.rhs(t, &y);
            let k2 = self.rhs(t + 0.5 * h, &[0, 1, 2].map(|i| y[i] + 0.5 * h * k1[i]));
            let k3 = self.rhs(t + 0.5 * h, &[0, 1, 2].map(|i| y[i] + 0.5 * h * k2[i]));
            let k4 = self.rhs(t + h, &[0, 1, 2].map(|i| y[i] + h * k3[i]));
            for i in 0..3 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        y
    }

    /// State and monodromy after one period from `y0` (RK4, `n` steps, variational
    /// equations alongside).
    fn period_map(&self, y0: [f64; 3], n: usize, frozen: bool) -> ([f64; 3], DMatrix<f64>) {
        self.period_map_with(y0, n, frozen, self.tau)
    }

    /// [`Self::period_map`] with the variational equations' time constant `tau_var` (the
    /// orbit's stays `self.tau`).
    fn period_map_with(
        &self,
        y0: [f64; 3],
        n: usize,
        frozen: bool,
        tau_var: f64,
    ) -> ([f64; 3], DMatrix<f64>) {
        let p = std::f64::consts::TAU / self.w;
        let h = p / n as f64;
        let mut y = y0;
        let mut phi = DMatrix::<f64>::identity(3, 3);
        let add = |a: &[f64; 3], b: &[f64; 3], s: f64| {
            [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
        };
        let var = Reference {
            w: self.w,
            tau: tau_var,
        };
        let jm = |y: &[f64; 3]| {
            let j = var.jac(y, frozen);
            DMatrix::from_fn(3, 3, |r, c| j[r][c])
        };
        for k in 0..n {
            let t = k as f64 * h;
            let k1 = self.rhs(t, &y);
            let y2 = add(&y, &k1, 0.5 * h);
            let k2 = self.rhs(t + 0.5 * h, &y2);
            let y3 = add(&y, &k2, 0.5 * h);
            let k3 = self.rhs(t + 0.5 * h, &y3);
            let y4 = add(&y, &k3, h);
            let k4 = self.rhs(t + h, &y4);
            let p1 = jm(&y) * &phi;
            let p2 = jm(&y2) * (&phi + &p1 * (0.5 * h));
            let p3 = jm(&y3) * (&phi + &p2 * (0.5 * h));
            let p4 = jm(&y4) * (&phi + &p3 * h);
            phi += (p1 + p2 * 2.0 + p3 * 2.0 + p4) * (h / 6.0);
            for i in 0..3 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        (y, phi)
    }

    /// The periodic orbit through (near) `guess` by Newton on the period map, and the
    /// Floquet exponents `ln μ / P` of the full (`frozen = false`) or frozen problem.
    fn orbit(&self, guess: [f64; 3], frozen: bool) -> ([f64; 3], Vec<Complex64>) {
        let n = 1600;
        let mut y = guess;
        for _ in 0..30 {
            let (yp, phi) = self.period_map(y, n, false);
            let r = DVector::from_fn(3, |i, _| yp[i] - y[i]);
            let a = phi - DMatrix::<f64>::identity(3, 3);
            let d = a.lu().solve(&(-&r)).expect("regular shooting matrix");
            for i in 0..3 {
                y[i] += d[i];
            }
            if d.norm() < 1e-13 * (1.0 + y.iter().map(|v| v.abs()).sum::<f64>()) {
                break;
            }
        }
        let (_, phi) = self.period_map(y, n, frozen);
        let p = std::f64::consts::TAU / self.w;
        let m = if frozen {
            phi.view((0, 0), (2, 2)).into_owned()
        } else {
            phi
        };
        let ex = m
            .complex_eigenvalues()
            .iter()
            .map(|mu| mu.ln() / p)
            .collect();
        (y, ex)
    }
}

/// The state `[x, ẋ, θ]` of a harmonic-balance solution at `t = 0`.
fn state0(s: &HbSolution) -> [f64; 3] {
    let (mut x, mut v, mut th) = ([0.0], [0.0], [0.0]);
    s.state_at(0.0, &mut x, &mut v, &mut th);
    [x[0], v[0], th[0]]
}

fn branch(system: &ThermoDuffing, order: u32, stability: bool) -> Branch {
    let basis = Basis::integer(order).expect("basis");
    let hb = HarmonicBalance::new(system, &basis, None).expect("hb");
    let mut opts = ContinuationOptions::new(0.8, 1.3);
    opts.ds_max = 0.05;
    opts.scale_mech = Some(1.0);
    opts.scale_therm = Some(1.0);
    opts.scale_omega = Some(1.0);
    let method = Variational::default();
    let mut cont =
        Continuation::new(hb, opts, stability.then_some(&method as _)).expect("continuation");
    cont.run(|_| {}).expect("branch")
}

/// The branch at order `order` with stability, and its located Neimark–Sacker point.
fn located_neimark_sacker(system: &ThermoDuffing, order: u32) -> (Branch, usize) {
    let b = branch(system, order, true);
    let k = b
        .bifurcations
        .iter()
        .position(|p| p.bifurcation == Some(BifurcationKind::NeimarkSacker))
        .expect("a located Neimark–Sacker point");
    (b, k)
}

fn hill(system: &ThermoDuffing, order: u32, s: &HbSolution) -> Vec<Complex64> {
    let basis = Basis::integer(order).expect("basis");
    let hb = HarmonicBalance::new(system, &basis, None).expect("hb");
    HillPencil::new(&hb, s, None)
        .expect("pencil")
        .near_zero(3, &HillOptions::default())
        .expect("near zero")
        .exponents
}

fn max_re(v: &[Complex64]) -> Complex64 {
    *v.iter()
        .max_by(|a, b| a.re.total_cmp(&b.re))
        .expect("exponents")
}

#[test]
fn near_zero_exponents_match_the_variational_equations_along_the_branch() {
    let tau = 100.0 * std::f64::consts::TAU;
    let system = ThermoDuffing::new(tau);
    let b = branch(&system, 9, false);
    let mut checked = 0;
    for p in b.points.iter().step_by(7) {
        let s = &p.solution;
        let r = Reference { w: s.omega, tau };
        let (_, reference) = r.orbit(state0(s), false);
        let mine = hill(&system, 9, s);
        assert_eq!(mine.len(), 3, "ω {}: {mine:?}", s.omega);
        for l in &reference {
            let d = mine
                .iter()
                .map(|m| (m - l).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                d < 1e-6 * l.norm().max(1e-3),
                "ω {}: reference exponent {l} against {mine:?}",
                s.omega
            );
        }
        checked += 1;
    }
    assert!(checked >= 10, "{checked} points");
}

/// Bisects `g` (a sign change between `a` and `b`) to `tol`.
fn bisect(mut a: f64, mut b: f64, tol: f64, g: impl Fn(f64) -> f64) -> f64 {
    let ga = g(a);
    assert!(ga * g(b) < 0.0, "no sign change in [{a}, {b}]");
    while (b - a).abs() > tol {
        let m = 0.5 * (a + b);
        if g(m) * ga > 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// The located Neimark–Sacker point of the tool on the branch at `tau_periods`, with its
/// reference: the Neimark–Sacker point and the frozen fold by shooting and the
/// variational equations, bisected between the branch points around the tool's point.
/// Returns (tool ω, reference ω, reference frozen-fold ω, tool angle, reference angle).
fn neimark_sacker(tau_periods: f64) -> (f64, f64, f64, f64, f64) {
    let tau = tau_periods * std::f64::consts::TAU;
    let system = ThermoDuffing::new(tau);
    let order = 9;
    let (b, k) = located_neimark_sacker(&system, order);
    let ns = &b.bifurcations[k];
    let s = &ns.solution;
    let tool = max_re(&hill(&system, order, s));
    let period = s.period();
    // bracket: the branch points around the located one
    let i = b
        .points
        .iter()
        .position(|p| p.index >= ns.index)
        .expect("point after");
    let (pa, pb) = (&b.points[i - 1].solution, &b.points[i].solution);
    let (ya, yb) = (state0(pa), state0(pb));
    let guess = |w: f64| {
        let f = (w - pa.omega) / (pb.omega - pa.omega);
        [0, 1, 2].map(|k| ya[k] + f * (yb[k] - ya[k]))
    };
    let g = |w: f64| {
        let (_, ex) = Reference { w, tau }.orbit(guess(w), false);
        max_re(&ex).re
    };
    let w_ns = bisect(pa.omega, pb.omega, 1e-10, g);
    let (_, ex) = Reference { w: w_ns, tau }.orbit(guess(w_ns), false);
    let angle_ref = max_re(&ex).im.abs() * std::f64::consts::TAU / w_ns;
    // the frozen fold: a real frozen exponent through zero, before the NS point
    let frozen = |p: &HbSolution| {
        let (_, ex) = Reference { w: p.omega, tau }.orbit(state0(p), true);
        max_re(&ex).re
    };
    let j = (1..=i)
        .rev()
        .find(|&j| frozen(&b.points[j - 1].solution) < 0.0 && frozen(&b.points[j].solution) >= 0.0)
        .expect("the frozen fold before the point");
    let (qa, qb) = (&b.points[j - 1].solution, &b.points[j].solution);
    let (za, zb) = (state0(qa), state0(qb));
    let w_ff = bisect(qa.omega, qb.omega, 1e-10, |w| {
        let f = (w - qa.omega) / (qb.omega - qa.omega);
        let y = [0, 1, 2].map(|k| za[k] + f * (zb[k] - za[k]));
        let (_, ex) = Reference { w, tau }.orbit(y, true);
        max_re(&ex).re
    });
    (s.omega, w_ns, w_ff, tool.im.abs() * period, angle_ref)
}

/// The Neimark–Sacker point beside the frozen fold: located by the sweep where the
/// reference puts it, with its angle; its offset from the frozen fold shrinks like
/// `ε = 1/τ` and its angle like `√ε` (τ = 100, 1 000, 10 000 forcing periods).
#[test]
fn neimark_sacker_point_beside_the_frozen_fold_scales_with_the_time_constant() {
    let taus = [100.0, 1000.0, 10000.0];
    let found: Vec<_> = taus.iter().map(|&t| neimark_sacker(t)).collect();
    for (&tau, &(w, w_ref, w_ff, a, a_ref)) in taus.iter().zip(&found) {
        println!(
            "τ = {tau} periods: Neimark–Sacker at {w:.9} (reference {w_ref:.9}), frozen fold {w_ff:.9}, offset {:.4e}, angle {a:.5e} rad (reference {a_ref:.5e})",
            w_ref - w_ff
        );
        assert!((w - w_ref).abs() < 1e-7, "τ = {tau}: {w} against {w_ref}");
        assert!(
            (a - a_ref).abs() < 1e-3 * a_ref,
            "τ = {tau}: angle {a} against {a_ref}"
        );
        // after the frozen fold on the way up, and close to it
        assert!(
            w_ref > w_ff && w_ref - w_ff < 1e-3,
            "τ = {tau}: {w_ref} vs {w_ff}"
        );
    }
    for k in 1..taus.len() {
        let ratio = taus[k] / taus[k - 1];
        let offsets = (found[k - 1].1 - found[k - 1].2) / (found[k].1 - found[k].2);
        let angles = found[k - 1].4 / found[k].4;
        assert!(
            (offsets / ratio - 1.0).abs() < 0.05,
            "offset ratio {offsets} for τ ratio {ratio}"
        );
        assert!(
            (angles / ratio.sqrt() - 1.0).abs() < 0.05,
            "angle ratio {angles} for τ ratio {ratio}"
        );
    }
}

/// Just past the Neimark–Sacker point a long direct integration leaves the orbit in a
/// slow, growing oscillation of the temperature whose period is the one the pair's angle
/// gives (and, once large, jumps to the lower branch: the point is subcritical).
#[test]
fn a_trajectory_just_past_the_point_modulates_with_the_predicted_period() {
    let tau_periods = 100.0;
    let tau = tau_periods * std::f64::consts::TAU;
    let (_, w_ns, _, _, _) = neimark_sacker(tau_periods);
    let system = ThermoDuffing::new(tau);
    let b = branch(&system, 9, false);
    let w = w_ns + 2e-5;
    let i = b
        .points
        .iter()
        .position(|p| p.solution.omega > w)
        .expect("past the point");
    let r = Reference { w, tau };
    let (y0, ex) = r.orbit(state0(&b.points[i].solution), false);
    let lambda = max_re(&ex);
    assert!(lambda.re > 0.0 && lambda.im.abs() > 0.0, "{lambda}");
    let predicted = std::f64::consts::TAU / lambda.im.abs() * w / std::f64::consts::TAU; // periods
    // stroboscopic temperature deviation, once per forcing period, from a small kick
    let mut y = y0;
    // (a small kick, followed while the departure stays linear: below 1e-3)
    y[2] += 1e-7;
    let n_periods = (12.0 * predicted) as usize;
    let mut dev = Vec::with_capacity(n_periods);
    for _ in 0..n_periods {
        y = r.advance(y, 400);
        dev.push(y[2] - y0[2]);
        if (y[2] - y0[2]).abs() > 1e-3 {
            break;
        }
    }
    // the period from the zero crossings of the deviation (up-crossings, interpolated)
    let ups: Vec<f64> = (1..dev.len())
        .filter(|&k| dev[k - 1] < 0.0 && dev[k] >= 0.0)
        .map(|k| (k - 1) as f64 + dev[k - 1] / (dev[k - 1] - dev[k]))
        .collect();
    println!(
        "λ = {lambda}, deviation max {:.3e}, at the end {:.3e}, up-crossings {ups:?}",
        dev.iter().map(|d| d.abs()).fold(0.0, f64::max),
        dev[dev.len() - 1]
    );
    assert!(ups.len() >= 4, "{} up-crossings", ups.len());
    let measured = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    println!(
        "ω = {w:.6}: predicted modulation {predicted:.1} periods, measured {measured:.1} ({} up-crossings)",
        ups.len()
    );
    assert!(
        (measured / predicted - 1.0).abs() < 0.03,
        "{measured} against {predicted}"
    );
}

/// The thermal share of the crossing mode at the Neimark–Sacker point (the exponent's
/// relative change with the thermal capacity, the orbit held) against the same derivative
/// of the reference's variational equations.
#[test]
fn the_crossing_pairs_thermal_share_matches_the_reference() {
    let tau = 100.0 * std::f64::consts::TAU;
    let system = ThermoDuffing::new(tau);
    let order = 9;
    let (b, k) = located_neimark_sacker(&system, order);
    let ns = &b.bifurcations[k];
    let s = &ns.solution;
    let f = ns.stability.as_ref().expect("stability at the point");
    let m = f.crossing_pair(s.period()).expect("a crossing pair");
    let l = m.exponent.expect("a near-zero pair");
    let basis = Basis::integer(order).expect("basis");
    let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
    let options = HillOptions::default();
    let share = HillPencil::new(&hb, s, None)
        .expect("pencil")
        .thermal_share(l, 3, &options)
        .expect("share");
    let r = Reference { w: s.omega, tau };
    let (y0, ex) = r.orbit(state0(s), false);
    let l_ref = max_re(&ex);
    let eps = 1e-3;
    let moved = r.exponents_with_capacity(y0, tau * (1.0 + eps));
    let l_moved = moved
        .iter()
        .min_by(|a, b| (*a - l_ref).norm().total_cmp(&(*b - l_ref).norm()))
        .copied()
        .expect("exponent");
    let share_ref = (-((l_moved - l_ref) / (eps * l_ref)).re).clamp(0.0, 1.0);
    println!(
        "crossing pair {l} (angle {:.4e} rad, modulation {:.1} s = {:.1} periods), thermal share {share:.4} (reference {share_ref:.4})",
        m.angle_rad,
        m.period_s,
        m.period_s / s.period()
    );
    assert!(
        (share - share_ref).abs() < 1e-3,
        "{share} against {share_ref}"
    );
    assert!((m.angle_rad - l_ref.im.abs() * s.period()).abs() < 1e-3 * m.angle_rad);
}

/// The modes of Hill's eigenproblem near zero are the monodromy matrix's eigenvectors:
/// for each near-zero exponent λ of the self-heated oscillator beside its Neimark–Sacker
/// point, the mode's state at t = 0 (`[p, λp + ṗ, p_T]`) carried over one period by the
/// variational equations (an independent integration) comes back multiplied by
/// `μ = e^{λP}`.
#[test]
fn near_zero_modes_are_eigenvectors_of_the_monodromy_matrix() {
    let tau = 100.0 * std::f64::consts::TAU;
    let system = ThermoDuffing::new(tau);
    let (b, k) = located_neimark_sacker(&system, 9);
    let s9 = &b.bifurcations[k].solution;
    // the largest relative residual `‖Φy − μy‖/‖y‖` of the modes at `order`, on the orbit
    // solved again at that order
    let worst = |order: u32| -> f64 {
        let basis = Basis::integer(order).expect("basis");
        let hb = HarmonicBalance::new(&system, &basis, None).expect("hb");
        let guess = tmrotor::hb::HbSolution::from_unknowns(
            s9.omega,
            &basis,
            1,
            &embed(s9, order),
            &Default::default(),
        );
        let (a, st) = tmrotor::hb::newton::solve_fixed(
            &hb,
            s9.omega,
            &guess.unknowns(),
            &tmrotor::hb::NewtonOptions::default(),
        )
        .expect("orbit");
        let s = HbSolution::from_unknowns(s9.omega, &basis, 1, &a, &st);
        let modes = HillPencil::new(&hb, &s, None)
            .expect("pencil")
            .near_zero_modes(3, &HillOptions::default())
            .expect("modes");
        assert_eq!(modes.len(), 3, "{modes:?}");
        let phi = Variational::default()
            .monodromy(&system, &s)
            .expect("monodromy");
        let period = s.period();
        let mut worst: f64 = 0.0;
        for m in &modes {
            let (x, v, th) = m.state_at(&basis, s.omega, 1, 0.0);
            let y: Vec<Complex64> = x.into_iter().chain(v).chain(th).collect();
            let mu = (m.exponent * period).exp();
            let py: Vec<Complex64> = (0..3)
                .map(|i| (0..3).map(|j| y[j] * phi[(i, j)]).sum())
                .collect();
            let norm = y.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
            let err = py
                .iter()
                .zip(&y)
                .map(|(a, b)| (a - mu * b).norm_sqr())
                .sum::<f64>()
                .sqrt()
                / norm;
            println!(
                "order {order}, λ = {:.4e}: ‖Φy − μy‖/‖y‖ = {err:.2e}",
                m.exponent
            );
            worst = worst.max(err);
        }
        worst
    };
    let (e9, e15) = (worst(9), worst(15));
    // eigenvectors to the truncation's accuracy, converging with the order
    assert!(e9 < 1e-5, "order 9: {e9}");
    assert!(e15 < 0.1 * e9, "order 15: {e15} against {e9} at order 9");
}

/// `s`'s unknowns on the integer basis of `order` (its harmonics kept, new ones zero).
fn embed(s: &HbSolution, order: u32) -> Vec<f64> {
    let nc_old = s.basis.n_coeffs();
    let (h_old, h_new) = ((nc_old - 1) / 2, order as usize);
    let nc = 1 + 2 * h_new;
    let block = |c: &[f64]| {
        let mut out = vec![0.0; nc];
        out[0] = c[0];
        for h in 0..h_old.min(h_new) {
            out[1 + h] = c[1 + h];
            out[1 + h_new + h] = c[1 + h_old + h];
        }
        out
    };
    let mut u = block(s.mech_coeffs(0));
    u.extend(block(s.therm_coeffs(0)));
    u
}
