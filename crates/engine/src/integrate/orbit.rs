//! A [`PeriodicOrbit`] from uniformly sampled states, by trigonometric interpolation.
//!
//! From `N` samples `y_j = y(t₀ + jP/N)` the real discrete Fourier coefficients
//! `a_k = (2/N) Σ_j y_j cos(2πjk/N)`, `b_k = (2/N) Σ_j y_j sin(2πjk/N)` (`a_0` and the
//! Nyquist term for even `N` with weight 1/N) define the unique trigonometric polynomial of
//! degree `⌊N/2⌋` through the samples. For a smooth (analytic) periodic orbit it converges
//! exponentially in `N`, so 256 samples reproduce the reference orbits to round-off; for
//! non-smooth orbits (contact) it converges algebraically and should be fed more samples.

use crate::system::PeriodicOrbit;

/// A periodic orbit given by `N` uniform samples of the full state `[x, v, T]` over one
/// period, evaluated between samples by trigonometric interpolation.
#[derive(Clone, Debug)]
pub struct SampledOrbit {
    omega: f64,
    period: f64,
    /// Time of sample 0.
    t0: f64,
    n_mech: usize,
    n_therm: usize,
    /// Cosine coefficients, `a[k * dim + i]`, k = 0..=kmax.
    a: Vec<f64>,
    /// Sine coefficients, same layout.
    b: Vec<f64>,
    kmax: usize,
}

impl SampledOrbit {
    /// Builds the interpolant from `samples[j]` = state at `t0 + j·period/N`
    /// (`N = samples.len() ≥ 1`, each of length `2 n_mech + n_therm`).
    ///
    /// # Panics
    /// When `samples` is empty or a sample has the wrong length (programming errors: the
    /// samples come from [`super::steady_state`] or from test code).
    pub fn new(
        omega: f64,
        period: f64,
        t0: f64,
        n_mech: usize,
        n_therm: usize,
        samples: &[Vec<f64>],
    ) -> Self {
        let dim = 2 * n_mech + n_therm;
        let nsamp = samples.len();
        assert!(nsamp > 0, "SampledOrbit needs at least one sample");
        assert!(
            samples.iter().all(|s| s.len() == dim),
            "SampledOrbit sample length must be 2 n_mech + n_therm = {dim}"
        );
        let kmax = nsamp / 2;
        let mut a = vec![0.0; (kmax + 1) * dim];
        let mut b = vec![0.0; (kmax + 1) * dim];
        for k in 0..=kmax {
            let nyquist = nsamp.is_multiple_of(2) && k == kmax;
            let w = if k == 0 || nyquist { 1.0 } else { 2.0 } / nsamp as f64;
            for (j, y) in samples.iter().enumerate() {
                // Reduce jk mod N first so the angle stays small and exact.
                let phase = 2.0 * std::f64::consts::PI * ((j * k) % nsamp) as f64 / nsamp as f64;
                let (s, c) = phase.sin_cos();
                for i in 0..dim {
                    a[k * dim + i] += w * c * y[i];
                    if !nyquist && k > 0 {
                        b[k * dim + i] += w * s * y[i];
                    }
                }
            }
        }
        Self {
            omega,
            period,
            t0,
            n_mech,
            n_therm,
            a,
            b,
            kmax,
        }
    }

    /// Full state `[x, v, T]` at time `t` into `out`.
    pub fn state_into(&self, t: f64, out: &mut [f64]) {
        let dim = 2 * self.n_mech + self.n_therm;
        let theta = 2.0 * std::f64::consts::PI * ((t - self.t0) / self.period).rem_euclid(1.0);
        let (s1, c1) = theta.sin_cos();
        out[..dim].copy_from_slice(&self.a[..dim]);
        let (mut ck, mut sk) = (1.0, 0.0);
        for k in 1..=self.kmax {
            // Rotate (cos kθ, sin kθ) by θ.
            let c_new = ck * c1 - sk * s1;
            sk = sk * c1 + ck * s1;
            ck = c_new;
            let (ak, bk) = (
                &self.a[k * dim..(k + 1) * dim],
                &self.b[k * dim..(k + 1) * dim],
            );
            for i in 0..dim {
                out[i] += ak[i] * ck + bk[i] * sk;
            }
        }
    }

    /// Number of mechanical DoFs.
    pub fn n_mech(&self) -> usize {
        self.n_mech
    }

    /// Number of thermal DoFs.
    pub fn n_therm(&self) -> usize {
        self.n_therm
    }
}

impl PeriodicOrbit for SampledOrbit {
    fn omega(&self) -> f64 {
        self.omega
    }

    fn period(&self) -> f64 {
        self.period
    }

    fn state_at(&self, t: f64, x: &mut [f64], v: &mut [f64], temp: &mut [f64]) {
        let n = self.n_mech;
        let mut y = vec![0.0; 2 * n + self.n_therm];
        self.state_into(t, &mut y);
        x.copy_from_slice(&y[..n]);
        v.copy_from_slice(&y[n..2 * n]);
        temp.copy_from_slice(&y[2 * n..]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trigonometric_interpolation_is_exact_for_band_limited_signals() {
        let period = 3.0;
        let w = 2.0 * std::f64::consts::PI / period;
        let sig = |t: f64| {
            [
                0.3 + (w * t).cos() - 0.2 * (3.0 * w * t).sin(),
                (2.0 * w * t).sin() + 0.1 * (7.0 * w * t).cos(),
            ]
        };
        let n = 32;
        let t0 = 0.7;
        let samples: Vec<Vec<f64>> = (0..n)
            .map(|j| sig(t0 + j as f64 * period / n as f64).to_vec())
            .collect();
        let orbit = SampledOrbit::new(1.0, period, t0, 1, 0, &samples);
        let (mut x, mut v, mut temp) = ([0.0], [0.0], [0.0; 0]);
        for t in [0.0, 0.123, 1.9, 5.55, -2.2] {
            orbit.state_at(t, &mut x, &mut v, &mut temp);
            let e = sig(t);
            assert!((x[0] - e[0]).abs() < 1e-13 && (v[0] - e[1]).abs() < 1e-13);
        }
    }
}
