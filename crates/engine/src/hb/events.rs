//! Event-refined quadrature: exact Fourier coefficients of piecewise-smooth nonlinear terms.
//!
//! The AFT of [`super::aft`] samples the nonlinear terms on a uniform grid, which is
//! spectrally accurate for smooth forces. A force with a kink (unilateral contact, a stop,
//! rub: `k·max(0, d − g)`) has a spectrum that decays like `1/k²`, and its sampled
//! derivative jumps from one sample to the next as the contact instant moves across a
//! sample: the residual is not differentiable in the coefficients, and a continuation meets
//! tiny fold pairs wherever a contact instant crosses a sample (hundreds of them on the
//! two-mass contact benchmark).
//!
//! Here the instants where the terms stop being smooth (the zeros of the system's
//! switching functions, [`System::switching`](crate::system::System::switching)) are found on
//! the orbit, and one period is cut into pieces at them and at `panels` uniform panel
//! boundaries. Each piece is integrated by 8-point Gauss–Legendre quadrature, whose error
//! on a smooth piece spanning a phase `Φ` of the integrand's highest frequency falls like
//! `(Φ/2)^16/16!`. The coefficients `D_k = (1/P) ∫ y(t) e^{−ikθ(t)} dt` then hold for the
//! piecewise-smooth series itself: no aliasing, no sampling artefacts, and the Jacobian
//! assembled from the same quadrature is the derivative of these coefficients (the terms
//! must be continuous across a switching instant, so moving the instant adds nothing).
//!
//! A switching function that changes sign twice between two detection points (a contact
//! grazing within `P / (2·panels)`) is not seen; the detection grid has two points per
//! panel.

use num_complex::Complex64;

/// Gauss–Legendre nodes on `[−1, 1]`, 8 points (positive half; the rule is symmetric).
const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
/// The matching weights (they sum to 1 over the half).
const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// The fixed part of the event quadrature: `panels` uniform panels over the phase
/// `θ ∈ [0, 2π)` with 8 Gauss–Legendre nodes each, and their rows `e^{−ikθ}`,
/// `k = 0..=k_max`, computed once per harmonic balance.
#[derive(Clone, Debug)]
pub struct PanelRule {
    panels: usize,
    theta: Vec<f64>,
    weights: Vec<f64>,
    phases: Vec<Complex64>,
    k_len: usize,
}

/// Gauss–Legendre nodes and weights (normalised by `2π`) on `[a, b]` in phase.
fn gauss_nodes(a: f64, b: f64, theta: &mut Vec<f64>, weights: &mut Vec<f64>) {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let scale = half / (2.0 * std::f64::consts::PI);
    for (&x, &w) in GL_X.iter().rev().zip(GL_W.iter().rev()) {
        theta.push(mid - half * x);
        weights.push(w * scale);
    }
    for (&x, &w) in GL_X.iter().zip(&GL_W) {
        theta.push(mid + half * x);
        weights.push(w * scale);
    }
}

/// Appends `e^{−ikθ}`, `k = 0..k_len`, for each `θ` (rounding grows like `k ε`: 1e-14 at
/// `k = 50`).
pub(crate) fn push_phases(theta: &[f64], k_len: usize, out: &mut Vec<Complex64>) {
    for &t in theta {
        let (s, c) = t.sin_cos();
        let step = Complex64::new(c, -s);
        let mut z = Complex64::new(1.0, 0.0);
        for _ in 0..k_len {
            out.push(z);
            z *= step;
        }
    }
}

const TAU: f64 = 2.0 * std::f64::consts::PI;

impl PanelRule {
    /// `panels` uniform panels (at least 1), spectra up to multiple `k_max`.
    pub fn new(panels: usize, k_max: usize) -> Self {
        let panels = panels.max(1);
        let (mut theta, mut weights) = (Vec::new(), Vec::new());
        for j in 0..panels {
            let a = TAU * j as f64 / panels as f64;
            let b = TAU * (j + 1) as f64 / panels as f64;
            gauss_nodes(a, b, &mut theta, &mut weights);
        }
        let k_len = k_max + 1;
        let mut phases = Vec::with_capacity(theta.len() * k_len);
        push_phases(&theta, k_len, &mut phases);
        Self {
            panels,
            theta,
            weights,
            phases,
            k_len,
        }
    }

    /// The nodes' phases `θ`, 8 per panel, increasing.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// Node `i`'s row `e^{−ikθ_i}`, `k = 0..=k_max`.
    pub fn row(&self, i: usize) -> &[Complex64] {
        &self.phases[i * self.k_len..(i + 1) * self.k_len]
    }

