//! One transient run of the coupled rotor into a [`TransientSink`]: the driver beside the
//! sweep (`sweep.rs`), on the time axis instead of the speed axis.
//!
//! The engine's [`Transient`] integrates the model the sweep built ([`SweepProblem`]); this
//! module chooses the start state (a cold start, or a point of a recorded branch, possibly
//! perturbed), turns the integrator's steps into per-revolution records (RMS amplitude of
//! Eq. 35 over the basis's period, so that a settled transient reads the same number as the
//! harmonic-balance point; temperatures; clearances; bearing loads) and decimated
//! displacement samples, and stops cleanly on an interrupt with every written revolution
//! kept.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use thiserror::Error;

use crate::integrate::{
    IntegrateError, SpeedProfile, StepView, ThermalStepping, Transient, TransientOptions,
    TransientStats,
};
use crate::record::convert::to_micrometres;
use crate::record::transient::{Revolution, Samples, TransientInfo, TransientSink};
use crate::record::{RecordError, RunInfo, RunStatus};
use crate::study::SweepProblem;
use crate::system::{PeriodicOrbit, System};

/// Errors of a transient run.
#[derive(Debug, Error)]
pub enum TransientError {
    #[error("transient integration: {0}")]
    Integrate(#[from] IntegrateError),
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error("{file}: {reason}")]
    Recording { file: String, reason: String },
    #[error("transient setting {field} = {value}: {reason}")]
    Setting {
        field: &'static str,
        value: String,
        reason: String,
    },
}

/// Where the run starts.
#[derive(Clone, Debug)]
pub struct StartState {
    /// Displacements, velocities (length `n_mech`) and temperatures (`n_therm`).
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub temp: Vec<f64>,
    /// In words, for the recording ("cold start", "point 12 of sweep.mcap").
    pub label: String,
}

impl StartState {
    /// At rest in the static gravity equilibrium on the bearings, every temperature at
    /// ambient.
    pub fn cold(problem: &SweepProblem) -> Self {
        let sys = &problem.system;
        Self {
            x: sys.static_equilibrium(),
            v: vec![0.0; sys.n_mech()],
            temp: vec![sys.ambient_temp_c(); sys.n_therm()],
            label: "cold start: at rest in the static equilibrium, temperatures at ambient".into(),
        }
    }

    /// On a periodic orbit at its time 0 (a harmonic-balance point).
    pub fn on_orbit(
        orbit: &dyn PeriodicOrbit,
        n_mech: usize,
        n_therm: usize,
        label: String,
    ) -> Self {
        let (mut x, mut v, mut temp) = (vec![0.0; n_mech], vec![0.0; n_mech], vec![0.0; n_therm]);
        orbit.state_at(0.0, &mut x, &mut v, &mut temp);
        Self { x, v, temp, label }
    }

    /// Scales the oscillating part of the displacements and the velocities by `1 + factor`
    /// about `mean` (the orbit's mean displacement) and adds `temp_shift` K to every
    /// temperature.
    pub fn perturbed(mut self, mean: &[f64], factor: f64, temp_shift: f64) -> Self {
        for (x, m) in self.x.iter_mut().zip(mean) {
            *x = m + (1.0 + factor) * (*x - m);
        }
        for v in &mut self.v {
            *v *= 1.0 + factor;
        }
        for t in &mut self.temp {
            *t += temp_shift;
        }
        if factor != 0.0 || temp_shift != 0.0 {
            self.label = format!(
                "{}, perturbed: vibration ×{:.6}, temperatures {:+} K",
                self.label,
                1.0 + factor,
                temp_shift
            );
        }
        self
    }

