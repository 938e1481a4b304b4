//! `tmrotor sweep`: one continuation sweep written to an MCAP recording.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;

use crate::cli::interrupt::install_interrupt_flag;
use crate::derive::PERIOD_DOUBLED_SHARE;
use crate::record::McapOptions;
use crate::stability::IntervalMap;
use crate::study::{StabilityChoice, parse_name};
use crate::sweep::{Progress, StudySettings, SweepProblem, SweepReport};

/// The study flags shared by `tmrotor sweep` and `tmrotor truncation`: model, study file,
/// flow rate and temperatures.
#[derive(Debug, Clone, Args)]
pub struct StudyArgs {
    /// Model file (TOML); default: the built-in dual rotor (`tmrotor model show`).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Study settings file (TOML, keys of `StudySettings`); flags override it.
    #[arg(long)]
    pub study: Option<PathBuf>,
    /// Lubricant flow rate per bearing q_l (L/min) [default: 2].
    #[arg(long = "flow", value_name = "L_MIN", allow_negative_numbers = true)]
    pub flow_l_min: Option<f64>,
    /// Lubricant cooling temperature (°C) [default: 25].
    #[arg(long = "cooling-temp", value_name = "C", allow_negative_numbers = true)]
    pub cooling_temp_c: Option<f64>,
    /// Ambient temperature (°C) [default: 25].
    #[arg(long = "ambient-temp", value_name = "C", allow_negative_numbers = true)]
    pub ambient_temp_c: Option<f64>,
    /// Set a value of the model file by its path before it is checked, e.g.
    /// `--set 'thermal.bearings[2#].f_v=3.0'` (repeatable; the value is TOML; see
    /// docs/model-reference.md, "Setting values by path").
    #[arg(long = "set", value_name = "PATH=VALUE", value_parser = parse_set)]
    pub set: Vec<(String, toml::Value)>,
}

fn parse_set(text: &str) -> Result<(String, toml::Value), String> {
    crate::model::set::parse_assignment(text)
}

impl StudyArgs {
    /// The study file's settings (or the defaults) with these flags applied.
    pub fn settings(&self) -> anyhow::Result<StudySettings> {
        let mut s = load_study(self.study.as_deref())?;
        if self.model.is_some() {
            s.model = self.model.clone();
        }
        if let Some(v) = self.flow_l_min {
            s.operating.flow_l_min = v;
        }
        if let Some(v) = self.cooling_temp_c {
            s.operating.cooling_temp_c = v;
        }
        if let Some(v) = self.ambient_temp_c {
            s.operating.ambient_temp_c = v;
        }
        s.set.extend(self.set.iter().cloned());
        Ok(s)
    }
}

