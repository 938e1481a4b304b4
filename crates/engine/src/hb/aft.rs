//! Alternating frequency–time (AFT) transforms between harmonic coefficients and time
//! samples over one full period (paper Eq. 28: the Fourier coefficients `η` of the
//! nonlinear forces and of their derivatives are obtained by DFT/IDFT).
//!
//! With base frequency `Ω_b = ω / q_base` (see [`Basis`]) the response is periodic with
//! period `P = 2π / Ω_b`. Samples are taken at `t_j = j P / N`, `j = 0..N`, so harmonic
//! `h` with integer multiple `m_h` reads `cos(2π m_h j / N)` at sample `j`. The forward
//! map (coefficients → samples) is an inverse FFT of a Hermitian spectrum; the backward
//! map (samples → coefficients) is the discrete Galerkin projection
//!
//! ```text
//!   a_0 = (1/N) Σ_j y_j,   a_h = (2/N) Σ_j y_j cos(2π m_h j/N),   b_h = (2/N) Σ_j y_j sin(2π m_h j/N)
//! ```
//!
//! computed by a forward FFT. The Jacobian of a pointwise product `d(t)·x(t)` is built
//! from the spectrum `D_k = (1/N) Σ_j d_j e^{−2πi k j/N}` of the derivative samples by the
//! product-to-sum formulas ([`Aft::add_product_block`]); it is the exact derivative of the
//! discrete AFT residual, aliasing included.
//!
//! ## Sample count
//!
//! Default: the smallest power of two that is at least `4·(m_max + 1)` and at least 64,
//! where `m_max` is the largest integer multiple in the basis. Any `N > 2 m_max` projects a
//! polynomial force of degree 1 without aliasing; a cubic force needs `N > 4 m_max`
//! ([`Aft::new`] enforces `N > 2 m_max`). Hertzian contact with clearance
//! (`δ^{3/2} H(δ)`) is not smooth: its spectrum decays only algebraically, so harmonics
//! above `N/2` fold back onto the retained ones. The factor 4 and the floor of 64 keep that
//! aliasing error well below the truncation error of the basis itself; a power of two
//! keeps the FFT at its fastest.

use std::sync::Arc;

use num_complex::Complex64;
use rustfft::{Fft, FftPlanner};
use thiserror::Error;

use super::basis::Basis;

/// Errors of the AFT settings.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum AftError {
    #[error(
        "AFT sample count {n_samples} is too small for the basis: need more than {min} (2 × the largest integer multiple {max_multiple})"
    )]
    TooFewSamples {
        n_samples: usize,
        min: usize,
        max_multiple: u32,
    },
}

/// Which time signal of a column DoF a pointwise derivative multiplies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    /// The value `x(t)` (or `T(t)`).
    Value,
    /// The physical-time derivative `ẋ(t)`.
    Rate,
}

/// Precomputed FFT plans and harmonic layout for one basis and sample count.
#[derive(Clone)]
pub struct Aft {
    basis: Basis,
    n: usize,
    multiples: Vec<usize>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
}

impl std::fmt::Debug for Aft {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Aft")
            .field("n_samples", &self.n)
            .field("multiples", &self.multiples)
            .finish()
    }
}

impl Aft {
    /// Default sample count for `basis` (see the module docs for the reason).
    pub fn default_samples(basis: &Basis) -> usize {
        let m = basis.max_integer_multiple() as usize;
        (4 * (m + 1)).max(64).next_power_of_two()
    }

    /// AFT for `basis` with `n_samples` samples per period (`None`: the default).
    pub fn new(basis: &Basis, n_samples: Option<usize>) -> Result<Self, AftError> {
        let n = n_samples.unwrap_or_else(|| Self::default_samples(basis));
        let m = basis.max_integer_multiple();
        if n <= 2 * m as usize {
            return Err(AftError::TooFewSamples {
                n_samples: n,
                min: 2 * m as usize,
                max_multiple: m,
            });
        }
        let mut planner = FftPlanner::new();
        Ok(Self {
            basis: basis.clone(),
            n,
            multiples: (0..basis.n_harmonics())
                .map(|h| basis.integer_multiple(h) as usize)
                .collect(),
            fwd: planner.plan_fft_forward(n),
            inv: planner.plan_fft_inverse(n),
        })
    }

    /// The basis.
    pub fn basis(&self) -> &Basis {
        &self.basis
    }

    /// The integer multiple `m_h` of the base frequency of each harmonic `h`.
    pub fn multiples(&self) -> &[usize] {
        &self.multiples
    }

    /// Samples per period `N`.
    pub fn n_samples(&self) -> usize {
        self.n
    }

    /// Sample instant `t_j = j P / N` in physical time for base frequency `omega`.
    pub fn time(&self, omega: f64, j: usize) -> f64 {
        self.basis.period(omega) * j as f64 / self.n as f64
    }