    /// On `orbit` (a converged point of `hb`) at time 0, moved along its `k`-th Floquet
    /// mode nearest zero (Hill's eigenproblem, [`crate::stability::HillPencil`]), the
    /// modes ordered by decreasing real part of their exponent (0: the most unstable, or
    /// least stable). The mode's real part at t = 0 is scaled so that its largest
    /// displacement is `size` times the orbit's largest vibration amplitude (its largest
    /// displacement about the mean), the sign of `size` choosing the direction.
    pub fn along_mode(
        orbit: &crate::hb::HbSolution,
        hb: &crate::hb::HarmonicBalance<'_>,
        k: usize,
        size: f64,
        label: String,
    ) -> Result<(Self, crate::stability::HillMode), TransientError> {
        let setting = |reason: String| TransientError::Setting {
            field: "perturb_mode",
            value: k.to_string(),
            reason,
        };
        let (n_mech, n_therm) = (orbit.n_mech(), orbit.n_therm());
        let mut modes = crate::stability::HillPencil::new(hb, orbit, None)
            .and_then(|p| p.near_zero_modes(n_therm + 2, &crate::stability::HillOptions::default()))
            .map_err(|e| setting(format!("the point's Floquet modes: {e}")))?;
        modes.sort_by(|a, b| b.exponent.re.total_cmp(&a.exponent.re));
        let n = modes.len();
        if k >= n {
            return Err(setting(format!(
                "the point has {n} Floquet modes near zero (0 … {})",
                n.saturating_sub(1)
            )));
        }
        let mode = modes.swap_remove(k);
        let (dx, dv, dt) = mode.state_at(&orbit.basis, orbit.omega, n_mech, 0.0);
        let mode_max = dx.iter().map(|c| c.re.abs()).fold(0.0, f64::max);
        // the orbit's vibration: largest displacement about the mean, over 64 samples
        let period = crate::system::PeriodicOrbit::period(orbit);
        let (mut x, mut v, mut t) = (vec![0.0; n_mech], vec![0.0; n_mech], vec![0.0; n_therm]);
        let mut vib: f64 = 0.0;
        for j in 0..64 {
            crate::system::PeriodicOrbit::state_at(
                orbit,
                j as f64 * period / 64.0,
                &mut x,
                &mut v,
                &mut t,
            );
            for (d, xd) in x.iter().enumerate() {
                vib = vib.max((xd - orbit.mech_coeffs(d)[0]).abs());
            }
        }
        if !(mode_max > 0.0 && vib > 0.0) {
            return Err(setting(
                "the mode moves no displacement at t = 0, or the orbit does not vibrate; \
                 perturb the temperatures with --perturb-temp instead"
                    .into(),
            ));
        }
        let scale = size * vib / mode_max;
        let mut start = Self::on_orbit(orbit, n_mech, n_therm, label);
        for (a, d) in start.x.iter_mut().zip(&dx) {
            *a += scale * d.re;
        }
        for (a, d) in start.v.iter_mut().zip(&dv) {
            *a += scale * d.re;
        }
        for (a, d) in start.temp.iter_mut().zip(&dt) {
            *a += scale * d.re;
        }
        let mu = (mode.exponent * period).exp();
        start.label = format!(
            "{}, perturbed along Floquet mode {k} (exponent {:.4e}{:+.4e}i 1/s, multiplier \
             modulus {:.6}) by {size} of the vibration",
            start.label,
            mode.exponent.re,
            mode.exponent.im,
            mu.norm()
        );
        Ok((start, mode))
    }
}

/// A point of a recorded sweep to start a run from, with the model and study that
/// computed it (rebuilt from the recording's run description, on the point's branch's
/// basis): what `tmrotor transient --from REC --point I` and a campaign's
/// `transient = { from = …, point = … }` start from.
pub struct RecordedStart {
    /// The recording's problem (model, coupled rotor, basis, settings).
    pub problem: SweepProblem,
    /// The point's harmonic-balance orbit.
    pub orbit: crate::hb::HbSolution,
    /// The point's speed, rad/s.
    pub omega: f64,
    /// `point 93 of sweep.mcap (ω = 468.47 rad/s, stable)`.
    pub label: String,
}

