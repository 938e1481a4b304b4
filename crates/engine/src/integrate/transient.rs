//! Transient response of a [`System`] over a speed profile: the mechanical equations by an
//! implicit HHT-α scheme with local error control, the thermal equations on their own,
//! slower scale from heat averaged over revolutions (a multi-rate scheme).
//!
//! # Why two rates
//! A revolution takes milliseconds; the thermal network's time constants are seconds to
//! hours. The mechanical equations are stiff (the FE rotor's upper modes and the Hertz
//! contacts: an explicit Runge–Kutta method needs about 10⁵ steps per revolution on the
//! built-in dual rotor), so they are integrated implicitly; the thermal equations are slow,
//! so within a *macro step* of `k` revolutions the temperatures are held and the heat the
//! nonlinear terms generate, `g`, and its temperature derivative `∂g/∂T` are averaged over
//! the macro step. The temperatures then advance by one linearly implicit trapezoidal step
//! of the thermal network with those averages. This is exact in the limit of heat that
//! does not change over a macro step, and the error it makes is measured against the
//! single-rate run ([`ThermalStepping::EveryStep`], the temperatures advanced after every
//! mechanical step) in the tests and in docs/transient.md.
//!
//! # Mechanical scheme
//! HHT-α (H. M. Hilber, T. J. R. Hughes, R. L. Taylor, "Improved numerical dissipation for
//! time integration algorithms in structural dynamics", Earthquake Eng. Struct. Dyn. 5
//! (1977) 283–292) with `α = −0.05`, `β = (1 − α)²/4`, `γ = 1/2 − α`: second order,
//! unconditionally stable for linear systems, with a little numerical damping of the
//! unresolved upper modes the contacts excite. The equation of a step is
//!
//! ```text
//!   M a₁ + (1+α)(C v₁ + K x₁ + P f₁ − F₁) − α(C v₀ + K x₀ + P f₀ − F₀) = 0
//! ```
//!
//! with the Newmark updates of `x₁`, `v₁` in `a₁`. In the unknown `x₁` it reads
//! `A x₁ + (1+α) P f(Pᵀx₁) = b` with the constant `A = M/(βh²) + (1+α)(γ/(βh) C + K)`,
//! so Newton runs on the `p` nonlinear DoFs alone (`z = Pᵀx₁`,
//! `z = Pᵀ A⁻¹ b − (1+α) Pᵀ A⁻¹ P f(z)`), and `A` is factored only when the step size or
//! the speed changes. Local error estimate (O. C. Zienkiewicz, Y. M. Xie, "A simple error
//! estimator and adaptive time stepping procedure for dynamic analysis", Earthquake Eng.
//! Struct. Dyn. 20 (1991) 871–887): `e = (β − 1/6) h² (a₁ − a₀)`, with the step size chosen
//! so that `‖e_i / (atol + rtol·|x_i|)‖_rms ≤ 1`.
//!
//! # Speed profile
//! Every time-dependent term of a rotor model depends on time through the rotation angle
//! `φ(t) = ∫ω dt` (unbalance, cage positions, the second rotor at a fixed speed ratio). The
//! system is evaluated at the instantaneous speed `ω(t)` and at the time `φ(t)/ω(t)`, at
//! which `ω t` is the true angle; at a fixed speed this is the system's own time. The
//! unbalance force from the angular acceleration, `m e ω̇`, is left out: its size relative
//! to the centrifugal `m e ω²` is `ω̇/ω²` (4·10⁻⁵ at 10 rad/s² and 500 rad/s). The
//! speed-dependent linear matrices (gyroscopic terms, tabulated supports, convection) are
//! rebuilt whenever the speed has moved by [`TransientOptions::omega_refresh`] relative
//! since they were built.

use std::sync::Arc;

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::IntegrateError;
use crate::system::{DenseMatrix, NonlinearEval, System};

/// Rotor speed over time.
#[derive(Clone, Debug, PartialEq)]
pub enum SpeedProfile {
    /// A fixed speed (rad/s).
    Constant(f64),
    /// From `from` to `to` (rad/s) at a constant acceleration of magnitude `accel`
    /// (rad/s²), held at `to` afterwards: a run-up when `to > from`, a coast-down when
    /// `to < from`.
    Ramp { from: f64, to: f64, accel: f64 },
    /// Piecewise linear through `(t, ω)` pairs (s, rad/s), `t` strictly increasing from 0;
    /// held at the last speed afterwards.
    Table(Vec<(f64, f64)>),
}