    /// Base angular frequency `Ω_b = ω / q_base` (rad/s).
    pub fn base_frequency(&self, omega: f64) -> f64 {
        omega / f64::from(self.basis.base_den())
    }

    /// Coefficients of the time derivative `ẋ` of a DoF with coefficients `coeffs`:
    /// `a_h' = w_h b_h`, `b_h' = −w_h a_h`, `w_h = m_h Ω_b`.
    pub fn derivative_coeffs(&self, coeffs: &[f64], omega: f64, out: &mut [f64]) {
        let nh = self.multiples.len();
        let wb = self.base_frequency(omega);
        out[0] = 0.0;
        for (h, &m) in self.multiples.iter().enumerate() {
            let w = m as f64 * wb;
            out[1 + h] = w * coeffs[1 + nh + h];
            out[1 + nh + h] = -w * coeffs[1 + h];
        }
    }

    /// Time samples `y_j`, `j = 0..N`, of a DoF with coefficients `coeffs`.
    pub fn synthesize(&self, coeffs: &[f64], samples: &mut [f64], buf: &mut Vec<Complex64>) {
        let nh = self.multiples.len();
        buf.clear();
        buf.resize(self.n, Complex64::new(0.0, 0.0));
        buf[0] = Complex64::new(coeffs[0], 0.0);
        for (h, &m) in self.multiples.iter().enumerate() {
            let (a, b) = (coeffs[1 + h], coeffs[1 + nh + h]);
            buf[m] += Complex64::new(0.5 * a, -0.5 * b);
            buf[self.n - m] += Complex64::new(0.5 * a, 0.5 * b);
        }
        self.inv.process(buf);
        for (s, c) in samples.iter_mut().zip(buf.iter()) {
            *s = c.re;
        }
    }

    /// Normalised spectrum `D_k = (1/N) Σ_j y_j e^{−2πi k j/N}`, `k = 0..N`.
    pub fn spectrum(&self, samples: &[f64], buf: &mut Vec<Complex64>) {
        let inv_n = 1.0 / self.n as f64;
        buf.clear();
        buf.extend(samples.iter().map(|&y| Complex64::new(y * inv_n, 0.0)));
        self.fwd.process(buf);
    }

    /// Galerkin projection of samples onto the basis, written to `out`
    /// (`1 + 2H` coefficients); `buf` receives the spectrum.
    pub fn project(&self, samples: &[f64], out: &mut [f64], buf: &mut Vec<Complex64>) {
        self.spectrum(samples, buf);
        self.project_spectrum(buf, out);
    }

    /// The basis coefficients (`1 + 2H`, into `out`) of a series with normalised spectrum
    /// `spec` ([`Aft::spectrum`], or [`super::EventNodes::spectrum`]).
    pub fn project_spectrum(&self, buf: &[Complex64], out: &mut [f64]) {
        let nh = self.multiples.len();
        out[0] = buf[0].re;
        for (h, &m) in self.multiples.iter().enumerate() {
            out[1 + h] = 2.0 * buf[m].re;
            out[1 + nh + h] = -2.0 * buf[m].im;
        }
    }

    /// `C(k) = (1/N) Σ d_j cos(2πkj/N)` for any integer `k`.
    #[inline]
    fn c_of(&self, spec: &[Complex64], k: isize) -> f64 {
        spec[k.unsigned_abs() % self.n].re
    }

    /// `S(k) = (1/N) Σ d_j sin(2πkj/N)` for any integer `k` (odd in `k`).
    #[inline]
    fn s_of(&self, spec: &[Complex64], k: isize) -> f64 {
        let v = -spec[k.unsigned_abs() % self.n].im;
        if k < 0 { -v } else { v }
    }

