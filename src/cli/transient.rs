//! `tmrotor transient`: the coupled rotor integrated in time (a fixed speed, a run-up or
//! coast-down, or a table of speeds), from a cold start or from a recorded point, written
//! to an MCAP recording on the simulated time axis.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use indicatif::ProgressBar;

use super::sweep::{StudyArgs, parse_range};
use crate::cli::interrupt::install_interrupt_flag;
use crate::integrate::IntegrateError;
use crate::integrate::{SpeedProfile, ThermalStepping, TransientOptions};
use crate::record::McapOptions;
use crate::record::output::check_target;
use crate::study::SweepProblem;
use crate::transient::{
    RecordedStart, StartState, TransientSettings, describe_profile, run_transient,
};

/// Speed profile, start state and integrator settings of a transient run.
#[derive(Debug, Clone, Args)]
pub struct TransientArgs {
    #[command(flatten)]
    pub base: StudyArgs,
    /// Truncation order of the harmonic basis: sets the recording's basis and the window of
    /// the RMS amplitudes (the basis's period) [default: 3].
    #[arg(long, allow_negative_numbers = true)]
    pub order: Option<u32>,
    /// Mechanical model only (no thermal network, clearances fixed at δ0).
    #[arg(long)]
    pub no_thermal: bool,
    /// A fixed speed, rad/s (default with --from: the point's speed).
    #[arg(long, value_name = "RAD_S", allow_negative_numbers = true)]
    pub speed: Option<f64>,
    /// A linear run-up (START < END) or coast-down (START > END), rad/s, at --accel.
    #[arg(
        long,
        value_name = "START:END",
        conflicts_with = "speed",
        allow_hyphen_values = true
    )]
    pub ramp: Option<String>,
    /// Magnitude of the ramp's acceleration, rad/s² [default: 10].
    #[arg(
        long,
        value_name = "RAD_S2",
        requires = "ramp",
        allow_negative_numbers = true
    )]
    pub accel: Option<f64>,
    /// A speed table: a CSV file of `time_s,omega_rad_s` rows (a header line is allowed),
    /// times increasing from 0; the speed is linear between rows and held after the last.
    #[arg(long, value_name = "CSV", conflicts_with_all = ["speed", "ramp"])]
    pub profile: Option<PathBuf>,
    /// Simulated time, s [default: the ramp's or table's end plus 1 s; 100 revolutions at a
    /// fixed speed].
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Start on the orbit of a point of this sweep recording (with --point) instead of a
    /// cold start; the model and study are the recording's.
    #[arg(long, value_name = "RECORDING", requires = "point")]
    pub from: Option<PathBuf>,
    /// Index of the recorded point to start from.
    #[arg(
        long,
        value_name = "I",
        requires = "from",
        allow_negative_numbers = true
    )]
    pub point: Option<u64>,
    /// Scale the start's vibration (displacements about their mean, and velocities) by
    /// 1 + F, e.g. 0.05 for a 5 % larger orbit.
    #[arg(
        long,
        value_name = "F",
        allow_negative_numbers = true,
        default_value_t = 0.0
    )]
    pub perturb: f64,
    /// With --from: perturb along the K-th Floquet mode of the point nearest zero instead
    /// of scaling the vibration (Hill's eigenproblem; 0 = the mode with the largest real
    /// part of its exponent, the most unstable or least stable), by --perturb times the
    /// orbit's largest vibration amplitude (its sign the direction).
    #[arg(
        long,
        value_name = "K",
        requires = "from",
        allow_negative_numbers = true
    )]
    pub perturb_mode: Option<usize>,
    /// Add K kelvin to every start temperature.
    #[arg(
        long,
        value_name = "K",
        allow_negative_numbers = true,
        default_value_t = 0.0
    )]
    pub perturb_temp: f64,
    /// Relative local error tolerance of the mechanical integrator [default: 1e-4].
    #[arg(long, allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// HHT-α parameter in [−1/3, 0]: 0 is the trapezoidal rule (no numerical damping),
    /// below 0 damps the unresolved upper modes [default: −0.05].
    #[arg(long, value_name = "ALPHA", allow_negative_numbers = true)]
    pub alpha: Option<f64>,
    /// Advance the temperatures after every mechanical step with that step's heat (single
    /// rate, the reference for the default averaged macro steps).
    #[arg(long)]
    pub single_rate: bool,
    /// Most revolutions in one thermal macro step [default: 50].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub max_thermal_revolutions: Option<u32>,
    /// Displacement samples per revolution on /transient/samples; 0 for none [default: 16].
    #[arg(long, value_name = "N", default_value_t = crate::transient::DEFAULT_SAMPLES_PER_REVOLUTION, allow_negative_numbers = true)]
    pub samples_per_rev: u32,
    /// Output recording.
    #[arg(short, long, default_value = "transient.mcap")]
    pub output: PathBuf,
    /// No progress output.
    #[arg(long, short)]
    pub quiet: bool,
}