impl SpeedProfile {
    /// Checks the profile: speeds finite and positive, accelerations positive, table
    /// times increasing from 0. The error names the entry.
    pub fn check(&self) -> Result<(), IntegrateError> {
        let bad = |field: &'static str, value: f64, reason: &'static str| {
            Err(IntegrateError::Setting {
                field,
                value: format!("{value}"),
                reason,
            })
        };
        let speed_ok = |w: f64| w.is_finite() && w > 0.0;
        match self {
            Self::Constant(w) if !speed_ok(*w) => {
                bad("speed", *w, "a speed must be finite and above 0 rad/s")
            }
            Self::Ramp { from, .. } if !speed_ok(*from) => bad(
                "from",
                *from,
                "the start speed must be finite and above 0 rad/s (the rotation angle's time φ/ω needs ω > 0)",
            ),
            Self::Ramp { to, .. } if !speed_ok(*to) => {
                bad("to", *to, "the end speed must be finite and above 0 rad/s")
            }
            Self::Ramp { accel, .. } if !(accel.is_finite() && *accel > 0.0) => bad(
                "accel",
                *accel,
                "the acceleration's magnitude must be finite and above 0 rad/s² (the sign follows from the speeds)",
            ),
            Self::Table(rows) => {
                if rows.is_empty() {
                    return bad("table", 0.0, "the speed table has no rows");
                }
                if rows[0].0 != 0.0 {
                    return bad("table time", rows[0].0, "the first row must be at t = 0 s");
                }
                for w in rows.windows(2) {
                    if w[1].0 <= w[0].0 || !w[1].0.is_finite() {
                        return bad("table time", w[1].0, "times must increase strictly");
                    }
                }
                for &(_, w) in rows {
                    if !speed_ok(w) {
                        return bad("table speed", w, "speeds must be finite and above 0 rad/s");
                    }
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// The profile's natural end: when a ramp reaches its end speed, the last table time;
    /// `None` for a constant speed.
    pub fn end_time(&self) -> Option<f64> {
        match self {
            Self::Constant(_) => None,
            Self::Ramp { from, to, accel } => Some((to - from).abs() / accel),
            Self::Table(rows) => rows.last().map(|r| r.0),
        }
    }

    /// The simulated time a run of this profile takes unless told otherwise: its natural
    /// end plus 1 s to settle, or 100 revolutions at a constant speed (s).
    pub fn default_duration(&self) -> f64 {
        match self.end_time() {
            Some(t) => t + 1.0,
            None => 100.0 * std::f64::consts::TAU / self.omega(0.0),
        }
    }

    /// Speed at `t` (rad/s).
    pub fn omega(&self, t: f64) -> f64 {
        match self {
            Self::Constant(w) => *w,
            Self::Ramp { from, to, accel } => {
                let t_end = (to - from).abs() / accel;
                let s = t.clamp(0.0, t_end);
                from + (to - from).signum() * accel * s
            }
            Self::Table(rows) => {
                let i = rows.partition_point(|r| r.0 <= t);
                if i == 0 {
                    return rows[0].1;
                }
                if i == rows.len() {
                    return rows[i - 1].1;
                }
                let (t0, w0) = rows[i - 1];
                let (t1, w1) = rows[i];
                w0 + (w1 - w0) * (t - t0) / (t1 - t0)
            }
        }
    }

    /// Rotation angle `φ(t) = ∫₀ᵗ ω dt` (rad), exact for the piecewise linear speed.
    pub fn phase(&self, t: f64) -> f64 {
        match self {
            Self::Constant(w) => w * t,
            Self::Ramp { from, to, accel } => {
                let t_end = (to - from).abs() / accel;
                let s = t.clamp(0.0, t_end);
                let a = (to - from).signum() * accel;
                let ramp = from * s + 0.5 * a * s * s;
                ramp + to * (t - s).max(0.0)
            }
            Self::Table(rows) => {
                let mut phi = 0.0;
                for w in rows.windows(2) {
                    let (t0, w0) = w[0];
                    let (t1, w1) = w[1];
                    if t <= t0 {
                        return phi;
                    }
                    let s = t.min(t1);
                    let ws = w0 + (w1 - w0) * (s - t0) / (t1 - t0);
                    phi += 0.5 * (w0 + ws) * (s - t0);
                    if t <= t1 {
                        return phi;
                    }
                }
                let (tl, wl) = rows[rows.len() - 1];
                phi + wl * (t - tl).max(0.0)
            }
        }
    }
}

/// How the thermal equations are advanced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThermalStepping {
    /// After every mechanical step, with that step's heat (single rate: the reference).
    EveryStep,
    /// After macro steps of whole revolutions, with the heat averaged over them; the
    /// number of revolutions per macro step adapts between 1 and `max_revolutions` so
    /// that the estimated local temperature error stays below `temp_tol` (K) and no
    /// temperature moves by more than `max_temp_step` (K) in one macro step.
    Averaged {
        max_revolutions: u32,
        temp_tol: f64,
        max_temp_step: f64,
    },
}

impl Default for ThermalStepping {
    /// 1 to 50 revolutions a macro step, 1 mK local error, at most 0.05 K a step: a
    /// 0.05 K change moves a bearing clearance by about 0.1 % of the built-in model's
    /// clearances (expansion ≈ 1.2·10⁻⁵/K over radii of a few cm), which the mechanics
    /// sees as a step change; 50 revolutions keep the heat average close to the
    /// revolution it ends at.
    fn default() -> Self {
        Self::Averaged {
            max_revolutions: 50,
            temp_tol: 1e-3,
            max_temp_step: 0.05,
        }
    }
}

/// Settings of [`Transient`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransientOptions {
    /// HHT parameter `α ∈ [−1/3, 0]`. Default −0.05: a little damping of the unresolved
    /// upper modes (spectral radius 0.9 at infinite frequency) at second-order accuracy.
    pub alpha: f64,
    /// Relative tolerance of the local displacement error. Default 1e-6, which keeps the
    /// orbit within 1e-4 relative of the harmonic-balance orbit on the built-in model
    /// (docs/transient.md).
    pub rtol: f64,
    /// Absolute tolerance of the local displacement error (m, or the system's unit).
    /// Default 1e-11.
    pub atol: f64,
    /// Fewest steps per revolution (the per-revolution statistics sample each step).
    /// Default 64.
    pub min_steps_per_revolution: u32,
    /// Rebuild the speed-dependent matrices when `|ω − ω_built| > omega_refresh·ω_built`.
    /// Default 1e-4: a 0.01 % error in the gyroscopic and support terms.
    pub omega_refresh: f64,
    /// Newton tolerance on the nonlinear DoFs, relative to their size. Default 1e-10.
    pub newton_tol: f64,
    /// Newton iterations before a step is retried smaller. Default 12.
    pub max_newton: usize,
    /// Thermal stepping; see [`ThermalStepping`].
    pub thermal: ThermalStepping,
    /// Step budget (accepted and rejected) per call of [`Transient::advance`]. Default 10⁸.
    pub max_steps: u64,
}

impl TransientOptions {
    /// Checks the settings as an integration would before it starts, so that a caller
    /// can refuse them before it opens its outputs.
    pub fn check(&self) -> Result<(), IntegrateError> {
        check_options(self)
    }
}

impl Default for TransientOptions {
    fn default() -> Self {
        Self {
            alpha: -0.05,
            rtol: 1e-6,
            atol: 1e-11,
            min_steps_per_revolution: 64,
            omega_refresh: 1e-4,
            newton_tol: 1e-10,
            max_newton: 12,
            thermal: ThermalStepping::default(),
            max_steps: 100_000_000,
        }
    }
}

/// Counts of a [`Transient`] run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TransientStats {
    pub accepted: u64,
    pub rejected: u64,
    pub newton_iterations: u64,
    pub factorizations: u64,
    pub thermal_steps: u64,
}

/// The state after an accepted step, handed to the observer of [`Transient::advance`].
pub struct StepView<'s> {
    /// Time (s).
    pub t: f64,
    /// Speed (rad/s) and rotation angle (rad).
    pub omega: f64,
    pub phase: f64,
    pub x: &'s [f64],
    pub v: &'s [f64],
    pub temp: &'s [f64],
    /// The nonlinear terms at this state (values and derivatives).
    pub eval: &'s NonlinearEval,
}