/// Study parameters; every default is the paper's default study.
#[derive(Debug, Clone, Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub base: StudyArgs,
    /// Truncation order of the harmonic basis (paper Eq. 34) [default: 3].
    #[arg(long, allow_negative_numbers = true)]
    pub order: Option<u32>,
    /// Sweep range START:END in rad/s [default: 300:700].
    #[arg(long, value_name = "START:END", allow_hyphen_values = true)]
    pub omega: Option<String>,
    /// Largest continuation step (scaled arclength) [default: 0.15].
    #[arg(long, allow_negative_numbers = true)]
    pub ds_max: Option<f64>,
    /// Maximum number of points [default: 2000].
    #[arg(long, allow_negative_numbers = true)]
    pub max_points: Option<usize>,
    /// Mechanical model only (no thermal network, clearances fixed at δ0).
    #[arg(long)]
    pub no_thermal: bool,
    /// Leave out the half orders of the paper's basis that the rotor speeds cannot make
    /// (ω/2 for λ = 6/5): the primary response on its own period, its period doublings
    /// located as such.
    #[arg(long)]
    pub no_half_orders: bool,
    /// Add the combination tones of the two rotors' speeds to the basis (ω/5, 4ω/5, 11ω/5,
    /// … for λ = 6/5; study key `combination_tones`): the paper's basis has none, the
    /// bearings make them (about 10 % of the amplitude near 522 rad/s on the built-in
    /// model, docs/transient.md); 2.4× the harmonics, several times the cost.
    #[arg(long)]
    pub combination_tones: bool,
    /// Integrate every rolling element's contact exactly between the instants where it
    /// takes up and loses its load, instead of sampling the bearings (study key
    /// `exact_contacts`): where elements lose contact, sampling moves folds and makes tiny
    /// artefact fold pairs that no multiplier confirms; several times the cost per point
    #[arg(long)]
    pub exact_contacts: bool,
    /// Do not follow the period-doubled branches from the period doublings located on the
    /// primary basis (with --no-half-orders the sweep follows each as a branch of its own).
    #[arg(long)]
    pub no_switch: bool,
    /// Skip Floquet stability (faster; no stable flags, and of the bifurcations only the
    /// saddle-nodes, which are the folds of the branch and need no multipliers).
    #[arg(long)]
    pub no_stability: bool,
    /// Floquet method: exp-sip (exponential-split SIP, default) or sip (the paper's
    /// explicit product, Eq. 33; refuses stiff models).
    #[arg(long, value_name = "METHOD", value_parser = parse_name::<StabilityChoice>)]
    pub stability_method: Option<StabilityChoice>,
    /// SIP intervals per period (exp-sip: the start, extrapolated with half as many and
    /// doubled up to 4096 where a multiplier is close to the unit circle) [default: 512].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub sip_intervals: Option<usize>,
    /// Interval map of the exp-sip product: exponential (default; exact for the
    /// quasi-static response of stiff modes) or strang (the midpoint split of earlier
    /// versions).
    #[arg(long, value_name = "MAP", value_parser = parse_name::<IntervalMap>)]
    pub interval_map: Option<IntervalMap>,
    /// Cut-off (rad/s) of the Craig–Bampton reduction used for stability; 0 = full model
    /// [default: 20000].
    #[arg(long, value_name = "RAD_S", allow_negative_numbers = true)]
    pub reduction_cutoff: Option<f64>,
    /// Output recording.
    #[arg(short, long, default_value = "sweep.mcap")]
    pub output: PathBuf,
    /// Lean recording: leave out /orbits and /scene, which replay and the Python package
    /// re-derive from /harmonics (about a fifth of the size; a viewer's 3D panel then has
    /// nothing to draw)
    #[arg(long)]
    pub lean: bool,
    /// No progress: no bar on a terminal, no progress lines when the output goes to a file.
    #[arg(long, short)]
    pub quiet: bool,
    /// More detail in the closing summary (the Floquet kernel's instruction set).
    #[arg(long, short)]
    pub verbose: bool,
    /// Do not re-solve the located bifurcations and unlocated changes of stability at
    /// higher truncation orders after the branch (study key `verify = false`). By default
    /// each is re-solved at the order + 1 and + 2 in a window of ±1 rad/s and the summary
    /// and `/truncation` say whether it holds, moved or vanished; a vanished one is not a
    /// result of the model. A few seconds per group of bifurcations.
    #[arg(long)]
    pub no_verify: bool,
    /// The orders of that check, e.g. `4,5,7` (study key `verify_orders`; default the
    /// order + 1 and + 2).
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub verify_orders: Vec<u32>,
}

impl SweepArgs {
    /// The settings these arguments describe.
    pub fn settings(&self) -> anyhow::Result<StudySettings> {
        let mut s = self.base.settings()?;
        if let Some(v) = self.order {
            s.harmonic.order = v;
        }
        if let Some(r) = &self.omega {
            (s.sweep.omega_start, s.sweep.omega_end) = parse_range("--omega", r)?;
        }
        if let Some(v) = self.ds_max {
            s.sweep.ds_max = v;
        }
        if let Some(v) = self.max_points {
            s.sweep.max_points = v;
        }
        if self.no_verify {
            s.floquet.verify = false;
        }
        if !self.verify_orders.is_empty() {
            s.floquet.verify_orders = self.verify_orders.clone();
        }
        if self.no_thermal {
            s.operating.thermal = false;
        }
        if self.no_half_orders {
            s.harmonic.half_orders = false;
        }
        if self.combination_tones {
            s.harmonic.combination_tones = true;
        }
        if self.exact_contacts {
            s.harmonic.exact_contacts = true;
        }
        if self.no_switch {
            s.sweep.switch_branches = false;
        }
        if self.no_stability {
            s.floquet.stability = false;
        }
        if let Some(m) = self.stability_method {
            s.floquet.stability_method = m;
        }
        if let Some(v) = self.sip_intervals {
            s.floquet.sip_intervals = v;
        }
        if let Some(m) = self.interval_map {
            s.floquet.interval_map = m;
        }
        if let Some(v) = self.reduction_cutoff {
            s.floquet.reduction_cutoff_rad_s = v;
        }
        Ok(s)
    }
}

