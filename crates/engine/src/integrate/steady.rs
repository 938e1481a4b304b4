//! Steady-state response by direct integration, and stroboscopic (Poincaré) samples.

use super::{Dopri5, Dopri5Options, IntegrateError, SampledOrbit, StateSpace};
use crate::system::System;

/// Settings of [`steady_state_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteadyStateOptions {
    /// Integrator tolerances (default [`Dopri5Options::default`]).
    pub integrator: Dopri5Options,
    /// Samples over the final period. Default 256: resolves 128 harmonics, far more than
    /// the smooth reference orbits carry, and `max |x|` to ~(π/256)²/2 ≈ 8e-5 relative
    /// from the samples alone (amplitudes are refined by interpolation, see
    /// [`SteadyState::amplitude`]).
    pub samples_per_period: usize,
}

impl Default for SteadyStateOptions {
    fn default() -> Self {
        Self {
            integrator: Dopri5Options::default(),
            samples_per_period: 256,
        }
    }
}

/// One period of a time-integrated response after the transient.
#[derive(Clone, Debug)]
pub struct SteadyState {
    pub omega: f64,
    pub period: f64,
    /// Time of the first sample (an integer number of periods after the start).
    pub t0: f64,
    pub n_mech: usize,
    pub n_therm: usize,
    /// `samples[j]` = full state `[x, v, T]` at `t0 + j·period/N`.
    pub samples: Vec<Vec<f64>>,
    /// `max_i |y_i(t0 + P) − y_i(t0)|`: how far the response is from `P`-periodic (a
    /// converged period-P response gives the integration error; period doubling or
    /// quasi-periodicity give O(amplitude)).
    pub periodicity_error: f64,
}

impl SteadyState {
    /// `max_t |x_dof(t)|` over the period, refined by evaluating the trigonometric
    /// interpolant on a grid 16 times finer than the samples.
    pub fn amplitude(&self, dof: usize) -> f64 {
        let orbit = self.orbit();
        let fine = 16 * self.samples.len();
        let mut y = vec![0.0; 2 * self.n_mech + self.n_therm];
        (0..fine)
            .map(|j| {
                orbit.state_into(self.t0 + j as f64 * self.period / fine as f64, &mut y);
                y[dof].abs()
            })
            .fold(0.0, f64::max)
    }

    /// The samples as a [`PeriodicOrbit`](crate::system::PeriodicOrbit).
    pub fn orbit(&self) -> SampledOrbit {
        SampledOrbit::new(
            self.omega,
            self.period,
            self.t0,
            self.n_mech,
            self.n_therm,
            &self.samples,
        )
    }
}

/// [`steady_state_with`] with default settings.
pub fn steady_state(
    system: &dyn System,
    omega: f64,
    y0: &[f64],
    period: f64,
    settle_periods: usize,
) -> Result<SteadyState, IntegrateError> {
    steady_state_with(
        system,
        omega,
        y0,
        period,
        settle_periods,
        &SteadyStateOptions::default(),
    )
}

/// Integrates `system` at `omega` from the full state `y0 = [x, v, T]` at `t = 0` over
/// `settle_periods` periods, then samples one more period (`period` in s: the period of
/// the forcing, or a multiple of it to capture subharmonic responses).
pub fn steady_state_with(
    system: &dyn System,
    omega: f64,
    y0: &[f64],
    period: f64,
    settle_periods: usize,
    opts: &SteadyStateOptions,
) -> Result<SteadyState, IntegrateError> {
    let space = StateSpace::new(system, omega)?;
    let dim = space.dim();
    check_start(dim, y0, period)?;
    if opts.samples_per_period == 0 {
        return Err(IntegrateError::Setting {
            field: "samples_per_period",
            value: "0".into(),
            reason: "must be at least 1",
        });
    }
    let mut ws = space.workspace();
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| space.rhs(t, y, dy, &mut ws);
    let mut solver = Dopri5::new(dim, opts.integrator);
    let mut y = y0.to_vec();
    let mut t = 0.0;
    for _ in 0..settle_periods {
        solver.integrate(&mut rhs, t, &mut y, t + period)?;
        t += period;
    }
    let t0 = t;
    let nsamp = opts.samples_per_period;
    let mut samples = Vec::with_capacity(nsamp);
    samples.push(y.clone());
    for j in 1..=nsamp {
        let t_next = t0 + j as f64 * period / nsamp as f64;
        solver.integrate(&mut rhs, t, &mut y, t_next)?;
        t = t_next;
        if j < nsamp {
            samples.push(y.clone());
        }
    }
    let periodicity_error = y
        .iter()
        .zip(&samples[0])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    Ok(SteadyState {
        omega,
        period,
        t0,
        n_mech: space.n_mech(),
        n_therm: space.n_therm(),
        samples,
        periodicity_error,
    })
}

/// Stroboscopic samples: integrates from `y0` at `t = 0` over `settle_periods` periods,
/// then returns `count` states `y(t_s + kP)`, `k = 0..count`. A period-`P` response gives
/// identical samples, a period-`2P` response alternating ones, a quasi-periodic one a
/// closed curve.
pub fn poincare_samples(
    system: &dyn System,
    omega: f64,
    y0: &[f64],
    period: f64,
    settle_periods: usize,
    count: usize,
    integrator: &Dopri5Options,
) -> Result<Vec<Vec<f64>>, IntegrateError> {
    let space = StateSpace::new(system, omega)?;
    let dim = space.dim();
    check_start(dim, y0, period)?;
    let mut ws = space.workspace();
    let mut rhs = |t: f64, y: &[f64], dy: &mut [f64]| space.rhs(t, y, dy, &mut ws);
    let mut solver = Dopri5::new(dim, *integrator);
    let mut y = y0.to_vec();
    let mut t = 0.0;
    for _ in 0..settle_periods {
        solver.integrate(&mut rhs, t, &mut y, t + period)?;
        t += period;
    }
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        if k > 0 {
            solver.integrate(&mut rhs, t, &mut y, t + period)?;
            t += period;
        }
        out.push(y.clone());
    }
    Ok(out)
}

pub(super) fn check_start(dim: usize, y0: &[f64], period: f64) -> Result<(), IntegrateError> {
    if y0.len() != dim {
        return Err(IntegrateError::Dimension {
            what: "initial state [x, v, T]",
            expected: dim,
            found: y0.len(),
        });
    }
    if !(period > 0.0 && period.is_finite()) {
        return Err(IntegrateError::Setting {
            field: "period",
            value: period.to_string(),
            reason: "must be positive and finite",
        });
    }
    Ok(())
}