impl RecordedStart {
    /// Reads point `index` of the sweep recording at `path`; errors name the file and say
    /// which points it holds.
    pub fn read(path: &std::path::Path, index: u64) -> Result<Self, TransientError> {
        let file = path.display().to_string();
        let fail = |reason: String| TransientError::Recording {
            file: file.clone(),
            reason,
        };
        let rec = crate::record::read_recording(path).map_err(|e| fail(e.to_string()))?;
        let point = rec.point(index).ok_or_else(|| {
            fail(format!(
                "no point {index} (the recording holds {} points{})",
                rec.points.len(),
                rec.points
                    .last()
                    .map_or(String::new(), |p| format!(", indices up to {}", p.index))
            ))
        })?;
        let run = rec.run_of(point.branch).ok_or_else(|| {
            fail(format!(
                "point {index} is on branch {} which the recording does not describe",
                point.branch
            ))
        })?;
        let rederive = crate::derive::CoupledRederive::from_run(&run)
            .map_err(|e| fail(format!("rebuilding its model: {e}")))?;
        let orbit = rederive.solution(point);
        let label = format!(
            "point {index} of {file} (ω = {} rad/s{})",
            point.omega_rad_s,
            match point.stable {
                Some(true) => ", stable",
                Some(false) => ", unstable",
                None => "",
            }
        );
        Ok(Self {
            problem: rederive.into_problem(),
            omega: point.omega_rad_s,
            orbit,
            label,
        })
    }

    /// The orbit's mean displacements (the centre of [`StartState::perturbed`]'s scaling).
    fn mean(&self) -> Vec<f64> {
        (0..self.orbit.n_mech())
            .map(|d| self.orbit.mech_coeffs(d)[0])
            .collect()
    }

    /// On the orbit at time 0, its vibration scaled by `1 + factor` and its temperatures
    /// shifted by `temp_shift` K ([`StartState::perturbed`]).
    pub fn on_orbit(&self, factor: f64, temp_shift: f64) -> StartState {
        let sys = &self.problem.system;
        StartState::on_orbit(&self.orbit, sys.n_mech(), sys.n_therm(), self.label.clone())
            .perturbed(&self.mean(), factor, temp_shift)
    }

    /// On the orbit moved along its `k`-th Floquet mode nearest zero by `size`
    /// ([`StartState::along_mode`]), temperatures shifted by `temp_shift` K.
    pub fn along_mode(
        &self,
        k: usize,
        size: f64,
        temp_shift: f64,
    ) -> Result<(StartState, crate::stability::HillMode), TransientError> {
        let hb = crate::hb::HarmonicBalance::new(
            &self.problem.system,
            &self.problem.basis,
            self.problem.settings.harmonic.aft_samples,
        )
        .map_err(|e| TransientError::Setting {
            field: "perturb_mode",
            value: k.to_string(),
            reason: format!("the point's harmonic balance: {e}"),
        })?;
        let (start, mode) = StartState::along_mode(&self.orbit, &hb, k, size, self.label.clone())?;
        Ok((start.perturbed(&self.mean(), 0.0, temp_shift), mode))
    }
}

/// Settings of one transient run.
#[derive(Clone, Debug)]
pub struct TransientSettings {
    pub profile: SpeedProfile,
    /// Simulated time (s).
    pub duration_s: f64,
    pub options: TransientOptions,
    /// Displacement samples per revolution on `/transient/samples` (0: none). Default 16.
    pub samples_per_revolution: u32,
}

/// What a finished (or stopped) run reports.
#[derive(Clone, Debug)]
pub struct TransientReport {
    pub revolutions: u64,
    pub simulated_s: f64,
    pub wall_s: f64,
    pub stats: TransientStats,
    pub interrupted: bool,
    /// The last revolution written.
    pub last: Option<Revolution>,
}

impl TransientReport {
    /// Simulated seconds per wall-clock second.
    pub fn speed(&self) -> f64 {
        self.simulated_s / self.wall_s.max(1e-9)
    }
}

/// The profile in words.
pub fn describe_profile(profile: &SpeedProfile) -> String {
    match profile {
        SpeedProfile::Constant(w) => format!("fixed speed {w} rad/s"),
        SpeedProfile::Ramp { from, to, accel } => format!(
            "{} {from} -> {to} rad/s at {accel} rad/s^2",
            if to > from { "run-up" } else { "coast-down" }
        ),
        SpeedProfile::Table(rows) => format!("speed table of {} rows", rows.len()),
    }
}

fn describe_thermal(t: ThermalStepping) -> String {
    match t {
        ThermalStepping::EveryStep => "every step (single rate)".into(),
        ThermalStepping::Averaged {
            max_revolutions,
            temp_tol,
            max_temp_step,
        } => format!(
            "averaged over 1..{max_revolutions} revolutions (local error {temp_tol} K, at most {max_temp_step} K a step)"
        ),
    }
}