/// The matrices at one speed.
struct Linear {
    omega: f64,
    mass: Mat<f64>,
    damping: Mat<f64>,
    stiffness: Mat<f64>,
    capacity: Mat<f64>,
    conductance: Mat<f64>,
    thermal_load: Vec<f64>,
}

/// `A⁻¹`, `A⁻¹P` and `S = PᵀA⁻¹P` for one step size at one speed.
struct Factored {
    h: f64,
    omega: f64,
    a_inv: Mat<f64>,
    a_inv_p: Mat<f64>,
    s: Mat<f64>,
}

/// Heat averaging over a thermal macro step.
struct HeatAverage {
    span: f64,
    g: Vec<f64>,
    dg_dt: Vec<f64>,
    revolutions_target: u32,
    phase_start: f64,
}

fn to_faer(a: &DenseMatrix) -> Mat<f64> {
    Mat::from_fn(a.n, a.n, |i, j| a.get(i, j))
}

fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    (sum / n.max(1) as f64).sqrt()
}

/// A transient run of a [`System`]: state, step size and the factorizations of the current
/// step (see the module docs).
pub struct Transient<'a> {
    system: &'a dyn System,
    profile: SpeedProfile,
    opts: TransientOptions,
    n: usize,
    m: usize,
    mech: Vec<usize>,
    therm: Vec<usize>,
    beta: f64,
    gamma: f64,
    t: f64,
    x: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    temp: Vec<f64>,
    /// Effective load `P f − F` at the current state (the α-weighted old term).
    load: Vec<f64>,
    eval: NonlinearEval,
    /// Heat and its temperature derivative at the last accepted state.
    g_prev: Vec<f64>,
    dg_prev: Vec<f64>,
    h: f64,
    linear: Linear,
    /// Factorizations of recent step sizes at the current speed (steps come from a
    /// ladder `h₀·2^(−k/4)`, so few distinct sizes recur).
    factored: Vec<Arc<Factored>>,
    /// The ladder's base step `h₀`.
    h_base: f64,
    heat: Option<HeatAverage>,
    stats: TransientStats,
    // scratch
    force: Vec<f64>,
    xp: Vec<f64>,
    vp: Vec<f64>,
    tq: Vec<f64>,
}