pub use crate::transient::DEFAULT_RTOL;

/// Reads a `time_s,omega_rad_s` table.
fn read_table(path: &Path) -> anyhow::Result<Vec<(f64, f64)>> {
    let text = crate::input::read_text(path, crate::input::MAX_INPUT_BYTES)
        .with_context(|| format!("reading speed table {}", path.display()))?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut cols = line.split(',').map(str::trim);
        let (Some(a), Some(b), None) = (cols.next(), cols.next(), cols.next()) else {
            bail!(
                "{}:{}: expected two columns time_s,omega_rad_s",
                path.display(),
                i + 1
            );
        };
        match (a.parse::<f64>(), b.parse::<f64>()) {
            (Ok(t), Ok(w)) => rows.push((t, w)),
            _ if rows.is_empty() && i == 0 => {} // header
            _ => bail!("{}:{}: {line:?} is not two numbers", path.display(), i + 1),
        }
    }
    let profile = SpeedProfile::Table(rows.clone());
    profile
        .check()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(rows)
}

impl TransientArgs {
    fn profile(&self, start_speed: Option<f64>) -> anyhow::Result<SpeedProfile> {
        let profile = if let Some(r) = &self.ramp {
            let (from, to) = parse_range("--ramp", r)?;
            if from == to {
                bail!("--ramp {r}: START and END are equal; use --speed for a fixed speed");
            }
            SpeedProfile::Ramp {
                from,
                to,
                accel: self.accel.unwrap_or(10.0),
            }
        } else if let Some(path) = &self.profile {
            SpeedProfile::Table(read_table(path)?)
        } else if let Some(w) = self.speed.or(start_speed) {
            SpeedProfile::Constant(w)
        } else {
            bail!(
                "no speed: give --speed RAD_S, --ramp START:END, --profile CSV or --from REC --point I"
            );
        };
        let flag = if self.ramp.is_some() {
            "--ramp/--accel"
        } else if self.profile.is_some() {
            "--profile"
        } else if self.speed.is_some() {
            "--speed"
        } else {
            "the recorded point's speed"
        };
        profile
            .check()
            .map_err(|e| anyhow::anyhow!("{flag}: {e}"))?;
        Ok(profile)
    }

    fn options(&self) -> anyhow::Result<TransientOptions> {
        let mut o = TransientOptions {
            rtol: self.rtol.unwrap_or(DEFAULT_RTOL),
            ..TransientOptions::default()
        };
        if let Some(a) = self.alpha {
            o.alpha = a;
        }
        if self.single_rate {
            o.thermal = ThermalStepping::EveryStep;
        } else if let Some(n) = self.max_thermal_revolutions {
            if n == 0 {
                bail!("--max-thermal-revolutions 0: at least 1 revolution a thermal step");
            }
            if let ThermalStepping::Averaged {
                max_revolutions, ..
            } = &mut o.thermal
            {
                *max_revolutions = n;
            }
        }
        if !(self.perturb.is_finite() && self.perturb > -1.0) {
            bail!(
                "--perturb {}: the factor must be finite and above -1",
                self.perturb
            );
        }
        if !self.perturb_temp.is_finite() || self.perturb_temp.abs() > 500.0 {
            bail!("--perturb-temp {}: at most ±500 K", self.perturb_temp);
        }
        if self.samples_per_rev > 4096 {
            bail!("--samples-per-rev {}: at most 4096", self.samples_per_rev);
        }
        // the integrator's own checks, before the output is opened
        o.check().map_err(|e| match e {
            IntegrateError::Setting { field: "rtol", .. } => anyhow::anyhow!("--rtol: {e}"),
            IntegrateError::Setting { field: "alpha", .. } => anyhow::anyhow!("--alpha: {e}"),
            e => anyhow::anyhow!("{e}"),
        })?;
        Ok(o)
    }
}