/// Per-node running sums over one revolution.
#[derive(Clone, Default)]
struct RevolutionSums {
    span: f64,
    /// ∫x, ∫y, ∫x², ∫y² per node.
    sums: Vec<[f64; 4]>,
    /// Smallest and largest x, smallest and largest y per node (the peak excursion is taken
    /// from them about the window's mean).
    extremes: Vec<[f64; 4]>,
    steps: u32,
    /// Largest radial load per bearing at the revolution's samples.
    load_max: Vec<f64>,
}

/// No extremes yet: `[min x, max x, min y, max y]` before any sample.
const NO_EXTREMES: [f64; 4] = [
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
];

/// Widens the extremes `ext` to hold those of `other` (both `[min x, max x, min y, max y]`).
fn widen(ext: &mut [f64; 4], other: &[f64; 4]) {
    ext[0] = ext[0].min(other[0]);
    ext[1] = ext[1].max(other[1]);
    ext[2] = ext[2].min(other[2]);
    ext[3] = ext[3].max(other[3]);
}

impl RevolutionSums {
    /// Empty sums for `nodes` dynamic nodes and `bearings` bearings.
    fn new(nodes: usize, bearings: usize) -> Self {
        Self {
            sums: vec![[0.0; 4]; nodes],
            extremes: vec![NO_EXTREMES; nodes],
            load_max: vec![0.0; bearings],
            ..Self::default()
        }
    }
}

/// The default relative tolerance of a transient run: 1e-4 holds a settled orbit to
/// about 1e-3 of its amplitude on the built-in model at a third of the cost of 1e-6
/// (docs/transient.md).
pub const DEFAULT_RTOL: f64 = 1e-4;

/// Displacement samples per revolution recorded on `/transient/samples` by default.
pub const DEFAULT_SAMPLES_PER_REVOLUTION: u32 = 16;

/// Runs the transient of `problem` from `start` into `sink`. `progress` sees each
/// revolution; `interrupt` set stops at the next step with status `interrupted`.
pub fn run_transient(
    problem: &SweepProblem,
    start: &StartState,
    settings: &TransientSettings,
    sink: &mut dyn TransientSink,
    progress: &mut dyn FnMut(&Revolution),
    interrupt: Option<Arc<AtomicBool>>,
) -> Result<TransientReport, TransientError> {
    let d = settings.duration_s;
    if !(d.is_finite() && d > 0.0) {
        return Err(TransientError::Setting {
            field: "duration",
            value: d.to_string(),
            reason: "the simulated time must be finite and above 0 s".into(),
        });
    }
    let sys = &problem.system;
    let run = &problem.run;
    let window = problem.basis.base_den().max(1);
    let corners: Vec<(f64, f64)> = match &settings.profile {
        SpeedProfile::Table(rows) => rows.clone(),
        p => {
            let mut c = vec![(0.0, p.omega(0.0))];
            if let Some(te) = p.end_time()
                && te > 0.0
            {
                c.push((te, p.omega(te)));
            }
            c.push((d, p.omega(d)));
            c
        }
    };
    let info = TransientInfo {
        profile: describe_profile(&settings.profile),
        start: start.label.clone(),
        duration_s: d,
        profile_time_s: corners.iter().map(|c| c.0).collect(),
        profile_omega_rad_s: corners.iter().map(|c| c.1).collect(),
        thermal_stepping: describe_thermal(settings.options.thermal),
        rtol: settings.options.rtol,
        atol: settings.options.atol,
        window_revolutions: window,
        samples_per_revolution: settings.samples_per_revolution,
    };
    let mut integ = Transient::new(
        sys,
        settings.profile.clone(),
        &start.x,
        &start.v,
        &start.temp,
        settings.options,
    )?;
    sink.begin_transient(run, &info)?;
    let outcome = drive(
        problem,
        &mut integ,
        settings,
        window,
        sink,
        progress,
        interrupt.as_deref(),
    );
    let status = match &outcome {
        Ok(r) if r.interrupted => RunStatus::Interrupted,
        Ok(_) => RunStatus::Completed,
        Err(e) => RunStatus::Failed(e.to_string()),
    };
    let finished = sink.finish_transient(status);
    let report = outcome?;
    finished?;
    Ok(report)
}