impl<'a> Transient<'a> {
    /// Starts at `t = 0` from `x`, `v` (length `n_mech`) and `temp` (length `n_therm`).
    pub fn new(
        system: &'a dyn System,
        profile: SpeedProfile,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        opts: TransientOptions,
    ) -> Result<Self, IntegrateError> {
        profile.check()?;
        check_options(&opts)?;
        let n = system.n_mech();
        let m = system.n_therm();
        for (what, len, want) in [
            ("initial displacements", x.len(), n),
            ("initial velocities", v.len(), n),
            ("initial temperatures", temp.len(), m),
        ] {
            if len != want {
                return Err(IntegrateError::Dimension {
                    what,
                    expected: want,
                    found: len,
                });
            }
        }
        let dofs = system.nonlinear_dofs().clone();
        let omega = profile.omega(0.0);
        let linear = build_linear(system, omega);
        let alpha = opts.alpha;
        let mut me = Self {
            system,
            n,
            m,
            beta: 0.25 * (1.0 - alpha) * (1.0 - alpha),
            gamma: 0.5 - alpha,
            t: 0.0,
            x: x.to_vec(),
            v: v.to_vec(),
            a: vec![0.0; n],
            temp: temp.to_vec(),
            load: vec![0.0; n],
            eval: NonlinearEval::new(dofs.mech.len(), dofs.therm.len()),
            g_prev: Vec::new(),
            dg_prev: Vec::new(),
            h: std::f64::consts::TAU / omega / f64::from(opts.min_steps_per_revolution),
            linear,
            factored: Vec::new(),
            h_base: std::f64::consts::TAU / omega / f64::from(opts.min_steps_per_revolution),
            heat: None,
            stats: TransientStats::default(),
            force: vec![0.0; n],
            xp: vec![0.0; dofs.mech.len()],
            vp: vec![0.0; dofs.mech.len()],
            tq: vec![0.0; dofs.therm.len()],
            mech: dofs.mech,
            therm: dofs.therm,
            profile,
            opts,
        };
        me.initial_acceleration()?;
        Ok(me)
    }

    /// Time (s).
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Displacements, velocities and temperatures now.
    pub fn state(&self) -> (&[f64], &[f64], &[f64]) {
        (&self.x, &self.v, &self.temp)
    }

    /// Counts so far.
    pub fn stats(&self) -> TransientStats {
        self.stats
    }

    /// The speed profile.
    pub fn profile(&self) -> &SpeedProfile {
        &self.profile
    }

    /// Current step size (s).
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// The system's time argument at `t`: `φ(t)/ω(t)` (see the module docs).
    fn system_time(&self, t: f64) -> (f64, f64) {
        let w = self.profile.omega(t);
        (w, self.profile.phase(t) / w)
    }

    /// Evaluates the nonlinear terms at `(t, x, v)` with the held temperatures into
    /// `self.eval`.
    fn evaluate(&mut self, t: f64, x: &[f64], v: &[f64]) {
        let (w, ts) = self.system_time(t);
        for (k, &i) in self.mech.iter().enumerate() {
            self.xp[k] = x[i];
            self.vp[k] = v[i];
        }
        for (k, &i) in self.therm.iter().enumerate() {
            self.tq[k] = self.temp[i];
        }
        self.system
            .eval_nonlinear(w, ts, &self.xp, &self.vp, &self.tq, &mut self.eval);
    }

    /// The effective load `P f − F` of the α-weighted old term from `self.eval` and
    /// `self.force` (the load at the same time).
    fn set_load(&mut self) {
        for (l, f) in self.load.iter_mut().zip(&self.force) {
            *l = -f;
        }
        for (k, &i) in self.mech.iter().enumerate() {
            self.load[i] += self.eval.f[k];
        }
    }

