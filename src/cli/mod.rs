//! The `tmrotor` command line: one file per subcommand, each with `run(args)`.
//! `src/main.rs` only parses and maps errors to exit codes.

pub mod campaign;
pub mod campbell;
pub mod interrupt;
pub mod linear_outputs;
pub mod model;
pub mod modes;
pub mod replay;
pub mod report;
pub mod sweep;
pub mod transient;
pub mod truncation;
pub mod unbalance;

use clap::{Parser, Subcommand};

/// How often a long command whose progress goes to a file (not a terminal) writes a
/// progress line: often enough to follow a cluster job's log, rarely enough to keep it
/// short (a default sweep writes one line, a paper campaign about seven).
pub const LOG_EVERY: std::time::Duration = std::time::Duration::from_secs(15);

/// The progress bars' style: `template` (indicatif's), drawn with `=>`; the default bar if
/// the template does not parse.
/// Starts the recording `path` and says on stderr where a killed earlier writer's file
/// was moved.
pub fn create_recording(
    path: &std::path::Path,
    options: crate::record::McapOptions,
) -> anyhow::Result<crate::record::McapSink> {
    let sink = crate::record::McapSink::create(path, options)?;
    if let Some(kept) = sink.stale_partial() {
        eprintln!(
            "note: an earlier run writing {} was killed; what it recorded was moved to {}",
            path.display(),
            kept.display()
        );
    }
    Ok(sink)
}

pub fn bar_style(template: &str) -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template(template)
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> ")
}

/// Nonlinear thermo-mechanical rotor dynamics: harmonic balance, continuation, Floquet
/// stability, MCAP recordings.
#[derive(Debug, Parser)]
#[command(name = "tmrotor", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run one continuation sweep (default: the built-in dual rotor, q_l = 2 L/min, 25 °C,
    /// ω ∈ [300, 700] rad/s, order 3) and write an MCAP recording.
    Sweep(sweep::SweepArgs),
    /// Run a campaign of sweeps (TOML file) in parallel, one recording per run plus a
    /// manifest; resumable, shardable (`--shard I/N`, then `campaign merge DIR`).
    Campaign(campaign::CampaignArgs),
    /// Check a model file, or print the built-in one.
    #[command(subcommand)]
    Model(model::ModelCommand),
    /// Damped natural frequencies, damping ratios and whirl directions at one speed.
    Modes(modes::ModesArgs),
    /// Campbell diagram and critical speeds (1× LP, 1× HP) over a speed range, modes
    /// followed by shape; CSV and figure.
    Campbell(campbell::CampbellArgs),
    /// Unbalance response (Bode and polar) of the linearised rotor over a speed range.
    Unbalance(unbalance::UnbalanceArgs),
    /// The reproduction report (markdown) of a campaign directory: the paper's findings
    /// against the recordings.
    Report(report::ReportArgs),
    /// Truncation study (paper Section 5.1): per order, amplitudes, temperatures and the
    /// residual of the governing equations (Eq. 36) at points A–D.
    Truncation(truncation::TruncationArgs),
    /// The coupled rotor in time: a fixed speed, a run-up or coast-down, or a speed table,
    /// from a cold start or a recorded point; an MCAP recording on the simulated time axis.
    Transient(transient::TransientArgs),
}

/// An error with its causes, as `{:#}` prints it, but without a cause whose text the
/// message already holds: several of the crate's errors name their I/O error in their own
/// message and also keep it as the source, which printed it twice ("cannot read f.mcap: No
/// such file or directory (os error 2): No such file or directory (os error 2)").
/// A count flag's value: a whole number of at least 1 (a count of 0 would run and print
/// nothing).
pub fn positive_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("{text:?} is not a whole number")),
    }
}

pub fn error_text(err: &anyhow::Error) -> String {
    let mut text = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

/// CPU time (user and system) this process has used so far, seconds, where the system
/// tells it (Linux: `/proc/self/stat`); `None` elsewhere.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    cpu_seconds_of_stat(&stat)
}