    /// The nodes of one period for switching functions whose values at this rule's nodes
    /// are `values` (node-major, `n_switch` per node): where one changes sign between two
    /// consecutive nodes (cyclically), `locate(i, (θa, sa), (θb, sb))` returns its zero in
    /// `[θa, θb]` (`sa`, `sb` its values there, from `values`), and the panels holding
    /// zeros are cut there and integrated piece by piece. For the bracket across the
    /// period's end (`θb` = the first node's phase + 2π) `sb` is `None`: the first node's
    /// value decides the sign, but a switching function need not be periodic in `θ` (a
    /// rolling-element bearing's contacts move with the cage, whose speed is not a
    /// multiple of the base frequency), so the locator evaluates it at `θb`.
    pub fn refine(
        &self,
        values: &[f64],
        n_switch: usize,
        mut locate: impl FnMut(usize, (f64, f64), (f64, Option<f64>)) -> f64,
    ) -> EventNodes {
        let n = self.theta.len();
        let mut events = Vec::new();
        if n_switch > 0 {
            for j in 0..n {
                let jn = (j + 1) % n;
                let (ta, tb) = (
                    self.theta[j],
                    if jn == 0 {
                        self.theta[0] + TAU
                    } else {
                        self.theta[jn]
                    },
                );
                for i in 0..n_switch {
                    let (sa, sb) = (values[j * n_switch + i], values[jn * n_switch + i]);
                    if sa.is_finite() && sb.is_finite() && (sa > 0.0) != (sb > 0.0) {
                        let sb = (jn != 0).then_some(sb);
                        events.push(locate(i, (ta, sa), (tb, sb)).rem_euclid(TAU));
                    }
                }
            }
            events.sort_by(f64::total_cmp);
            events.dedup_by(|a, b| (*a - *b).abs() <= 1e-13 * TAU);
        }
        let width = TAU / self.panels as f64;
        let mut nodes = EventNodes {
            events,
            k_len: self.k_len,
            ..EventNodes::default()
        };
        let mut e = 0;
        for j in 0..self.panels {
            let (a, b) = (width * j as f64, width * (j + 1) as f64);
            let first = e;
            while e < nodes.events.len() && nodes.events[e] < b {
                e += 1;
            }
            let inside: Vec<f64> = nodes.events[first..e]
                .iter()
                .copied()
                .filter(|&t| t > a + 1e-15 * TAU && t < b - 1e-15 * TAU)
                .collect();
            if inside.is_empty() {
                for i in 8 * j..8 * (j + 1) {
                    nodes.theta.push(self.theta[i]);
                    nodes.weights.push(self.weights[i]);
                    nodes.rows.push(Row::Rule(i));
                }
                continue;
            }
            let cuts: Vec<f64> = std::iter::once(a)
                .chain(inside)
                .chain(std::iter::once(b))
                .collect();
            for w in cuts.windows(2) {
                let start = nodes.theta.len();
                gauss_nodes(w[0], w[1], &mut nodes.theta, &mut nodes.weights);
                for i in start..nodes.theta.len() {
                    nodes.rows.push(Row::Own(nodes.phases.len() / self.k_len));
                    push_phases(&nodes.theta[i..=i], self.k_len, &mut nodes.phases);
                }
            }
        }
        nodes
    }
}

/// Where a node's phase row lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// Node `i` of the [`PanelRule`] (its state may be reused).
    Rule(usize),
    /// Row `i` of the nodes' own table (a panel cut at a switching instant).
    Own(usize),
}

/// Quadrature nodes over one period, with the located switching instants.
#[derive(Clone, Debug, Default)]
pub struct EventNodes {
    /// Node phases `θ = Ω_b t` in `[0, 2π)`, increasing.
    pub theta: Vec<f64>,
    /// Weights normalised by the period (they sum to 1).
    pub weights: Vec<f64>,
    /// Where each node comes from.
    pub rows: Vec<Row>,
    /// The switching instants found, as phases, increasing.
    pub events: Vec<f64>,
    /// `e^{−ikθ}` of the cut panels' nodes, `k_len` per node.
    phases: Vec<Complex64>,
    k_len: usize,
}

impl EventNodes {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.theta.len()
    }

    /// `true` when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.theta.is_empty()
    }

    /// The row `e^{−ikθ}`, `k = 0..=k_max`, of a node (`rule`: the rule these nodes were
    /// refined from).
    pub fn row<'r>(&'r self, rule: &'r PanelRule, row: Row) -> &'r [Complex64] {
        let k = self.k_len;
        match row {
            Row::Rule(i) => rule.row(i),
            Row::Own(i) => &self.phases[i * k..(i + 1) * k],
        }
    }

    /// `D_k = Σ_i w_i y_i e^{−ikθ_i}` for `k = 0..=k_max` into `buf` (resized to `n`, the
    /// rest zero), the layout of [`super::Aft::spectrum`]: `series` holds `y` at the nodes
    /// and `rule` is the rule these nodes were refined from.
    pub fn spectrum(&self, rule: &PanelRule, series: &[f64], n: usize, buf: &mut Vec<Complex64>) {
        let k = self.k_len;
        buf.clear();
        buf.resize(n.max(k), Complex64::new(0.0, 0.0));
        let out = &mut buf[..k];
        for ((&y, &w), row) in series.iter().zip(&self.weights).zip(&self.rows) {
            let yw = y * w;
            if yw == 0.0 {
                continue;
            }
            for (o, p) in out.iter_mut().zip(self.row(rule, *row)) {
                *o += p * yw;
            }
        }
    }
}