    /// `a₀` from the equations of motion at the start state.
    fn initial_acceleration(&mut self) -> Result<(), IntegrateError> {
        let (x, v) = (self.x.clone(), self.v.clone());
        self.evaluate(0.0, &x, &v);
        let (w, ts) = self.system_time(0.0);
        self.system.forcing(w, ts, &mut self.force);
        self.set_load();
        let lin = &self.linear;
        let rhs = Mat::from_fn(self.n, 1, |i, _| {
            let mut r = -self.load[i];
            for j in 0..self.n {
                r -= lin.damping[(i, j)] * v[j] + lin.stiffness[(i, j)] * x[j];
            }
            r
        });
        self.g_prev = self.eval.g.clone();
        self.dg_prev = self.eval.dg_dt.clone();
        let a = lin.mass.partial_piv_lu().solve(&rhs);
        for i in 0..self.n {
            self.a[i] = a[(i, 0)];
        }
        if self.a.iter().any(|v| !v.is_finite()) {
            return Err(IntegrateError::Singular { matrix: "mass" });
        }
        Ok(())
    }

    /// Factors `A` for step `h` at the current speed when it is not factored already.
    fn factor(&mut self, h: f64) -> Result<usize, IntegrateError> {
        if let Some(i) = self
            .factored
            .iter()
            .position(|f| f.h == h && f.omega == self.linear.omega)
        {
            return Ok(i);
        }
        let (n, p) = (self.n, self.mech.len());
        let (beta, gamma, alpha) = (self.beta, self.gamma, self.opts.alpha);
        let lin = &self.linear;
        let am = Mat::from_fn(n, n, |i, j| {
            lin.mass[(i, j)] / (beta * h * h)
                + (1.0 + alpha) * (gamma / (beta * h) * lin.damping[(i, j)] + lin.stiffness[(i, j)])
        });
        let a_inv = am
            .partial_piv_lu()
            .solve(Mat::<f64>::identity(n, n).as_ref());
        if a_inv
            .col_iter()
            .flat_map(|c| c.iter())
            .any(|v| !v.is_finite())
        {
            return Err(IntegrateError::Singular {
                matrix: "HHT iteration",
            });
        }
        let a_inv_p = Mat::from_fn(n, p, |i, k| a_inv[(i, self.mech[k])]);
        let s = Mat::from_fn(p, p, |k, l| a_inv_p[(self.mech[k], l)]);
        let omega = lin.omega;
        self.factored.retain(|f| f.omega == omega);
        if self.factored.len() >= 6 {
            self.factored.remove(0);
        }
        self.factored.push(Arc::new(Factored {
            h,
            omega,
            a_inv,
            a_inv_p,
            s,
        }));
        self.stats.factorizations += 1;
        Ok(self.factored.len() - 1)
    }