/// Adds step `s` of length `h` to the revolution under way, `current`: its span and step
/// count, and at each dynamic node of `run` the trapezoidal integrals of x, y, x² and y²
/// from the node's previous position in `last_xy` (moved on to this step's) and the
/// extremes.
fn add_step(
    current: &mut RevolutionSums,
    run: &RunInfo,
    s: &StepView<'_>,
    h: f64,
    last_xy: &mut [(f64, f64)],
) {
    current.span += h;
    current.steps += 1;
    for (k, n) in run.nodes.iter().enumerate() {
        let (x, y) = (s.x[n.dof_x], s.x[n.dof_y]);
        let (x0, y0) = last_xy[k];
        let acc = &mut current.sums[k];
        acc[0] += 0.5 * h * (x + x0);
        acc[1] += 0.5 * h * (y + y0);
        acc[2] += 0.5 * h * (x * x + x0 * x0);
        acc[3] += 0.5 * h * (y * y + y0 * y0);
        widen(&mut current.extremes[k], &[x, x, y, y]);
        last_xy[k] = (x, y);
    }
}

/// The displacement samples of step `s` at the dynamic nodes of `run`.
fn samples(run: &RunInfo, s: &StepView<'_>) -> Samples {
    let x_m: Vec<f64> = run.nodes.iter().map(|n| s.x[n.dof_x]).collect();
    let y_m: Vec<f64> = run.nodes.iter().map(|n| s.x[n.dof_y]).collect();
    Samples {
        time_s: s.t,
        omega_rad_s: s.omega,
        x_um: to_micrometres(&x_m),
        y_um: to_micrometres(&y_m),
        x_m,
        y_m,
    }
}

/// The record of revolution `revolution`, which step `s` (of length `h`) completes after
/// `steps` steps: each dynamic node's RMS and peak amplitude over the window `history` (the
/// revolution's sums last), and at `s` the temperatures, the bearings' clearance changes,
/// their clearances (from `clearances0`) and loads, with each load's largest value over the
/// revolution.
fn revolution_record(
    problem: &SweepProblem,
    clearances0: &[f64],
    history: &std::collections::VecDeque<RevolutionSums>,
    s: &StepView<'_>,
    revolution: u64,
    steps: u32,
    h: f64,
) -> Revolution {
    let sys = &problem.system;
    let run = &problem.run;
    let n_nodes = run.nodes.len();
    let ts = s.phase / s.omega;
    let span: f64 = history.iter().map(|r| r.span).sum();
    let mut rms = Vec::with_capacity(n_nodes);
    let mut peak = Vec::with_capacity(n_nodes);
    for k in 0..n_nodes {
        let mut acc = [0.0; 4];
        let mut ext = NO_EXTREMES;
        for r in history {
            for (a, v) in acc.iter_mut().zip(&r.sums[k]) {
                *a += v;
            }
            widen(&mut ext, &r.extremes[k]);
        }
        let (mx, my) = (acc[0] / span, acc[1] / span);
        let var = (acc[2] / span - mx * mx).max(0.0) + (acc[3] / span - my * my).max(0.0);
        rms.push(var.sqrt());
        let dx = (ext[0] - mx).abs().max((ext[1] - mx).abs());
        let dy = (ext[2] - my).abs().max((ext[3] - my).abs());
        peak.push(dx.hypot(dy));
    }
    let states = sys.bearing_states(s.omega, ts, s.x, s.temp);
    let delta_v_m: Vec<f64> = states.iter().map(|b| b.delta_v_m).collect();
    let effective_clearance_m: Vec<f64> = states
        .iter()
        .zip(clearances0)
        .map(|(b, c0)| c0 + b.delta_v_m)
        .collect();
    Revolution {
        index: revolution,
        time_s: s.t,
        omega_rad_s: s.omega,
        amplitude_rms_um: to_micrometres(&rms),
        amplitude_max_um: to_micrometres(&peak),
        delta_v_um: to_micrometres(&delta_v_m),
        effective_clearance_um: to_micrometres(&effective_clearance_m),
        amplitude_rms_m: rms,
        amplitude_max_m: peak,
        temperature_c: run.thermal_nodes.iter().map(|n| s.temp[n.dof]).collect(),
        delta_v_m,
        effective_clearance_m,
        bearing_load_n: states.iter().map(|b| b.fb_n).collect(),
        bearing_load_max_n: history
            .back()
            .map_or(&[][..], |r| &r.load_max)
            .iter()
            .zip(&states)
            .map(|(m, b)| m.max(b.fb_n))
            .collect(),
        step_count: steps,
        last_step_s: h,
    }
}