/// CPU time used since `start` (an earlier [`process_cpu_seconds`]), seconds; `None` where
/// either reading is missing.
pub fn cpu_seconds_since(start: Option<f64>) -> Option<f64> {
    difference(process_cpu_seconds(), start)
}

/// `now − then` when both readings are there.
fn difference(now: Option<f64>, then: Option<f64>) -> Option<f64> {
    now.zip(then).map(|(now, then)| now - then)
}

/// Time the host's hypervisor has kept this machine's cores from running, summed over the
/// cores, seconds (Linux: the `steal` column of `/proc/stat`); `None` elsewhere. On a
/// virtual machine whose host is busy this is what makes the same command take longer
/// from one hour to the next.
pub fn steal_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    steal_seconds_of(&stat)
}

/// The `steal` column (the eighth number) of the `cpu` line of a `/proc/stat` text,
/// seconds.
fn steal_seconds_of(stat: &str) -> Option<f64> {
    let line = stat.lines().find(|l| l.starts_with("cpu "))?;
    let steal: u64 = line.split_whitespace().nth(8)?.parse().ok()?;
    Some(steal as f64 / USER_HZ)
}

/// `"; the host held back 8.6 s of the cores (steal time)"` when the steal time since
/// `start` (an earlier [`steal_seconds`]) is at least 2 % of the cores' time over
/// `wall_s`; empty otherwise.
pub fn steal_note(start: Option<f64>, wall_s: f64) -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    match difference(steal_seconds(), start) {
        Some(s) if s >= 0.02 * cores * wall_s && s > 0.0 => {
            format!("; the host held back {s:.1} s of the cores (steal time)")
        }
        _ => String::new(),
    }
}

/// Clock ticks per second of the times in `/proc/PID/stat` (`USER_HZ`): fixed at 100 by
/// the Linux ABI on x86-64 and aarch64, whatever the kernel's own tick rate.
const USER_HZ: f64 = 100.0;

/// `utime + stime` of a `/proc/PID/stat` line, seconds: fields 14 and 15, counted after
/// the command name, which is in parentheses and may itself hold spaces and parentheses.
fn cpu_seconds_of_stat(stat: &str) -> Option<f64> {
    let rest = &stat[stat.rfind(')')? + 1..];
    // the first field after the name is field 3 (the state)
    let mut fields = rest.split_whitespace().skip(11);
    let utime: u64 = fields.next()?.parse().ok()?;
    let stime: u64 = fields.next()?.parse().ok()?;
    Some((utime + stime) as f64 / USER_HZ)
}

/// `"in 1 min 14 s; CPU 142 s, 191 % of one core (2 cores)"`: the wall time and, where
/// known, the CPU time of a long command, for its closing line.
pub fn time_and_cpu(wall_s: f64, cpu_s: Option<f64>) -> String {
    let wall = if wall_s >= 60.0 {
        // whole seconds first, so that 119.7 s reads 2 min 0 s, not 1 min 60 s
        let s = wall_s.round() as u64;
        format!("{} min {} s", s / 60, s % 60)
    } else {
        format!("{wall_s:.1} s")
    };
    match cpu_share(wall_s, cpu_s) {
        Some(cpu) => format!("in {wall}; {cpu}"),
        None => format!("in {wall}"),
    }
}

/// `"CPU 142 s, 191 % of one core (2 cores)"` for `cpu_s` seconds of CPU over `wall_s` of
/// wall time; `None` without a CPU time (or wall time).
pub fn cpu_share(wall_s: f64, cpu_s: Option<f64>) -> Option<String> {
    let cpu = cpu_s.filter(|_| wall_s > 0.0)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    Some(format!(
        "CPU {} s, {:.0} % of one core ({cores} core{})",
        if cpu < 100.0 {
            format!("{cpu:.1}")
        } else {
            format!("{cpu:.0}")
        },
        100.0 * cpu / wall_s,
        if cores == 1 { "" } else { "s" }
    ))
}