    /// Tries one step of size `h` from the current state; returns the new state and the
    /// error norm, or `None` when Newton did not converge.
    #[allow(clippy::type_complexity)]
    fn try_step(
        &mut self,
        h: f64,
    ) -> Result<Option<(Vec<f64>, Vec<f64>, Vec<f64>, f64)>, IntegrateError> {
        let slot = self.factor(h)?;
        let (n, p) = (self.n, self.mech.len());
        let (beta, gamma, alpha) = (self.beta, self.gamma, self.opts.alpha);
        let t1 = self.t + h;
        let xt: Vec<f64> = (0..n)
            .map(|i| self.x[i] + h * self.v[i] + h * h * (0.5 - beta) * self.a[i])
            .collect();
        let vt: Vec<f64> = (0..n)
            .map(|i| self.v[i] + h * (1.0 - gamma) * self.a[i])
            .collect();
        // b without the (1+α)(−F₁) term, which needs the load at t₁ (state independent)
        let (w1, ts1) = self.system_time(t1);
        self.system.forcing(w1, ts1, &mut self.force);
        let lin = &self.linear;
        let cgb = gamma / (beta * h);
        let mut b = vec![0.0; n];
        for i in 0..n {
            let mut r = (1.0 + alpha) * self.force[i] + alpha * self.load[i];
            for j in 0..n {
                r += lin.mass[(i, j)] * xt[j] / (beta * h * h)
                    - (1.0 + alpha) * lin.damping[(i, j)] * (vt[j] - cgb * xt[j])
                    + alpha * (lin.damping[(i, j)] * self.v[j] + lin.stiffness[(i, j)] * self.x[j]);
            }
            b[i] = r;
        }
        let fac = Arc::clone(&self.factored[slot]);
        let mut x0 = vec![0.0; n];
        for i in 0..n {
            let row = fac.a_inv.row(i);
            x0[i] = (0..n).map(|j| row[j] * b[j]).sum();
        }
        let (s, a_inv_p) = (&fac.s, &fac.a_inv_p);
        // Newton on z = x₁ at the nonlinear DoFs, from the predictor x̃.
        let c: Vec<f64> = self.mech.iter().map(|&i| x0[i]).collect();
        let mut z: Vec<f64> = self.mech.iter().map(|&i| xt[i]).collect();
        let mut x1 = xt.clone();
        let mut v1 = vec![0.0; n];
        let mut converged = p == 0;
        let scale = z.iter().fold(0.0f64, |m, v| m.max(v.abs())) + self.opts.atol;
        for _ in 0..self.opts.max_newton.max(1) {
            if p == 0 {
                break;
            }
            for (k, &i) in self.mech.iter().enumerate() {
                x1[i] = z[k];
                v1[i] = vt[i] + cgb * (z[k] - xt[i]);
            }
            self.evaluate(t1, &x1, &v1);
            self.stats.newton_iterations += 1;
            // R = z − c + (1+α) S f(z);  J = I + (1+α) S (∂f/∂x + cgb ∂f/∂v)
            let mut jac = Mat::<f64>::identity(p, p);
            let mut r = vec![0.0; p];
            for k in 0..p {
                let mut rk = z[k] - c[k];
                for l in 0..p {
                    rk += (1.0 + alpha) * s[(k, l)] * self.eval.f[l];
                }
                r[k] = rk;
                for l in 0..p {
                    let mut sum = 0.0;
                    for j in 0..p {
                        sum += s[(k, j)]
                            * (self.eval.df_dx[j * p + l] + cgb * self.eval.df_dv[j * p + l]);
                    }
                    jac[(k, l)] += (1.0 + alpha) * sum;
                }
            }
            let rhs = Mat::from_fn(p, 1, |k, _| -r[k]);
            let dz = jac.partial_piv_lu().solve(&rhs);
            let mut step = 0.0f64;
            for k in 0..p {
                let d = dz[(k, 0)];
                if !d.is_finite() {
                    return Ok(None);
                }
                z[k] += d;
                step = step.max(d.abs());
            }
            if step <= self.opts.newton_tol * scale {
                converged = true;
                break;
            }
        }
        if !converged {
            return Ok(None);
        }
        // final f at the converged z, then x₁ = A⁻¹b − (1+α) A⁻¹P f
        for (k, &i) in self.mech.iter().enumerate() {
            x1[i] = z[k];
            v1[i] = vt[i] + cgb * (z[k] - xt[i]);
        }
        self.evaluate(t1, &x1, &v1);
        for i in 0..n {
            let mut xi = x0[i];
            for l in 0..p {
                xi -= (1.0 + alpha) * a_inv_p[(i, l)] * self.eval.f[l];
            }
            x1[i] = xi;
        }
        let a1: Vec<f64> = (0..n).map(|i| (x1[i] - xt[i]) / (beta * h * h)).collect();
        for i in 0..n {
            v1[i] = vt[i] + gamma * h * a1[i];
        }
        if x1.iter().chain(&v1).any(|v| !v.is_finite()) {
            return Ok(None);
        }
        let ce = (beta - 1.0 / 6.0) * h * h;
        let size = self.x.iter().chain(&x1).fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = self.opts.atol + self.opts.rtol * size;
        let err = rms((0..n).map(|i| ce * (a1[i] - self.a[i]) / tol));
        Ok(Some((x1, v1, a1, err)))
    }

    /// The largest ladder step `h₀·2^(−k/4)` not above `h`.
    fn ladder(&self, h: f64) -> f64 {
        let k = (4.0 * (self.h_base / h).log2()).ceil();
        self.h_base * (-k / 4.0).exp2()
    }

    /// The largest step the revolution and profile constraints allow at `t`.
    fn step_cap(&self, t: f64) -> f64 {
        std::f64::consts::TAU
            / self.profile.omega(t)
            / f64::from(self.opts.min_steps_per_revolution.max(1))
    }

