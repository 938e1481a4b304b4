//! Explicit Runge–Kutta integrators: adaptive Dormand–Prince 5(4) and classical RK4.
//!
//! Dormand–Prince 5(4) (J. R. Dormand, P. J. Prince, "A family of embedded Runge–Kutta
//! formulae", J. Comput. Appl. Math. 6 (1980) 19–26; tableau as in E. Hairer, S. P. Nørsett,
//! G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer 1993,
//! Table II.5.2): seven stages, first-same-as-last, the 5th-order solution propagated
//! (local extrapolation), the embedded 4th-order one used for the error estimate.
//! Step control: `err = ‖e_i / (atol + rtol·max(|y0_i|, |y1_i|))‖_rms`, new step
//! `h·min(5, max(0.2, 0.9·err^(−1/5)))`, step rejected when `err > 1`.
//!
//! Output: [`Dopri5::integrate`] stops exactly at the requested end time (the last step is
//! shortened), so samples at prescribed instants carry the full 5th-order accuracy; between
//! steps [`Dopri5::integrate_observed`] hands each accepted step to an observer together
//! with a cubic Hermite interpolant ([`HermiteStep`]) built from the end values and slopes
//! (local error `O(h⁴)`), dense enough for plotting and event location.

use super::IntegrateError;

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order weights minus 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

/// Settings of [`Dopri5`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dopri5Options {
    /// Relative tolerance. Default 1e-10: the integrator is a reference for amplitudes
    /// compared at 1e-4 relative and multipliers compared at 1e-6, so it must be far
    /// tighter than both.
    pub rtol: f64,
    /// Absolute tolerance. Default 1e-12 (states of order 1e-3..1 in the reference
    /// problems; scale it with the problem for physical units).
    pub atol: f64,
    /// First trial step; `None` picks `0.01·|t1 − t0|` bounded by `h_max`.
    pub h_init: Option<f64>,
    /// Largest step. Default: unbounded.
    pub h_max: f64,
    /// Budget of steps (accepted + rejected) per call. Default 10⁷.
    pub max_steps: usize,
}

impl Default for Dopri5Options {
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            atol: 1e-12,
            h_init: None,
            h_max: f64::INFINITY,
            max_steps: 10_000_000,
        }
    }
}

/// Counters of a [`Dopri5`] run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dopri5Stats {
    pub accepted: usize,
    pub rejected: usize,
    pub rhs_evals: usize,
}

/// One accepted step with its cubic Hermite interpolant.
pub struct HermiteStep<'s> {
    pub t0: f64,
    pub t1: f64,
    pub y0: &'s [f64],
    pub f0: &'s [f64],
    pub y1: &'s [f64],
    pub f1: &'s [f64],
}

impl HermiteStep<'_> {
    /// Interpolated state at `t ∈ [t0, t1]`.
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        let h = self.t1 - self.t0;
        let s = (t - self.t0) / h;
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s * s * (3.0 - 2.0 * s);
        let h11 = s * s * (s - 1.0);
        for i in 0..out.len() {
            out[i] =
                h00 * self.y0[i] + h10 * h * self.f0[i] + h01 * self.y1[i] + h11 * h * self.f1[i];
        }
    }
}

/// Adaptive Dormand–Prince 5(4) integrator with reusable buffers. Consecutive calls that
/// continue from where the last one stopped reuse the step size and the FSAL stage.
pub struct Dopri5 {
    opts: Dopri5Options,
    k: [Vec<f64>; 7],
    ystage: Vec<f64>,
    ynew: Vec<f64>,
    h: Option<f64>,
    /// Time at which `k[0]` holds `f(t, y)` for the state left by the last call.
    fsal_t: Option<f64>,
    /// That state, so a call from a different state at the same time re-evaluates.
    fsal_y: Vec<f64>,
    pub stats: Dopri5Stats,
}

impl Dopri5 {
    /// An integrator for states of length `dim`.
    pub fn new(dim: usize, opts: Dopri5Options) -> Self {
        Self {
            opts,
            k: std::array::from_fn(|_| vec![0.0; dim]),
            ystage: vec![0.0; dim],
            ynew: vec![0.0; dim],
            h: None,
            fsal_t: None,
            fsal_y: vec![0.0; dim],
            stats: Dopri5Stats::default(),
        }
    }

    /// Settings in use.
    pub fn options(&self) -> &Dopri5Options {
        &self.opts
    }

    /// Integrates `ẏ = f(t, y)` from `t0` to `t1` (`t1 > t0`), overwriting `y`.
    pub fn integrate<F>(
        &mut self,
        f: &mut F,
        t0: f64,
        y: &mut [f64],
        t1: f64,
    ) -> Result<(), IntegrateError>
    where
        F: FnMut(f64, &[f64], &mut [f64]),
    {
        self.integrate_observed(f, t0, y, t1, &mut |_| {})
    }