/// Study settings from a TOML file (keys of `StudySettings`), or the defaults.
pub fn load_study(path: Option<&std::path::Path>) -> anyhow::Result<StudySettings> {
    match path {
        Some(path) => {
            let text = crate::input::read_text(path, crate::input::MAX_INPUT_BYTES)
                .with_context(|| format!("reading study file {}", path.display()))?;
            toml::from_str::<StudySettings>(&text)
                .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))
        }
        None => Ok(StudySettings::default()),
    }
}

/// `START:END` in rad/s for option `option`.
pub fn parse_range(option: &str, r: &str) -> anyhow::Result<(f64, f64)> {
    let (a, b) = r
        .split_once(':')
        .ok_or_else(|| anyhow::anyhow!("{option} {r:?}: expected START:END in rad/s"))?;
    let start = a
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("{option} {r:?}: START is not a number"))?;
    let end = b
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("{option} {r:?}: END is not a number"))?;
    Ok((start, end))
}

/// Runs the sweep and prints a summary.
pub fn run(args: &SweepArgs, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    let (cpu_start, steal_start) = (super::process_cpu_seconds(), super::steal_seconds());
    let mut inputs: Vec<&std::path::Path> = Vec::new();
    inputs.extend(args.base.model.as_deref());
    inputs.extend(args.base.study.as_deref());
    crate::record::output::check_target(&args.output, &inputs)?;
    let settings = args.settings()?;
    let problem = SweepProblem::new(&settings)?;
    let options = if args.lean {
        McapOptions::lean()
    } else {
        McapOptions::default()
    };
    let mut sink = super::create_recording(&args.output, options)?;
    let interrupt = install_interrupt_flag().ok();
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(1000);
        b.set_style(super::bar_style("{elapsed_precise} [{bar:30}] ω {msg}"));
        b
    };
    // not on a terminal (a log file, a cluster job's output): plain lines instead of a bar
    let log = !args.quiet && !std::io::stderr().is_terminal();
    if log {
        eprintln!(
            "sweep: ω {} → {} rad/s, order {}, writing {} (as {} until the run ends)",
            settings.sweep.omega_start,
            settings.sweep.omega_end,
            settings.harmonic.order,
            args.output.display(),
            sink.path().display()
        );
    }
    let start = Instant::now();
    let mut last_line = start;
    let report = problem.run(&mut sink, interrupt, |p| {
        bar.set_position((p.fraction * 1000.0) as u64);
        bar.set_message(progress_message(p, ""));
        if log && last_line.elapsed() >= super::LOG_EVERY {
            last_line = Instant::now();
            eprintln!(
                "sweep: {} after {:.0} s",
                progress_message(p, "ω "),
                start.elapsed().as_secs_f64()
            );
        }
    });
    bar.finish_and_clear();
    let report = report.with_context(|| {
        if sink.committed() {
            format!(
                "sweep failed; the points computed so far are in {}",
                args.output.display()
            )
        } else {
            format!(
                "sweep failed before its first point; the earlier recording {} is kept",
                args.output.display()
            )
        }
    })?;
    outcome_summary(args, &report, (cpu_start, steal_start), out)?;
    branches_summary(&settings, &problem, &report, out)?;
    warnings_summary(&report, out)?;
    let file = args.output.display();
    writeln!(
        out,
        "next: replay info {file}; replay plot {file} --out figures/; or open it in Foxglove \
         or Rerun (docs/user-guide.md)"
    )?;
    if report.status == crate::record::RunStatus::Interrupted {
        return Err(super::Interrupted(format!(
            "the sweep stopped after {} points; {} is a complete recording of them",
            report.points,
            args.output.display()
        ))
        .into());
    }
    Ok(())
}