/// A zero of `f` in `[a, b]` where `f(a) = fa` and `f(b) = fb` differ in sign.
pub fn illinois(f: &mut impl FnMut(f64) -> f64, a: f64, fa: f64, b: f64, fb: f64) -> f64 {
    let (mut a, mut fa, mut b, mut fb) = (a, fa, b, fb);
    let tol = 4.0 * f64::EPSILON * a.abs().max(b.abs()).max(f64::MIN_POSITIVE);
    let mut side = 0i8;
    for _ in 0..100 {
        let c = (a * fb - b * fa) / (fb - fa);
        let c = if c.is_finite() && c > a.min(b) && c < a.max(b) {
            c
        } else {
            0.5 * (a + b)
        };
        let fc = f(c);
        if fc == 0.0 || (b - a).abs() <= tol || !fc.is_finite() {
            return c;
        }
        if (fc > 0.0) == (fb > 0.0) {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The nodes of `rule` for the single switching function `s(θ)`.
    fn refine_with(rule: &PanelRule, s: impl Fn(f64) -> f64) -> EventNodes {
        let values: Vec<f64> = rule.theta().iter().map(|&t| s(t)).collect();
        rule.refine(&values, 1, |_, (a, fa), (b, fb)| {
            let mut f = |t: f64| s(t);
            let fb = fb.unwrap_or_else(|| f(b));
            illinois(&mut f, a, fa, b, fb)
        })
    }

    /// The half-wave rectified cosine `max(0, cos θ − c)` has closed-form Fourier
    /// coefficients; the event quadrature must reproduce them to rounding, where uniform
    /// sampling errs at the level of the spectrum's `1/k²` tail.
    #[test]
    fn kinked_cosine_coefficients_are_exact() {
        let c = 0.3;
        // the harmonic balance's rule for multiples up to 6: 8 (6 + 1) panels
        let rule = PanelRule::new(56, 12);
        let nodes = refine_with(&rule, |t| t.cos() - c);
        assert_eq!(nodes.events.len(), 2, "{:?}", nodes.events);
        let a = c.acos();
        assert!((nodes.events[0] - a).abs() < 1e-14);
        assert!((nodes.events[1] - (2.0 * PI - a)).abs() < 1e-14);
        // two panels cut in two: 2 × 8 more nodes
        assert_eq!(nodes.len(), 56 * 8 + 16);
        let series: Vec<f64> = nodes
            .theta
            .iter()
            .map(|&t| (t.cos() - c).max(0.0))
            .collect();
        let mut spec = Vec::new();
        nodes.spectrum(&rule, &series, 32, &mut spec);
        // (1/2π) ∫_{−a}^{a} (cos θ − c) cos kθ dθ
        let exact = |k: i32| -> f64 {
            let k = f64::from(k);
            let sk = |m: f64| if m == 0.0 { a } else { (m * a).sin() / m };
            (0.5 * (sk(k - 1.0) + sk(k + 1.0)) - c * sk(k)) / PI
        };
        for k in 0..=12 {
            let d = spec[k as usize];
            assert!(
                (d.re - exact(k)).abs() < 1e-14,
                "k {k}: {} vs {}",
                d.re,
                exact(k)
            );
            assert!(d.im.abs() < 1e-14, "k {k}: odd part {}", d.im);
        }
        // the weights integrate 1 exactly
        assert!((nodes.weights.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    }

    /// A zero between the last node and the first (across θ = 0) is found and cut.
    #[test]
    fn a_switch_across_the_period_start_is_found() {
        let rule = PanelRule::new(4, 3);
        let nodes = refine_with(&rule, |t| (t - 1e-3).sin());
        assert_eq!(nodes.events.len(), 2, "{:?}", nodes.events);
        assert!((nodes.events[0] - 1e-3).abs() < 1e-14);
        assert!((nodes.events[1] - (PI + 1e-3)).abs() < 1e-14);
    }

    #[test]
    fn no_switching_gives_plain_panels() {
        let rule = PanelRule::new(32, 3);
        let nodes = rule.refine(&[], 0, |_, (a, _), _| a);
        assert_eq!(nodes.len(), 256);
        assert!(nodes.events.is_empty());
        let series: Vec<f64> = nodes.theta.iter().map(|&t| (3.0 * t).sin()).collect();
        let mut spec = Vec::new();
        nodes.spectrum(&rule, &series, 8, &mut spec);
        // sin 3θ = (e^{3iθ} − e^{−3iθ})/2i: D_3 = −i/2
        assert!((spec[3] - Complex64::new(0.0, -0.5)).norm() < 1e-13);
        assert!(spec[1].norm() < 1e-13 && spec[0].norm() < 1e-13);
    }
}