    /// As [`Dopri5::integrate`], calling `observer` after every accepted step.
    pub fn integrate_observed<F, O>(
        &mut self,
        f: &mut F,
        t0: f64,
        y: &mut [f64],
        t1: f64,
        observer: &mut O,
    ) -> Result<(), IntegrateError>
    where
        F: FnMut(f64, &[f64], &mut [f64]),
        O: FnMut(&HermiteStep<'_>),
    {
        let dim = y.len();
        if self.ynew.len() != dim {
            return Err(IntegrateError::Dimension {
                what: "integrator state",
                expected: self.ynew.len(),
                found: dim,
            });
        }
        if t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater)
            || !t0.is_finite()
            || !t1.is_finite()
        {
            return Err(IntegrateError::Interval { t0, t1 });
        }
        let span = t1 - t0;
        let o = self.opts;
        let mut h = self
            .h
            .or(o.h_init)
            .unwrap_or(0.01 * span)
            .min(o.h_max)
            .min(span);
        if self.fsal_t != Some(t0) || self.fsal_y != y {
            f(t0, y, &mut self.k[0]);
            self.stats.rhs_evals += 1;
        }
        let mut t = t0;
        let mut steps = 0usize;
        while t < t1 {
            if steps >= o.max_steps {
                return Err(IntegrateError::StepBudget {
                    steps,
                    t,
                    t_end: t1,
                });
            }
            steps += 1;
            let last = t + h >= t1 - 1e-14 * span.max(t1.abs());
            let h_try = if last { t1 - t } else { h };
            self.stages(f, t, y, h_try);
            let err = self.error_norm(y, h_try);
            if !err.is_finite() {
                return Err(IntegrateError::NonFinite { t });
            }
            let fac = if err == 0.0 {
                5.0
            } else {
                (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
            };
            if err <= 1.0 {
                self.stats.accepted += 1;
                let t_new = if last { t1 } else { t + h_try };
                {
                    let step = HermiteStep {
                        t0: t,
                        t1: t_new,
                        y0: y,
                        f0: &self.k[0],
                        y1: &self.ynew,
                        f1: &self.k[6],
                    };
                    observer(&step);
                }
                y.copy_from_slice(&self.ynew);
                self.k.swap(0, 6);
                t = t_new;
                // Keep the controller's step, not the shortened last one.
                if !last || h_try >= h {
                    h = (h_try * fac).min(o.h_max);
                }
            } else {
                self.stats.rejected += 1;
                h = h_try * fac.min(1.0);
                if h < 1e-14 * t.abs().max(span) {
                    return Err(IntegrateError::StepUnderflow { t, h });
                }
            }
        }
        self.h = Some(h);
        self.fsal_t = Some(t1);
        self.fsal_y.copy_from_slice(y);
        Ok(())
    }

    /// Forgets the step size and FSAL stage (call before integrating a different
    /// right-hand side; a new start state is detected automatically).
    pub fn reset(&mut self) {
        self.h = None;
        self.fsal_t = None;
    }

    fn stages<F>(&mut self, f: &mut F, t: f64, y: &[f64], h: f64)
    where
        F: FnMut(f64, &[f64], &mut [f64]),
    {
        let dim = y.len();
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;
        let ys = &mut self.ystage;
        for i in 0..dim {
            ys[i] = y[i] + h * A21 * k1[i];
        }
        f(t + C2 * h, ys, k2);
        for i in 0..dim {
            ys[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
        }
        f(t + C3 * h, ys, k3);
        for i in 0..dim {
            ys[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        f(t + C4 * h, ys, k4);
        for i in 0..dim {
            ys[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        f(t + C5 * h, ys, k5);
        for i in 0..dim {
            ys[i] =
                y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        f(t + h, ys, k6);
        let yn = &mut self.ynew;
        for i in 0..dim {
            yn[i] =
                y[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
        }
        f(t + h, yn, k7);
        self.stats.rhs_evals += 6;
    }

    fn error_norm(&self, y: &[f64], h: f64) -> f64 {
        let [k1, _, k3, k4, k5, k6, k7] = &self.k;
        let dim = y.len();
        let mut sum = 0.0;
        for i in 0..dim {
            let e =
                h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
            let sc = self.opts.atol + self.opts.rtol * y[i].abs().max(self.ynew[i].abs());
            sum += (e / sc) * (e / sc);
        }
        (sum / dim.max(1) as f64).sqrt()
    }
}

/// Classical fixed-step Runge–Kutta 4 from `t0` to `t1` in `steps` equal steps,
/// overwriting `y`. For cross-checks and problems where a fixed sampling is wanted.
pub fn rk4<F>(f: &mut F, t0: f64, y: &mut [f64], t1: f64, steps: usize)
where
    F: FnMut(f64, &[f64], &mut [f64]),
{
    let dim = y.len();
    let steps = steps.max(1);
    let h = (t1 - t0) / steps as f64;
    let (mut k1, mut k2, mut k3, mut k4) = (
        vec![0.0; dim],
        vec![0.0; dim],
        vec![0.0; dim],
        vec![0.0; dim],
    );
    let mut ys = vec![0.0; dim];
    for s in 0..steps {
        let t = t0 + s as f64 * h;
        f(t, y, &mut k1);
        for i in 0..dim {
            ys[i] = y[i] + 0.5 * h * k1[i];
        }
        f(t + 0.5 * h, &ys, &mut k2);
        for i in 0..dim {
            ys[i] = y[i] + 0.5 * h * k2[i];
        }
        f(t + 0.5 * h, &ys, &mut k3);
        for i in 0..dim {
            ys[i] = y[i] + h * k3[i];
        }
        f(t + h, &ys, &mut k4);
        for i in 0..dim {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ẏ = −y + sin t, exact y = (y0 + 1/2) e^{−t} + (sin t − cos t)/2.
    fn exact(t: f64, y0: f64) -> f64 {
        (y0 + 0.5) * (-t).exp() + 0.5 * (t.sin() - t.cos())
    }

    #[test]
    fn dopri_meets_tolerance_on_a_forced_linear_ode() {
        let mut f = |t: f64, y: &[f64], dy: &mut [f64]| dy[0] = -y[0] + t.sin();
        for rtol in [1e-6, 1e-9, 1e-12] {
            let mut solver = Dopri5::new(
                1,
                Dopri5Options {
                    rtol,
                    atol: rtol,
                    ..Default::default()
                },
            );
            let mut y = [2.0];
            solver
                .integrate(&mut f, 0.0, &mut y, 10.0)
                .expect("integration succeeds");
            let err = (y[0] - exact(10.0, 2.0)).abs();
            assert!(err < 100.0 * rtol, "rtol {rtol}: error {err}");
        }
    }

    #[test]
    fn dopri_is_fifth_order_with_fixed_steps() {
        // Fixed steps (huge tolerance, h_max) on the harmonic oscillator: halving h must
        // reduce the error by about 2^5.
        let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -y[0];
        };
        let mut errs = vec![];
        for h in [0.2, 0.1] {
            let mut solver = Dopri5::new(
                2,
                Dopri5Options {
                    rtol: 1e3,
                    atol: 1e3,
                    h_init: Some(h),
                    h_max: h,
                    ..Default::default()
                },
            );
            let mut y = [1.0, 0.0];
            solver
                .integrate(&mut f, 0.0, &mut y, 4.0)
                .expect("integration succeeds");
            errs.push((y[0] - 4.0f64.cos()).hypot(y[1] + 4.0f64.sin()));
        }
        let ratio = errs[0] / errs[1];
        assert!(
            ratio > 25.0 && ratio < 40.0,
            "ratio {ratio}, errors {errs:?}"
        );
    }

    #[test]
    fn rk4_is_fourth_order() {
        let mut f = |t: f64, y: &[f64], dy: &mut [f64]| dy[0] = -y[0] + t.sin();
        let mut errs = vec![];
        for steps in [50, 100] {
            let mut y = [2.0];
            rk4(&mut f, 0.0, &mut y, 5.0, steps);
            errs.push((y[0] - exact(5.0, 2.0)).abs());
        }
        let ratio = errs[0] / errs[1];
        assert!(ratio > 14.0 && ratio < 18.0, "ratio {ratio}");
    }

    #[test]
    fn hermite_output_interpolates_between_steps() {
        let mut f = |t: f64, y: &[f64], dy: &mut [f64]| dy[0] = -y[0] + t.sin();
        let mut solver = Dopri5::new(1, Dopri5Options::default());
        let mut y = [2.0];
        let mut worst: f64 = 0.0;
        let mut out = [0.0];
        solver
            .integrate_observed(&mut f, 0.0, &mut y, 6.0, &mut |s: &HermiteStep<'_>| {
                let tm = 0.5 * (s.t0 + s.t1);
                s.eval(tm, &mut out);
                worst = worst.max((out[0] - exact(tm, 2.0)).abs());
            })
            .expect("integration succeeds");
        assert!(worst < 1e-6, "worst interpolation error {worst}");
    }
}