    /// Integrates to `t_end`, calling `observer` after every accepted step; the observer
    /// returns `false` to stop early (the state is then that of the last accepted step).
    /// Returns whether the run reached `t_end`.
    pub fn advance(
        &mut self,
        t_end: f64,
        observer: &mut dyn FnMut(&StepView<'_>) -> bool,
    ) -> Result<bool, IntegrateError> {
        if !(t_end.is_finite()) {
            return Err(IntegrateError::Interval {
                t0: self.t,
                t1: t_end,
            });
        }
        let mut budget = self.opts.max_steps;
        while self.t < t_end - 1e-12 * t_end.abs().max(1e-9) {
            if budget == 0 {
                return Err(IntegrateError::StepBudget {
                    steps: usize::try_from(self.opts.max_steps).unwrap_or(usize::MAX),
                    t: self.t,
                    t_end,
                });
            }
            budget -= 1;
            self.refresh_linear()?;
            let cap = self.step_cap(self.t);
            let want = self.h.min(cap);
            let limited = want < self.h;
            let mut h = self.ladder(want);
            // never a sliver before the end: the last two steps share what is left (a tiny
            // step makes a₁ = (x₁ − x̃)/(βh²) lose its digits)
            let left = t_end - self.t;
            if left <= h {
                h = left;
            } else if left < 2.0 * h {
                h = 0.5 * left;
            }
            let Some((x1, v1, a1, err)) = self.try_step(h)? else {
                self.stats.rejected += 1;
                self.h = 0.5 * h;
                if self.h < 1e-14 * self.t.abs().max(1.0) {
                    return Err(IntegrateError::StepUnderflow {
                        t: self.t,
                        h: self.h,
                    });
                }
                continue;
            };
            let fac = if err == 0.0 {
                2.0
            } else {
                (0.9 * err.powf(-1.0 / 3.0)).clamp(0.3, 2.0)
            };
            if err > 1.0 {
                self.stats.rejected += 1;
                self.h = h * fac.min(0.9);
                if self.h < 1e-14 * self.t.abs().max(1.0) {
                    return Err(IntegrateError::StepUnderflow {
                        t: self.t,
                        h: self.h,
                    });
                }
                continue;
            }
            self.stats.accepted += 1;
            self.t += h;
            self.x = x1;
            self.v = v1;
            self.a = a1;
            // `self.eval` holds the terms at the new state (the step's last evaluation, at
            // the converged nonlinear DoFs) and `self.force` the load at its time
            self.set_load();
            self.accumulate_heat(h)?;
            // a step cut short by the end or the revolution cap does not shrink the
            // controller's step
            let proposed = h * fac;
            self.h = if limited {
                self.h.max(proposed)
            } else {
                proposed
            };
            let (omega, phase) = (self.profile.omega(self.t), self.profile.phase(self.t));
            let view = StepView {
                t: self.t,
                omega,
                phase,
                x: &self.x,
                v: &self.v,
                temp: &self.temp,
                eval: &self.eval,
            };
            if !observer(&view) {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Rebuilds the speed-dependent matrices when the speed has moved far enough.
    fn refresh_linear(&mut self) -> Result<(), IntegrateError> {
        let w = self.profile.omega(self.t);
        if (w - self.linear.omega).abs() > self.opts.omega_refresh * self.linear.omega {
            self.linear = build_linear(self.system, w);
        }
        Ok(())
    }

    /// Adds one mechanical step's heat to the macro step's average and advances the
    /// temperatures when the macro step is complete.
    fn accumulate_heat(&mut self, h: f64) -> Result<(), IntegrateError> {
        if self.m == 0 {
            return Ok(());
        }
        let q = self.therm.len();
        let phase_now = self.profile.phase(self.t);
        let heat = self.heat.get_or_insert_with(|| HeatAverage {
            span: 0.0,
            g: vec![0.0; q],
            dg_dt: vec![0.0; q * q],
            revolutions_target: 1,
            phase_start: phase_now - self.profile.omega(self.t) * h,
        });
        heat.span += h;
        for k in 0..q {
            heat.g[k] += 0.5 * h * (self.g_prev[k] + self.eval.g[k]);
        }
        for k in 0..q * q {
            heat.dg_dt[k] += 0.5 * h * (self.dg_prev[k] + self.eval.dg_dt[k]);
        }
        self.g_prev.copy_from_slice(&self.eval.g);
        self.dg_prev.copy_from_slice(&self.eval.dg_dt);
        let done = match self.opts.thermal {
            ThermalStepping::EveryStep => true,
            ThermalStepping::Averaged { .. } => {
                phase_now - heat.phase_start
                    >= std::f64::consts::TAU * f64::from(heat.revolutions_target) * (1.0 - 1e-9)
            }
        };
        if done {
            self.thermal_step()?;
        }
        Ok(())
    }

    /// One linearly implicit trapezoidal step of the thermal network over the macro
    /// step with its averaged heat; adapts the next macro step's length.
    fn thermal_step(&mut self) -> Result<(), IntegrateError> {
        let Some(heat) = self.heat.take() else {
            return Ok(());
        };
        let (m, q) = (self.m, self.therm.len());
        let span = heat.span;
        let lin = &self.linear;
        // rhs = F_T − K_T T − Q ḡ
        let mut rhs = Mat::from_fn(m, 1, |i, _| {
            let mut r = lin.thermal_load[i];
            for j in 0..m {
                r -= lin.conductance[(i, j)] * self.temp[j];
            }
            r
        });
        for (k, &i) in self.therm.iter().enumerate() {
            rhs[(i, 0)] -= heat.g[k] / span;
        }
        let system_matrix = |theta: f64| {
            let mut a = Mat::from_fn(m, m, |i, j| {
                lin.capacity[(i, j)] / span + theta * lin.conductance[(i, j)]
            });
            for (k, &i) in self.therm.iter().enumerate() {
                for (l, &j) in self.therm.iter().enumerate() {
                    a[(i, j)] += theta * heat.dg_dt[k * q + l] / span;
                }
            }
            a
        };
        let d_tr = system_matrix(0.5).partial_piv_lu().solve(&rhs);
        let d_be = system_matrix(1.0).partial_piv_lu().solve(&rhs);
        let mut biggest = 0.0f64;
        let mut err = 0.0f64;
        for i in 0..m {
            let d = d_tr[(i, 0)];
            if !d.is_finite() {
                return Err(IntegrateError::NonFinite { t: self.t });
            }
            self.temp[i] += d;
            biggest = biggest.max(d.abs());
            err = err.max((d - d_be[(i, 0)]).abs());
        }
        self.stats.thermal_steps += 1;
        let next = match self.opts.thermal {
            ThermalStepping::EveryStep => 1,
            ThermalStepping::Averaged {
                max_revolutions,
                temp_tol,
                max_temp_step,
            } => {
                let k = f64::from(heat.revolutions_target);
                let by_err = if err > 0.0 {
                    k * (0.9 * (temp_tol / err).sqrt()).clamp(0.5, 2.0)
                } else {
                    2.0 * k
                };
                let by_size = if biggest > 0.0 {
                    k * max_temp_step / biggest
                } else {
                    2.0 * k
                };
                by_err
                    .min(by_size)
                    .floor()
                    .clamp(1.0, f64::from(max_revolutions.max(1))) as u32
            }
        };
        self.heat = Some(HeatAverage {
            span: 0.0,
            g: vec![0.0; q],
            dg_dt: vec![0.0; q * q],
            revolutions_target: next,
            phase_start: self.profile.phase(self.t),
        });
        Ok(())
    }
}

fn build_linear(system: &dyn System, omega: f64) -> Linear {
    let lp = system.linear(omega);
    let mut thermal_load = vec![0.0; system.n_therm()];
    system.thermal_load(omega, &mut thermal_load);
    Linear {
        omega,
        mass: to_faer(&lp.mass),
        damping: to_faer(&lp.damping),
        stiffness: to_faer(&lp.stiffness),
        capacity: to_faer(&lp.thermal_capacity),
        conductance: to_faer(&lp.thermal_conductance),
        thermal_load,
    }
}

fn check_options(o: &TransientOptions) -> Result<(), IntegrateError> {
    let bad = |field: &'static str, value: f64, reason: &'static str| {
        Err(IntegrateError::Setting {
            field,
            value: format!("{value}"),
            reason,
        })
    };
    if !(-1.0 / 3.0..=0.0).contains(&o.alpha) {
        return bad("alpha", o.alpha, "HHT-α is stable for α in [−1/3, 0]");
    }
    if !(o.rtol > 0.0 && o.rtol < 1.0) {
        return bad("rtol", o.rtol, "must lie in (0, 1)");
    }
    if !(o.atol > 0.0 && o.atol.is_finite()) {
        return bad("atol", o.atol, "must be finite and above 0");
    }
    if o.min_steps_per_revolution < 8 {
        return bad(
            "min_steps_per_revolution",
            f64::from(o.min_steps_per_revolution),
            "at least 8 steps a revolution",
        );
    }
    if !(o.omega_refresh > 0.0 && o.omega_refresh < 0.1) {
        return bad("omega_refresh", o.omega_refresh, "must lie in (0, 0.1)");
    }
    if let ThermalStepping::Averaged {
        max_revolutions,
        temp_tol,
        max_temp_step,
    } = o.thermal
    {
        if max_revolutions == 0 {
            return bad(
                "max_revolutions",
                0.0,
                "at least 1 revolution a thermal step",
            );
        }
        if !(temp_tol > 0.0 && temp_tol.is_finite()) {
            return bad("temp_tol", temp_tol, "must be finite and above 0 K");
        }
        if !(max_temp_step > 0.0 && max_temp_step.is_finite()) {
            return bad(
                "max_temp_step",
                max_temp_step,
                "must be finite and above 0 K",
            );
        }
    }
    Ok(())
}