/// Runs the transient and prints a summary.
pub fn run(args: &TransientArgs, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = Vec::new();
    inputs.extend(args.base.model.as_deref());
    inputs.extend(args.base.study.as_deref());
    inputs.extend(args.from.as_deref());
    inputs.extend(args.profile.as_deref());
    check_target(&args.output, &inputs)?;
    let options = args.options()?;
    let (problem, start, start_speed) = match (&args.from, args.point) {
        (Some(rec_path), Some(index)) => {
            if args.base.model.is_some() || args.base.study.is_some() || !args.base.set.is_empty() {
                bail!(
                    "--from takes the model and study of the recording; leave out --model, --study and --set"
                );
            }
            let recorded = RecordedStart::read(rec_path, index)?;
            let start = match args.perturb_mode {
                None => recorded.on_orbit(args.perturb, args.perturb_temp),
                Some(k) => {
                    if args.perturb == 0.0 {
                        bail!(
                            "--perturb-mode {k}: give the size with --perturb (a fraction of \
                             the orbit's vibration, e.g. 0.01)"
                        );
                    }
                    let (start, mode) = recorded.along_mode(k, args.perturb, args.perturb_temp)?;
                    if !args.quiet {
                        eprintln!(
                            "transient: start along the Floquet mode of exponent {:.4e}{:+.4e}i \
                             1/s (period of the orbit {:.4e} s)",
                            mode.exponent.re,
                            mode.exponent.im,
                            crate::system::PeriodicOrbit::period(&recorded.orbit)
                        );
                    }
                    start
                }
            };
            let omega = recorded.omega;
            (recorded.problem, start, Some(omega))
        }
        _ => {
            let mut settings = args.base.settings()?;
            if let Some(o) = args.order {
                settings.harmonic.order = o;
            }
            if args.no_thermal {
                settings.operating.thermal = false;
            }
            let problem = SweepProblem::new(&settings)?;
            let cold = StartState::cold(&problem);
            let mean = cold.x.clone();
            let start = cold.perturbed(&mean, 0.0, args.perturb_temp);
            (problem, start, None)
        }
    };
    let profile = args.profile(start_speed)?;
    let duration = args.duration.unwrap_or_else(|| profile.default_duration());
    if !(duration.is_finite() && duration > 0.0) {
        bail!("--duration {duration}: the simulated time must be finite and above 0 s");
    }
    let settings = TransientSettings {
        profile: profile.clone(),
        duration_s: duration,
        options,
        samples_per_revolution: args.samples_per_rev,
    };
    let mut sink = super::create_recording(&args.output, McapOptions::default())?;
    let interrupt = install_interrupt_flag().ok();
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new((duration * 1000.0).ceil() as u64);
        b.set_style(super::bar_style("{elapsed_precise} [{bar:30}] {msg}"));
        b
    };
    let log = !args.quiet && !std::io::stderr().is_terminal();
    if log {
        eprintln!(
            "transient: {}, {duration} s simulated, start: {}; writing {}",
            describe_profile(&profile),
            start.label,
            args.output.display()
        );
    }
    let mut last_line = Instant::now();
    let report = run_transient(
        &problem,
        &start,
        &settings,
        &mut sink,
        &mut |r| {
            bar.set_position((r.time_s * 1000.0) as u64);
            let msg = format!(
                "t {:.3} s  ω {:.2} rad/s  largest RMS amplitude {:.3} µm",
                r.time_s,
                r.omega_rad_s,
                crate::record::transient::largest_amplitude(r).1 * 1e6
            );
            if log && last_line.elapsed() >= super::LOG_EVERY {
                last_line = Instant::now();
                eprintln!("{msg}");
            }
            bar.set_message(msg);
        },
        interrupt,
    )?;
    bar.finish_and_clear();
    writeln!(
        out,
        "{} revolutions, {:.4} s simulated in {:.1} s ({:.3} simulated s per wall s); {} steps ({} rejected), {} thermal steps, {} factorizations",
        report.revolutions,
        report.simulated_s,
        report.wall_s,
        report.speed(),
        report.stats.accepted,
        report.stats.rejected,
        report.stats.thermal_steps,
        report.stats.factorizations
    )?;
    if let Some(last) = &report.last {
        let run = &problem.run;
        let (k, a) = crate::record::transient::largest_amplitude(last);
        let node = run.nodes.get(k).map_or("?", |n| n.name.as_str());
        writeln!(
            out,
            "at the end: ω {:.3} rad/s, largest RMS amplitude {:.4} µm at {node}{}",
            last.omega_rad_s,
            a * 1e6,
            last.temperature_c
                .iter()
                .cloned()
                .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
                .map_or(String::new(), |t| format!(", hottest node {t:.2} °C"))
        )?;
    }
    writeln!(out, "recording: {}", args.output.display())?;
    if report.interrupted {
        return Err(super::Interrupted(format!(
            "the transient stopped after {} revolutions ({:.4} s simulated); {} is a complete recording of them",
            report.revolutions,
            report.simulated_s,
            args.output.display()
        ))
        .into());
    }
    Ok(())
}
