//! Multi-frequency trigonometric basis (paper Eq. 34).
//!
//! A basis is a constant term plus a set of frequencies, each a rational multiple
//! `p/q · ω` of the continuation parameter `ω`. Coefficients of one DoF are stored as
//!
//! ```text
//!   [a_0, a_1, …, a_H, b_1, …, b_H]      x(t) = a_0 + Σ_h a_h cos(ν_h ω t) + b_h sin(ν_h ω t)
//! ```
//!
//! (the paper's Eq. 23 ordering: constant, all cosines, all sines), with `ν_h = p_h/q_h`.
//! All frequencies are integer multiples of `ω / q_base` where `q_base` is the least
//! common multiple of the denominators in lowest terms, so the response is periodic with
//! period `2π q_base / ω` in `t` (`2π q_base` in `τ = ω t`).

use thiserror::Error;

/// A positive rational multiple `num/den` of the base frequency, kept in lowest terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Ratio {
    pub num: u32,
    pub den: u32,
}

impl Ratio {
    /// `num/den` in lowest terms. Errors on a zero numerator or denominator.
    pub fn new(num: u32, den: u32) -> Result<Self, BasisError> {
        if num == 0 || den == 0 {
            return Err(BasisError::ZeroRatio { num, den });
        }
        let g = gcd(num, den);
        Ok(Self {
            num: num / g,
            den: den / g,
        })
    }

    /// The value as a float.
    pub fn value(self) -> f64 {
        f64::from(self.num) / f64::from(self.den)
    }

    /// The rational closest to `x` with denominator at most `max_den`, if it matches `x`
    /// within `1e-9` relative; used to reject irrational-looking speed ratios.
    pub fn approximate(x: f64, max_den: u32) -> Option<Self> {
        if !x.is_finite() || x <= 0.0 {
            return None;
        }
        for den in 1..=max_den {
            let num = (x * f64::from(den)).round();
            if num >= 1.0 && num <= f64::from(u32::MAX) {
                let r = num / f64::from(den);
                if (r - x).abs() <= 1e-9 * x.max(1.0) {
                    return Self::new(num as u32, den).ok();
                }
            }
        }
        None
    }
}

/// Errors building a basis.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum BasisError {
    #[error("harmonic ratio {num}/{den} is not a positive rational")]
    ZeroRatio { num: u32, den: u32 },
    #[error("harmonic {num}/{den} appears twice in the basis")]
    Duplicate { num: u32, den: u32 },
    #[error("a basis needs at least one harmonic besides the constant term")]
    Empty,
    #[error("truncation order must be at least 1, got {0}")]
    ZeroOrder(u32),
}

/// The constant term plus harmonics `ν_h ω`, `h = 1..=H`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Basis {
    harmonics: Vec<Ratio>,
    base_den: u32,
}

impl Basis {
    /// A basis from a list of harmonic ratios (order is kept; duplicates are rejected).
    pub fn new(harmonics: Vec<Ratio>) -> Result<Self, BasisError> {
        if harmonics.is_empty() {
            return Err(BasisError::Empty);
        }
        for (i, h) in harmonics.iter().enumerate() {
            if harmonics[..i].contains(h) {
                return Err(BasisError::Duplicate {
                    num: h.num,
                    den: h.den,
                });
            }
        }
        let base_den = harmonics.iter().fold(1, |acc, h| lcm(acc, h.den));
        Ok(Self {
            harmonics,
            base_den,
        })
    }

    /// Integer harmonics `1, 2, …, order` of `ω` (the classic single-frequency basis).
    pub fn integer(order: u32) -> Result<Self, BasisError> {
        if order == 0 {
            return Err(BasisError::ZeroOrder(order));
        }
        Self::new((1..=order).map(|k| Ratio { num: k, den: 1 }).collect())
    }

    /// The paper's basis (Eq. 34) for truncation order `k` and speed ratio `λ = p/q`:
    /// `ω/2, λω/2, ω, λω, 2ω, 2λω, …, kω, kλω` (duplicates, which occur only for
    /// special λ, are dropped).
    pub fn paper(order: u32, lambda: Ratio) -> Result<Self, BasisError> {
        if order == 0 {
            return Err(BasisError::ZeroOrder(order));
        }
        let mut list: Vec<Ratio> = Vec::new();
        let mut push = |r: Ratio| {
            if !list.contains(&r) {
                list.push(r);
            }
        };
        push(Ratio::new(1, 2)?);
        push(Ratio::new(lambda.num, 2 * lambda.den)?);
        for k in 1..=order {
            push(Ratio::new(k, 1)?);
            push(Ratio::new(k * lambda.num, lambda.den)?);
        }
        Self::new(list)
    }

    /// The harmonic ratios `ν_h`, `h = 1..=H`.
    pub fn harmonics(&self) -> &[Ratio] {
        &self.harmonics
    }

    /// Number of harmonics `H` (not counting the constant term).
    pub fn n_harmonics(&self) -> usize {
        self.harmonics.len()
    }

    /// Coefficients per DoF: `1 + 2H`.
    pub fn n_coeffs(&self) -> usize {
        1 + 2 * self.harmonics.len()
    }

    /// `q_base`: every harmonic is an integer multiple of `ω / q_base`.
    pub fn base_den(&self) -> u32 {
        self.base_den
    }