    /// Adds `scale ·` (Jacobian of the projection of `d(t)·s(t)` with respect to the
    /// coefficients of the column DoF) into the `(1+2H) × (1+2H)` block at `block`
    /// (row-major with leading dimension `ld`), where `spec` is the spectrum of the samples
    /// of `d` ([`Aft::spectrum`]) and `s` is the column DoF's value or rate.
    pub fn add_product_block(
        &self,
        spec: &[Complex64],
        signal: Signal,
        omega: f64,
        scale: f64,
        block: &mut [f64],
        ld: usize,
    ) {
        let nh = self.multiples.len();
        // harmonic index -> (integer multiple, row weight); index 0 is the constant term
        let mult = |i: usize| -> isize {
            if i == 0 {
                0
            } else {
                self.multiples[i - 1] as isize
            }
        };
        // value of the projection onto row function (cos r or sin r) of d·(cos m or sin m)
        let cc = |r: isize, m: isize| self.c_of(spec, m - r) + self.c_of(spec, m + r);
        let cs = |r: isize, m: isize| self.s_of(spec, m + r) + self.s_of(spec, m - r); // row cos, col sin
        let sc = |r: isize, m: isize| self.s_of(spec, m + r) + self.s_of(spec, r - m); // row sin, col cos
        let ss = |r: isize, m: isize| self.c_of(spec, m - r) - self.c_of(spec, m + r);
        let wb = self.base_frequency(omega);
        for ri in 0..=nh {
            let r = mult(ri);
            // row weight: 1 for the mean (a0 row), 2 for the others; formulas above carry 2
            let wr = if ri == 0 { 0.5 } else { 1.0 };
            for ci in 0..=nh {
                let m = mult(ci);
                // Jacobian of row (cos r) / (sin r) w.r.t. the column's a_m and b_m
                let (mut d_cos_a, mut d_cos_b, mut d_sin_a, mut d_sin_b) = match signal {
                    Signal::Value => (
                        cc(r, m),
                        if ci == 0 { 0.0 } else { cs(r, m) },
                        sc(r, m),
                        if ci == 0 { 0.0 } else { ss(r, m) },
                    ),
                    Signal::Rate => {
                        // d/dt (a cos mφ) = −a m Ω_b sin mφ ; d/dt (b sin mφ) = b m Ω_b cos mφ
                        let w = m as f64 * wb;
                        (-w * cs(r, m), w * cc(r, m), -w * ss(r, m), w * sc(r, m))
                    }
                };
                d_cos_a *= wr * scale;
                d_cos_b *= wr * scale;
                d_sin_a *= scale;
                d_sin_b *= scale;
                let row_c = if ri == 0 { 0 } else { ri };
                let col_a = if ci == 0 { 0 } else { ci };
                block[row_c * ld + col_a] += d_cos_a;
                if ci > 0 {
                    block[row_c * ld + nh + ci] += d_cos_b;
                }
                if ri > 0 {
                    block[(nh + ri) * ld + col_a] += d_sin_a;
                    if ci > 0 {
                        block[(nh + ri) * ld + nh + ci] += d_sin_b;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hb::basis::Ratio;

    #[test]
    fn default_sample_count_is_power_of_two_with_margin() {
        let b = Basis::paper(3, Ratio::new(6, 5).expect("ratio")).expect("basis");
        // largest multiple 36 → 4·37 = 148 → 256
        assert_eq!(Aft::default_samples(&b), 256);
        let b1 = Basis::integer(1).expect("basis");
        assert_eq!(Aft::default_samples(&b1), 64);
        assert!(Aft::new(&b, Some(72)).is_err());
        assert!(Aft::new(&b, Some(73)).is_ok());
    }

    #[test]
    fn synthesis_matches_basis_eval_and_projection_inverts_it() {
        let b = Basis::paper(2, Ratio::new(6, 5).expect("ratio")).expect("basis");
        let aft = Aft::new(&b, None).expect("aft");
        let nc = b.n_coeffs();
        let coeffs: Vec<f64> = (0..nc).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
        let omega = 3.3;
        let mut x = vec![0.0; aft.n_samples()];
        let mut buf = Vec::new();
        aft.synthesize(&coeffs, &mut x, &mut buf);
        for (j, xj) in x.iter().enumerate() {
            let (xr, _, _) = b.eval(&coeffs, omega, aft.time(omega, j));
            assert!((xj - xr).abs() < 1e-12, "sample {j}: {xj} vs {xr}");
        }
        let mut back = vec![0.0; nc];
        aft.project(&x, &mut back, &mut buf);
        for (a, c) in back.iter().zip(&coeffs) {
            assert!((a - c).abs() < 1e-12);
        }
    }

    /// Aliasing: x = cos φ; x³ = (3 cos φ + cos 3φ)/4, x⁵ = (10 cos φ + 5 cos 3φ + cos 5φ)/16.
    /// With basis {1, 2, 3} the projection of x⁵ must give 10/16 on the first harmonic. With
    /// N = 8 samples the 5th harmonic folds onto the 3rd (8 − 5 = 3) and the 7th would fold
    /// onto the 1st; with the default N it must be exact.
    #[test]
    fn aliasing_appears_with_too_few_samples_and_not_with_the_default() {
        let b = Basis::integer(3).expect("basis");
        let coeffs = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let project_pow5 = |aft: &Aft| {
            let mut x = vec![0.0; aft.n_samples()];
            let mut buf = Vec::new();
            aft.synthesize(&coeffs, &mut x, &mut buf);
            let y: Vec<f64> = x.iter().map(|v| v.powi(5)).collect();
            let mut out = vec![0.0; 7];
            aft.project(&y, &mut out, &mut buf);
            out
        };
        let exact = project_pow5(&Aft::new(&b, None).expect("aft"));
        assert!((exact[1] - 10.0 / 16.0).abs() < 1e-14);
        assert!((exact[3] - 5.0 / 16.0).abs() < 1e-14);
        let aliased = project_pow5(&Aft::new(&b, Some(8)).expect("aft"));
        // the cos 5φ component (1/16) folds onto cos 3φ at N = 8
        assert!((aliased[3] - 6.0 / 16.0).abs() < 1e-14, "{}", aliased[3]);
    }
}