/// What the sweep did: its points and time, how the branch started and ended, the
/// refused steps, and the truncation checks.
fn outcome_summary(
    args: &SweepArgs,
    report: &SweepReport,
    (cpu_start, steal_start): (Option<f64>, Option<f64>),
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    writeln!(
        out,
        "{} in {:.1} s, {} → {}",
        plural(report.points, "point", "points"),
        report.total_seconds,
        report.status.label(),
        args.output.display()
    )?;
    if report.stable_points + report.unstable_points > 0 {
        writeln!(
            out,
            "  {} stable, {} unstable",
            report.stable_points, report.unstable_points
        )?;
    }
    writeln!(out, "  time: {}", report.time_summary_with(args.verbose))?;
    let cpu = super::cpu_seconds_since(cpu_start);
    if let Some(share) = super::cpu_share(report.total_seconds, cpu) {
        let steal = super::steal_note(steal_start, report.total_seconds);
        writeln!(out, "  {share}{steal}")?;
    }
    if let Some(from) = report.lead_in_from {
        writeln!(
            out,
            "  the start did not converge from the linear response; it was reached by \
             continuation from {from:.3} rad/s (not recorded)"
        )?;
    }
    if let Some(finish) = &report.finish {
        writeln!(out, "  the branch {finish}")?;
    }
    if report.rejected_steps > 0 {
        writeln!(
            out,
            "  {} refused and retried with half the step",
            plural(report.rejected_steps, "step", "steps")
        )?;
    }
    if let Some(note) = &report.stability_note {
        writeln!(out, "  stability not assessed: {note}")?;
    }
    truncation_summary(report, out)?;
    Ok(())
}

/// The period doublings (followed or why not), the switched branches and the
/// period-doubled stretches of the response.
fn branches_summary(
    settings: &StudySettings,
    problem: &SweepProblem,
    report: &SweepReport,
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    let doublings = report
        .bifurcations
        .iter()
        .filter(|(_, k)| k.starts_with("period-doubling"))
        .count();
    if doublings > 0 && report.branches.is_empty() && !problem.switches_branches() {
        let why = if !settings.sweep.switch_branches {
            "--no-switch (or switch_branches = false) leaves them"
        } else if !settings.floquet.stability {
            "switching needs stability"
        } else {
            "the basis holds the half orders of Eq. 34, on which a doubled response has no \
             branch of its own; --no-half-orders sweeps on the primary basis and follows each \
             doubled branch as a branch of its own"
        };
        writeln!(
            out,
            "  {} located, not followed: {why}",
            plural(doublings, "period doubling", "period doublings")
        )?;
    }
    for b in &report.branches {
        writeln!(
            out,
            "  branch {}: period-doubled, from the period doubling at ω = {:.3} rad/s, {} over {:.3}–{:.3} rad/s; {}",
            b.branch,
            b.origin_omega_rad_s,
            plural(b.points, "point", "points"),
            b.omega_range.0,
            b.omega_range.1,
            b.end
        )?;
        writeln!(
            out,
            "    {:.1} s: start {:.1} s, {}",
            b.seconds,
            b.switch_seconds,
            b.timings.summary(false)
        )?;
        for (w, kind) in &b.bifurcations {
            writeln!(out, "    {}", located_line(kind, *w))?;
        }
    }
    for st in &report.period_doubled {
        writeln!(
            out,
            "  period-doubled response (ω/2 share ≥ {:.0} %) on {st}",
            100.0 * PERIOD_DOUBLED_SHARE
        )?;
    }
    if !report.period_doubled.is_empty() {
        writeln!(
            out,
            "  the branch ran into a period-doubled response; --no-half-orders follows the \
             primary response on its own period (docs/user-guide.md, \"The primary basis\")"
        )?;
    }
    Ok(())
}