/// A sweep or campaign stopped by Ctrl-C or a termination signal (SIGTERM, SIGHUP: a
/// cluster job at its time limit) after writing what it had computed: the process exits
/// with status 130, not 0, so that scripts and schedulers see the work is not complete.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

/// Exit status of an [`Interrupted`] run (128 + SIGINT, the shell's convention).
pub const INTERRUPTED_EXIT: u8 = 130;

/// The figure flags shared by `replay plot` and `tmrotor campaign plot`.
#[derive(Debug, Clone, clap::Args)]
pub struct FigureArgs {
    /// Figure formats, comma-separated: png, svg (default both: the PNG to look at, the
    /// SVG, vector graphics with text kept as text, for a paper). PDF: convert the SVG,
    /// e.g. `rsvg-convert -f pdf`.
    #[arg(long, value_name = "LIST", default_value = "png,svg")]
    pub format: String,
    /// Draw each figure's title above its panels (default: none; a caption says it).
    #[arg(long)]
    pub title: bool,
}

impl FigureArgs {
    /// The output settings; an unknown format is an error saying what is accepted.
    pub fn output(&self) -> anyhow::Result<crate::figure::Output> {
        Ok(crate::figure::Output {
            formats: crate::figure::parse_formats(&self.format)
                .map_err(|e| anyhow::anyhow!("--format {:?}: {e}", self.format))?,
            title: self.title,
        })
    }
}

/// A re-derivation the recording cannot support (e.g. its embedded model cannot be rebuilt
/// by this version): exit status [`NOT_AVAILABLE_EXIT`], not a failure of the tool.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct NotAvailable(pub String);

/// Exit status of a [`NotAvailable`] outcome.
pub const NOT_AVAILABLE_EXIT: u8 = 2;

/// The one mapping from a command's outcome to the process's exit status, for both
/// binaries (`prog` prefixes the message):
///
/// | outcome | status | message (stderr) |
/// |---|---|---|
/// | success | 0 | none |
/// | output pipe closed by the reader (`replay branch … \| head`) | 0 | none |
/// | [`Interrupted`] (Ctrl-C, SIGTERM, SIGHUP) after saving what was computed | 130 | `interrupted: …` |
/// | [`NotAvailable`] | 2 | the reason |
/// | any other error | 1 | `error: …` with its causes ([`error_text`]) |
pub fn exit_code(prog: &str, result: anyhow::Result<()>) -> std::process::ExitCode {
    use std::process::ExitCode;
    let Err(err) = result else {
        return ExitCode::SUCCESS;
    };
    if closed_pipe(&err) {
        return ExitCode::SUCCESS;
    }
    if let Some(stop) = err.downcast_ref::<Interrupted>() {
        eprintln!("{prog}: interrupted: {stop}");
        return ExitCode::from(INTERRUPTED_EXIT);
    }
    if err.downcast_ref::<NotAvailable>().is_some() {
        eprintln!("{prog}: {}", error_text(&err));
        return ExitCode::from(NOT_AVAILABLE_EXIT);
    }
    eprintln!("{prog}: error: {}", error_text(&err));
    ExitCode::from(1)
}

/// Whether an error comes from writing to a pipe whose reader has gone (`| head`): the
/// reader has all it wanted, so the command ends quietly.
fn closed_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None => {
            let args = Cli::parse_from(["tmrotor", "sweep"]);
            match args.command {
                Some(Command::Sweep(a)) => sweep::run(&a, &mut std::io::stdout().lock()),
                _ => anyhow::bail!("internal: default sweep arguments did not parse"),
            }
        }
        Some(Command::Sweep(args)) => sweep::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Campaign(args)) => campaign::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Model(cmd)) => model::run(&cmd, &mut std::io::stdout().lock()),
        Some(Command::Modes(args)) => modes::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Campbell(args)) => campbell::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Unbalance(args)) => unbalance::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Report(args)) => report::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Truncation(args)) => truncation::run(&args, &mut std::io::stdout().lock()),
        Some(Command::Transient(args)) => transient::run(&args, &mut std::io::stdout().lock()),
    }
}