fn drive(
    problem: &SweepProblem,
    integ: &mut Transient<'_>,
    settings: &TransientSettings,
    window: u32,
    sink: &mut dyn TransientSink,
    progress: &mut dyn FnMut(&Revolution),
    interrupt: Option<&AtomicBool>,
) -> Result<TransientReport, TransientError> {
    let sys = &problem.system;
    let run = &problem.run;
    let n_nodes = run.nodes.len();
    let n_bear = run.bearings.len();
    let clearances0 = sys.initial_clearances_m();
    let wall = Instant::now();
    let tau = std::f64::consts::TAU;
    let samples_per_rev = settings.samples_per_revolution;
    let load_samples = samples_per_rev.max(16);
    let mut current = RevolutionSums::new(n_nodes, n_bear);
    let mut history: std::collections::VecDeque<RevolutionSums> = Default::default();
    let mut revolution: u64 = 0;
    let mut last_t = 0.0;
    let mut last_xy: Vec<(f64, f64)> = run
        .nodes
        .iter()
        .map(|n| {
            let (x, _, _) = integ.state();
            (x[n.dof_x], x[n.dof_y])
        })
        .collect();
    let mut next_sample_phase = 0.0;
    let mut next_load_phase = 0.0;
    let mut failure: Option<TransientError> = None;
    let mut interrupted = false;
    let mut last_rev: Option<Revolution> = None;
    let mut observer = |s: &StepView<'_>| -> bool {
        if interrupt.is_some_and(|f| f.load(Ordering::Relaxed)) {
            interrupted = true;
            return false;
        }
        let h = s.t - last_t;
        last_t = s.t;
        add_step(&mut current, run, s, h, &mut last_xy);
        let ts = s.phase / s.omega;
        if samples_per_rev > 0 && s.phase >= next_sample_phase {
            // on a grid of phases: the first step at or past each grid angle
            let spacing = tau / f64::from(samples_per_rev);
            while next_sample_phase <= s.phase {
                next_sample_phase += spacing;
            }
            let msg = samples(run, s);
            if let Err(e) = sink.write_samples(&msg) {
                failure = Some(e.into());
                return false;
            }
        }
        if n_bear > 0 && s.phase >= next_load_phase {
            let spacing = tau / f64::from(load_samples);
            while next_load_phase <= s.phase {
                next_load_phase += spacing;
            }
            for (m, b) in current
                .load_max
                .iter_mut()
                .zip(sys.bearing_states(s.omega, ts, s.x, s.temp))
            {
                *m = m.max(b.fb_n);
            }
        }
        if s.phase < tau * (revolution + 1) as f64 {
            return true;
        }
        revolution += 1;
        let done = std::mem::replace(&mut current, RevolutionSums::new(n_nodes, n_bear));
        let steps = done.steps;
        history.push_back(done);
        while history.len() > window as usize {
            history.pop_front();
        }
        let msg = revolution_record(problem, &clearances0, &history, s, revolution, steps, h);
        if let Err(e) = sink.write_revolution(&msg) {
            failure = Some(e.into());
            return false;
        }
        progress(&msg);
        last_rev = Some(msg);
        true
    };
    let reached = integ.advance(settings.duration_s, &mut observer);
    if let Some(e) = failure {
        return Err(e);
    }
    reached?;
    Ok(TransientReport {
        revolutions: revolution,
        simulated_s: integ.time(),
        wall_s: wall.elapsed().as_secs_f64(),
        stats: integ.stats(),
        interrupted,
        last: last_rev,
    })
}