    /// Integer multiple `m_h` with `ν_h = m_h / q_base`.
    pub fn integer_multiple(&self, h: usize) -> u32 {
        let r = self.harmonics[h];
        r.num * (self.base_den / r.den)
    }

    /// Largest integer multiple of `ω / q_base` in the basis.
    pub fn max_integer_multiple(&self) -> u32 {
        (0..self.harmonics.len())
            .map(|h| self.integer_multiple(h))
            .max()
            .unwrap_or(0)
    }

    /// Period of the response in physical time for base frequency `omega` (rad/s):
    /// `2π q_base / ω`.
    pub fn period(&self, omega: f64) -> f64 {
        2.0 * std::f64::consts::PI * f64::from(self.base_den) / omega
    }

    /// `(w_h, sin w_h t, cos w_h t)` of every harmonic `h` at time `t` into `out` (resized):
    /// the table [`Basis::eval_with`] reads, so that many coefficient sets evaluated at the
    /// same `t` share one set of `sin_cos` calls.
    pub fn trig_table(&self, omega: f64, t: f64, out: &mut Vec<(f64, f64, f64)>) {
        out.clear();
        out.extend(self.harmonics.iter().map(|r| {
            let w = r.value() * omega;
            let (s, c) = (w * t).sin_cos();
            (w, s, c)
        }));
    }

    /// [`Basis::eval`] with the harmonic values taken from a [`Basis::trig_table`].
    #[inline]
    pub fn eval_with(&self, coeffs: &[f64], trig: &[(f64, f64, f64)]) -> (f64, f64, f64) {
        let nh = trig.len();
        let mut x = coeffs[0];
        let mut v = 0.0;
        let mut a = 0.0;
        for (h, &(w, s, c)) in trig.iter().enumerate() {
            let (ac, bs) = (coeffs[1 + h], coeffs[1 + nh + h]);
            let p = ac * c + bs * s;
            x += p;
            v += w * (-ac * s + bs * c);
            a -= w * w * p;
        }
        (x, v, a)
    }

    /// Evaluates `x(t)`, `ẋ(t)` and `ẍ(t)` of one DoF from its `1 + 2H` coefficients.
    pub fn eval(&self, coeffs: &[f64], omega: f64, t: f64) -> (f64, f64, f64) {
        let nh = self.harmonics.len();
        let mut x = coeffs[0];
        let mut v = 0.0;
        let mut a = 0.0;
        for (h, r) in self.harmonics.iter().enumerate() {
            let w = r.value() * omega;
            let (s, c) = (w * t).sin_cos();
            let (ac, bs) = (coeffs[1 + h], coeffs[1 + nh + h]);
            x += ac * c + bs * s;
            v += w * (-ac * s + bs * c);
            a -= w * w * (ac * c + bs * s);
        }
        (x, v, a)
    }
}

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

fn lcm(a: u32, b: u32) -> u32 {
    a / gcd(a, b) * b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_basis_order_three_has_eight_frequencies_and_period_20pi() {
        let lambda = Ratio::new(6, 5).expect("valid ratio");
        let b = Basis::paper(3, lambda).expect("valid basis");
        assert_eq!(b.n_harmonics(), 8);
        assert_eq!(b.n_coeffs(), 17);
        assert_eq!(b.base_den(), 10);
        let expected = [5, 6, 10, 12, 20, 24, 30, 36];
        let got: Vec<u32> = (0..8).map(|h| b.integer_multiple(h)).collect();
        assert_eq!(got, expected);
        // period in τ = ω t is 20π
        assert!((b.period(1.0) - 20.0 * std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn eval_matches_closed_form_and_derivatives() {
        let b = Basis::integer(2).expect("valid basis");
        // x = 1 + 2 cos(ωt) + 3 sin(2ωt)
        let c = [1.0, 2.0, 0.0, 0.0, 3.0];
        let (w, t) = (1.7, 0.3);
        let (x, v, a) = b.eval(&c, w, t);
        assert!((x - (1.0 + 2.0 * (w * t).cos() + 3.0 * (2.0 * w * t).sin())).abs() < 1e-14);
        assert!((v - (-2.0 * w * (w * t).sin() + 6.0 * w * (2.0 * w * t).cos())).abs() < 1e-13);
        let a_ref = -2.0 * w * w * (w * t).cos() - 12.0 * w * w * (2.0 * w * t).sin();
        assert!((a - a_ref).abs() < 1e-12);
        let mut trig = Vec::new();
        b.trig_table(w, t, &mut trig);
        let (xt, vt, at) = b.eval_with(&c, &trig);
        assert!((xt - x).abs() < 1e-14 && (vt - v).abs() < 1e-13 && (at - a).abs() < 1e-12);
    }

    #[test]
    fn duplicates_and_zero_are_rejected() {
        let r = Ratio::new(1, 1).expect("valid");
        assert!(matches!(
            Basis::new(vec![r, r]),
            Err(BasisError::Duplicate { .. })
        ));
        assert!(Ratio::new(0, 3).is_err());
        assert_eq!(Ratio::new(4, 2).expect("valid"), Ratio { num: 2, den: 1 });
    }

    #[test]
    fn rational_approximation_rejects_irrational_looking_input() {
        assert_eq!(
            Ratio::approximate(1.2, 1000),
            Some(Ratio { num: 6, den: 5 })
        );
        assert_eq!(Ratio::approximate(std::f64::consts::SQRT_2, 100), None);
    }
}