/// The first warnings, and how many more the recording's log holds.
fn warnings_summary(report: &SweepReport, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    const SHOWN_WARNINGS: usize = 5;
    for w in report.warnings.iter().take(SHOWN_WARNINGS) {
        writeln!(out, "  warning: {w}")?;
    }
    if report.warnings.len() > SHOWN_WARNINGS {
        writeln!(
            out,
            "  … and {} more in the recording's /log (replay info lists them)",
            plural(
                report.warnings.len() - SHOWN_WARNINGS,
                "warning",
                "warnings"
            )
        )?;
    }
    Ok(())
}

/// `"1 point"`, `"2 points"`.
pub fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The progress bar's message: speed, points and bifurcations, or the lead-in's speed while
/// the start is being reached (`omega` prefixes the speed).
pub fn progress_message(p: &Progress, omega: &str) -> String {
    if p.lead_in {
        format!(
            "{omega}{:.1} rad/s: reaching the start by continuation (not recorded)",
            p.omega_rad_s
        )
    } else if let Some((done, batch, n)) = p.switching {
        format!(
            "{}, {}: following {} at once ({done} of at most {n} recorded)",
            plural(p.points, "point", "points"),
            plural(p.bifurcations, "bifurcation", "bifurcations"),
            plural(batch, "period-doubled branch", "period-doubled branches")
        )
    } else if p.verifying {
        format!(
            "{}, {}: re-solving them at higher truncation orders",
            plural(p.points, "point", "points"),
            plural(p.bifurcations, "bifurcation", "bifurcations")
        )
    } else {
        format!(
            "{omega}{:.1} rad/s, {}, {}",
            p.omega_rad_s,
            plural(p.points, "point", "points"),
            plural(p.bifurcations, "bifurcation", "bifurcations")
        )
    }
}

/// The run's located bifurcations with their truncation verdicts (`/truncation`): those
/// that hold or moved as results; those that vanished at a higher order, and the unlocated
/// changes of stability with theirs, apart.
fn truncation_summary(
    report: &crate::sweep::SweepReport,
    out: &mut dyn std::io::Write,
) -> anyhow::Result<()> {
    let mut vanished = Vec::new();
    for (w, kind, check) in report.checked_bifurcations() {
        let line = located_line(kind, w);
        match check {
            Some(c) if c.verdict().vanished() => {
                vanished.push(format!("{line}: {}", c.verdict_text()))
            }
            Some(c) => writeln!(out, "  {line}; {}", c.verdict_text())?,
            None => writeln!(out, "  {line}")?,
        }
    }
    if let Some(first) = report.truncation.first() {
        let orders: Vec<String> = first.orders.iter().map(|(k, _)| k.to_string()).collect();
        writeln!(
            out,
            "  truncation check: orders {} within ±{} rad/s, {:.1} s (--no-verify skips it)",
            orders.join(", "),
            first.window_rad_s,
            report.verify_seconds
        )?;
    }
    if !vanished.is_empty() {
        writeln!(
            out,
            "  not results of the model: located at order {} but gone at a higher order",
            report.truncation[0].recorded_order
        )?;
        for v in vanished {
            writeln!(out, "    {v}")?;
        }
    }
    for c in report.truncation.iter().filter(|c| c.kind.is_none()) {
        writeln!(
            out,
            "  change of stability between points {} and {} (ω ≈ {:.3} rad/s, not located): {}",
            c.after_point,
            c.after_point + 1,
            c.omega_rad_s,
            c.verdict_text()
        )?;
    }
    Ok(())
}

/// A located bifurcation's line of the summary: its label (the kind, with the details of
/// a Neimark–Sacker point in parentheses) and where it lies.
fn located_line(label: &str, w: f64) -> String {
    match label.split_once(" (") {
        Some((kind, details)) => format!("{kind} at ω = {w:.3} rad/s ({details}"),
        None => format!("{label} at ω = {w:.3} rad/s"),
    }
}