#[cfg(test)]
mod tests {
    use super::{
        cpu_seconds_of_stat, error_text, process_cpu_seconds, steal_note, steal_seconds,
        steal_seconds_of, time_and_cpu,
    };

    #[derive(Debug, thiserror::Error)]
    #[error("cannot read {path}: {source}")]
    struct Named {
        path: String,
        source: std::io::Error,
    }

    #[test]
    fn an_error_names_each_cause_once() {
        let io = || std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let named = anyhow::Error::new(Named {
            path: "f.mcap".into(),
            source: io(),
        });
        assert_eq!(
            format!("{named:#}"),
            "cannot read f.mcap: no such file: no such file"
        );
        assert_eq!(error_text(&named), "cannot read f.mcap: no such file");
        // a context whose message does not hold the cause keeps it
        let ctx = anyhow::Error::new(io()).context("sweep failed; the points so far are in x");
        assert_eq!(
            error_text(&ctx),
            "sweep failed; the points so far are in x: no such file"
        );
    }

    #[test]
    fn cpu_time_is_read_after_the_command_name() {
        // a command name with a space and a parenthesis; utime 1234, stime 56 ticks
        let stat = "4242 (my (odd) name) R 1 4242 4242 0 -1 4194304 100 0 0 0 1234 56 0 0 20 0 3 0 \
                    100 200 300";
        assert_eq!(cpu_seconds_of_stat(stat), Some(12.9));
        assert_eq!(cpu_seconds_of_stat("4242 (cut short) R 1 2"), None);
        assert_eq!(cpu_seconds_of_stat("no name at all"), None);
        if cfg!(target_os = "linux") {
            let before = process_cpu_seconds().expect("Linux has /proc/self/stat");
            // work until the reading has grown by 0.1 s (ten 10 ms ticks); on a loaded
            // machine this thread gets less than its wall time, so the bound is 20 s of
            // wall time, not a fixed amount of work
            let mut x = 0.0f64;
            let start = std::time::Instant::now();
            let mut after = before;
            while after - before < 0.1 && start.elapsed().as_secs_f64() < 20.0 {
                let burst = std::time::Instant::now();
                while burst.elapsed().as_secs_f64() < 0.01 {
                    x = std::hint::black_box((x + 1.0).sqrt());
                }
                after = process_cpu_seconds().expect("again");
            }
            assert!(
                after - before >= 0.1,
                "{before} → {after} s of CPU in {:.1} s of busy work",
                start.elapsed().as_secs_f64()
            );
        }
    }

    #[test]
    fn steal_time_is_the_eighth_number_of_the_cpu_line() {
        let stat = "cpu  2396009 0 228629 1259156 9508 0 1281 26133 0 0\n\
                    cpu0 1198004 0 114314 629578 4754 0 640 13066 0 0\n";
        assert_eq!(steal_seconds_of(stat), Some(261.33));
        assert_eq!(steal_seconds_of("cpu0 1 2 3 4 5 6 7 8\n"), None);
        assert_eq!(steal_seconds_of("cpu  1 2 3"), None);
        if cfg!(target_os = "linux") {
            assert!(steal_seconds().is_some(), "Linux has /proc/stat");
        }
        // no start reading: no note
        assert_eq!(steal_note(None, 10.0), "");
    }

    #[test]
    fn the_closing_line_gives_wall_time_and_cpu_share() {
        let line = time_and_cpu(84.4, Some(163.8));
        assert!(
            line.starts_with("in 1 min 24 s; CPU 164 s, 194 % of one core ("),
            "{line}"
        );
        assert_eq!(time_and_cpu(12.34, None), "in 12.3 s");
        assert_eq!(time_and_cpu(119.7, None), "in 2 min 0 s");
        assert!(time_and_cpu(2.0, Some(3.52)).starts_with("in 2.0 s; CPU 3.5 s, 176 %"));
    }
}
