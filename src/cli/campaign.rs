//! `tmrotor campaign`: several sweeps from one file, in parallel, with a manifest; and
//! `campaign plot DIR`: the runs overlaid in figures (PNG and SVG) ([`crate::figure::campaign`]).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

use clap::{Args, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use crate::campaign;
use crate::cli::interrupt::install_interrupt_flag;
use crate::cli::sweep::progress_message;
use crate::figure::campaign::{CampaignFigures, FigureOptions, plot_campaign};

#[derive(Debug, Clone, Args)]
pub struct CampaignArgs {
    #[command(subcommand)]
    pub command: Option<CampaignCommand>,
    /// Campaign file (TOML: a list of runs as in `examples/paper_campaign.toml`, a grid as
    /// in `examples/grid_campaign.toml`, or both).
    pub file: Option<PathBuf>,
    /// Runs computed at the same time (default: one per core). Each run's parallel parts
    /// get `threads / runs at a time` threads of their own (at least one); with one run
    /// at a time, it uses every core, and so does the last run still going once all
    /// have started.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run only shard I of N (runs whose position p has p mod N = I), e.g. `--shard 0/4`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// No progress: no bars on a terminal (one per run and one for the campaign), no
    /// progress lines when the output goes to a file (a line per run that ends and one on
    /// the whole campaign every 15 s).
    #[arg(long, short)]
    pub quiet: bool,
    /// Do not write the figures (`figures/` in the output directory) when every run has
    /// completed.
    #[arg(long)]
    pub no_figures: bool,
    /// List the runs (a grid expanded, with `--shard` that shard's) with their settings and
    /// whether each would run or be skipped as complete; check them; run and write
    /// nothing.
    #[arg(long)]
    pub dry_run: bool,
}

#[derive(Debug, Clone, Subcommand)]
pub enum CampaignCommand {
    /// Join the shard manifests of an output directory into manifest.toml.
    Merge {
        /// The campaign's output directory.
        dir: PathBuf,
    },
    /// Figures (PNG and SVG) of all runs overlaid: amplitude of node 8, clearance
    /// variations, bearing loads, temperatures (reads manifest.toml and the recordings of
    /// DIR).
    Plot {
        /// The campaign's output directory (holds manifest.toml).
        dir: PathBuf,
        /// Where the figures go (default: DIR/figures).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Dynamic node of the amplitude–frequency figure; repeat for several
        /// (default: 8, the paper's Fig. 8a).
        #[arg(long = "node", value_name = "ID")]
        nodes: Vec<u32>,
        /// ω of the bearing-position temperature chart, rad/s (nearest recorded point).
        #[arg(long, default_value_t = 620.0)]
        omega: f64,
        /// Thermal node of `temperature_node<ID>`, runs overlaid (default: 58, the paper's
        /// Fig. 15, for the built-in dual rotor; else not drawn).
        #[arg(long, value_name = "ID")]
        thermal_node: Option<u32>,
        /// Also draw the amplitude and node-temperature figures as small multiples: one
        /// panel per run on shared axes (`…_per_run`).
        #[arg(long)]
        per_run: bool,
        #[command(flatten)]
        figures: crate::cli::FigureArgs,
    },
    /// Operating map of a campaign over one parameter: the runs' saddle-node,
    /// Neimark–Sacker and period-doubling points joined into curves in (parameter, ω),
    /// fold-pair ends (cusps) bracketed, and the speeds where two or more stable responses
    /// coexist or none is stable; CSVs and a figure (see `examples/paper_map.toml`).
    Map {
        /// The campaign's output directory (holds manifest.toml).
        dir: PathBuf,
        /// Where the files go (default: DIR/map).
        #[arg(long)]
        out: Option<PathBuf>,
        /// The map's parameter: a settings key (`flow_l_min`) or `set.<path>` for a value
        /// of the model file (default: the one numeric setting that differs between runs).
        #[arg(long)]
        param: Option<String>,
        /// Largest ω distance (rad/s) of two points joined into a curve (default: 25 % of
        /// the swept ω range).
        #[arg(long, value_name = "RAD_S")]
        tolerance: Option<f64>,
        /// Narrow each fold-pair end by N bisections of the bracket, each a sweep without
        /// stability over ω ± 5 % of the swept range of the run with the pair (default 0:
        /// the grid's brackets).
        #[arg(long, value_name = "N", default_value_t = 0)]
        refine: usize,
        #[command(flatten)]
        figures: crate::cli::FigureArgs,
    },
}

fn report(figures: &CampaignFigures, out: &mut impl std::io::Write) -> std::io::Result<()> {
    for note in &figures.notes {
        writeln!(out, "note: {note}")?;
    }
    for path in &figures.written {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}

/// The operating map figure's size in pixels.
const MAP_FIGURE_SIZE: (u32, u32) = (1200, 800);

/// `campaign map DIR`: the map's files, then a line per curve and per fold-pair end.
fn map(
    dir: &std::path::Path,
    map_dir: Option<&std::path::Path>,
    options: crate::campaign::map::MapOptions,
    output: &crate::figure::Output,
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    use crate::campaign::map::operating_map;
    if let Some(t) = options.omega_tolerance
        && !(t.is_finite() && t > 0.0)
    {
        anyhow::bail!("--tolerance {t}: must be a positive number of rad/s");
    }
    let map_dir = map_dir.map_or_else(|| dir.join("map"), std::path::Path::to_path_buf);
    let (m, mut files) = operating_map(dir, &map_dir, &options)?;
    let figure = crate::figure::map::write_map_figure(&m, &map_dir, MAP_FIGURE_SIZE, output)?;
    files.written.extend(figure.written);
    files.notes.extend(figure.notes);
    for note in &files.notes {
        writeln!(out, "note: {note}")?;
    }
    writeln!(
        out,
        "map over {}: {} runs, {} curves, {} fold-pair ends",
        m.param,
        m.slices.len(),
        m.curves.len(),
        m.pair_ends.len()
    )?;
    for c in &m.curves {
        let (first, last) = (c.points[0], c.points[c.points.len() - 1]);
        writeln!(
            out,
            "  curve {:>2} {:<15} {} = {} … {}, ω = {:.2} … {:.2} rad/s ({})",
            c.id,
            crate::stability::BifurcationKind::label(c.kind),
            m.param,
            first.0,
            last.0,
            first.1,
            last.1,
            crate::cli::sweep::plural(c.points.len(), "point", "points")
        )?;
    }
    for e in &m.pair_ends {
        let how = if e.refined == 0 {
            String::new()
        } else {
            format!(
                " (after {})",
                crate::cli::sweep::plural(e.refined, "bisection", "bisections")
            )
        };
        writeln!(
            out,
            "  fold pair near ω = {:.2} rad/s at {} = {}, gone at {}: a cusp between{how}",
            e.omega, m.param, e.p_with, e.p_without
        )?;
    }
    for path in &files.written {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}

fn parse_shard(s: &str) -> anyhow::Result<(usize, usize)> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| anyhow::anyhow!("--shard {s:?}: expected I/N"))?;
    let (i, n): (usize, usize) = (
        i.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--shard {s:?}: I is not a number"))?,
        n.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--shard {s:?}: N is not a number"))?,
    );
    if n == 0 || i >= n {
        anyhow::bail!("--shard {s:?}: need 0 ≤ I < N");
    }
    Ok((i, n))
}

pub fn run(args: &CampaignArgs, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    if let Some(CampaignCommand::Merge { dir }) = &args.command {
        let m = campaign::merge_manifests(dir)?;
        writeln!(
            out,
            "merged {} runs into {}",
            m.runs.len(),
            dir.join("manifest.toml").display()
        )?;
        return Ok(());
    }
    if let Some(CampaignCommand::Plot {
        dir,
        out: fig_dir,
        nodes,
        omega,
        thermal_node,
        per_run,
        figures,
    }) = &args.command
    {
        let options = FigureOptions {
            nodes: nodes.clone(),
            omega_rad_s: *omega,
            thermal_node: *thermal_node,
            per_run: *per_run,
            output: figures.output()?,
            ..FigureOptions::default()
        };
        let fig_dir = fig_dir.clone().unwrap_or_else(|| dir.join("figures"));
        let figures = plot_campaign(dir, &fig_dir, &options)?;
        report(&figures, out)?;
        return Ok(());
    }
    if let Some(CampaignCommand::Map {
        dir,
        out: map_dir,
        param,
        tolerance,
        refine,
        figures,
    }) = &args.command
    {
        let options = crate::campaign::map::MapOptions {
            param: param.clone(),
            omega_tolerance: *tolerance,
            refine: *refine,
            progress: &|e| {
                eprintln!(
                    "fold pair near ω = {:.2} rad/s: present at {}, gone at {} ({} bisections)",
                    e.omega, e.p_with, e.p_without, e.refined
                )
            },
        };
        return map(dir, map_dir.as_deref(), options, &figures.output()?, out);
    }
    let file = args.file.as_ref().ok_or_else(|| {
        anyhow::anyhow!("campaign: give a campaign file (or `merge DIR`, `plot DIR`, `map DIR`)")
    })?;
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    if args.dry_run {
        return dry_run(file, shard, out);
    }
    let (start, cpu_start) = (Instant::now(), super::process_cpu_seconds());
    let steal_start = super::steal_seconds();
    let display = Display::new(args.quiet);
    let progress = |e: campaign::Event<'_>| display.show(e);
    let interrupt = install_interrupt_flag().ok();
    let manifest = campaign::run(file, args.threads, shard, interrupt.clone(), &progress)?;
    display.clear();
    for r in &manifest.runs {
        writeln!(
            out,
            "{:>12}  {:<12} {:>18} {:>7.1} s  {}",
            r.name,
            r.status,
            r.count_text(),
            r.seconds,
            r.recording
        )?;
    }
    if !args.no_figures {
        figures(&manifest, file, shard.is_some(), out)?;
    }
    let cpu = super::cpu_seconds_since(cpu_start);
    let wall = start.elapsed().as_secs_f64();
    writeln!(
        out,
        "campaign: {} {}{}",
        display.summary(),
        super::time_and_cpu(wall, cpu),
        super::steal_note(steal_start, wall)
    )?;
    let stopped = interrupt.is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed));
    let unfinished: Vec<&str> = manifest
        .runs
        .iter()
        .filter(|r| r.status != "completed")
        .map(|r| r.name.as_str())
        .collect();
    if unfinished.is_empty() {
        return Ok(());
    }
    let which = unfinished.join(", ");
    if stopped {
        return Err(super::Interrupted(format!(
            "{} of {} runs not completed ({which}); the same command resumes them",
            unfinished.len(),
            manifest.runs.len()
        ))
        .into());
    }
    anyhow::bail!(
        "{} of {} runs did not complete ({which}); their status and how they ended are in \
         the manifest",
        unfinished.len(),
        manifest.runs.len()
    )
}

/// `--dry-run`: the runs and what would happen to each.
fn dry_run(
    file: &std::path::Path,
    shard: Option<(usize, usize)>,
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    let (planned, dir) = campaign::plan(file, shard)?;
    // the output directory a real run would refuse, refused here too
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!(
            "{}: output_dir {}: it exists and is not a directory (the output is a directory \
             of files)",
            file.display(),
            dir.display()
        );
    }
    let which = match shard {
        Some((i, n)) => format!("shard {i}/{n}: "),
        None => String::new(),
    };
    let to_run = planned.iter().filter(|p| !p.skip).count();
    writeln!(
        out,
        "{}: {which}{} run{}, {to_run} to run, {} complete → {} (dry run: nothing run or written)",
        file.display(),
        planned.len(),
        if planned.len() == 1 { "" } else { "s" },
        planned.len() - to_run,
        dir.display()
    )?;
    let what = |p: &campaign::PlannedRun| match (&p.previous, p.skip) {
        (_, true) => "skip: completed".to_string(),
        (Some(status), false) if status != "pending" => {
            format!(
                "run ({} before)",
                status.split(':').next().unwrap_or(status)
            )
        }
        _ => "run".to_string(),
    };
    let width = planned.iter().map(|p| p.run.name.len()).max().unwrap_or(0);
    let what_width = planned.iter().map(|p| what(p).len()).max().unwrap_or(0);
    for p in &planned {
        let s = &p.run.settings;
        writeln!(
            out,
            "  #{:<3} {:<width$}  {:<what_width$}  flow {} L/min, cooling {} °C, ambient {} °C, \
             order {}, ω {} → {} rad/s{}{}{}",
            p.position,
            p.run.name,
            what(p),
            s.operating.flow_l_min,
            s.operating.cooling_temp_c,
            s.operating.ambient_temp_c,
            s.harmonic.order,
            s.sweep.omega_start,
            s.sweep.omega_end,
            if s.operating.thermal {
                ""
            } else {
                ", no thermal"
            },
            if s.floquet.stability {
                ""
            } else {
                ", no stability"
            },
            match s.set_summary() {
                set if set.is_empty() => String::new(),
                set => format!("; set {set}"),
            },
        )?;
    }
    Ok(())
}

/// The campaign's figures once every run is complete (or why they are not drawn).
fn figures(
    manifest: &campaign::Manifest,
    file: &std::path::Path,
    sharded: bool,
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    let pending = manifest
        .runs
        .iter()
        .filter(|r| r.status != "completed")
        .count();
    let (_, _, dir) = campaign::load(file)?;
    if sharded {
        writeln!(
            out,
            "figures: not written for a shard; after `tmrotor campaign merge {0}`, run \
             `tmrotor campaign plot {0}`",
            dir.display()
        )?;
    } else if pending > 0 {
        writeln!(
            out,
            "figures: not written, {pending} run(s) not completed; `tmrotor campaign plot {}` \
             draws what there is",
            dir.display()
        )?;
    } else {
        let figures = plot_campaign(&dir, &dir.join("figures"), &FigureOptions::default())
            .map_err(|e| anyhow::anyhow!("the runs are recorded, but the figures failed: {e}"))?;
        report(&figures, out)?;
    }
    Ok(())
}

/// What a campaign shows while it runs: on a terminal a bar for the whole campaign and one
/// per run (points, current ω, bifurcations); anywhere else (a log file, a cluster job's
/// output) a line when a run ends or is skipped and a line on the whole campaign every
/// [`super::LOG_EVERY`]; nothing with `--quiet`.
struct Display {
    bars: Option<Bars>,
    log: bool,
    state: Mutex<Tally>,
}

struct Bars {
    multi: MultiProgress,
    overall: ProgressBar,
    style: ProgressStyle,
}

/// The campaign so far.
struct Tally {
    runs: Vec<RunTally>,
    skipped: usize,
    start: Instant,
    last_log: Instant,
}

#[derive(Default)]
struct RunTally {
    name: String,
    fraction: f64,
    points: usize,
    bifurcations: usize,
    omega: Option<f64>,
    /// Completed (now or before).
    completed: bool,
    /// Ended, however (completed, interrupted, failed).
    ended: bool,
    /// A transient run: its count is of revolutions, not in the points' total.
    transient: bool,
    bar: Option<ProgressBar>,
}

impl Tally {
    fn run(&mut self, name: &str) -> Option<&mut RunTally> {
        self.runs.iter_mut().find(|r| r.name == name)
    }

    fn completed(&self) -> usize {
        self.runs.iter().filter(|r| r.completed).count()
    }

    /// Mean of the runs' fractions of their ω ranges (a completed run counts whole).
    fn fraction(&self) -> f64 {
        if self.runs.is_empty() {
            return 0.0;
        }
        let sum: f64 = self
            .runs
            .iter()
            .map(|r| {
                if r.completed {
                    1.0
                } else {
                    r.fraction.clamp(0.0, 1.0)
                }
            })
            .sum();
        sum / self.runs.len() as f64
    }

    /// `2/6 runs completed (1 before), 843 points, 12 bifurcations`.
    fn summary(&self) -> String {
        let before = if self.skipped > 0 {
            format!(" ({} before)", self.skipped)
        } else {
            String::new()
        };
        format!(
            "{}/{} runs completed{before}, {} points, {} bifurcations",
            self.completed(),
            self.runs.len(),
            self.runs
                .iter()
                .filter(|r| !r.transient)
                .map(|r| r.points)
                .sum::<usize>(),
            self.runs.iter().map(|r| r.bifurcations).sum::<usize>()
        )
    }
}

impl Display {
    fn new(quiet: bool) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let bars = (!quiet && terminal).then(|| {
            let multi = MultiProgress::new();
            let style = super::bar_style("{prefix:>10} {elapsed_precise} [{bar:25}] {msg}");
            let overall = multi.add(ProgressBar::new(1000));
            overall.set_style(style.clone());
            overall.set_prefix("campaign");
            Bars {
                multi,
                overall,
                style,
            }
        });
        let now = Instant::now();
        Self {
            bars,
            log: !quiet && !terminal,
            state: Mutex::new(Tally {
                runs: Vec::new(),
                skipped: 0,
                start: now,
                last_log: now,
            }),
        }
    }

    fn show(&self, event: campaign::Event<'_>) {
        use campaign::Event;
        let Ok(mut t) = self.state.lock() else {
            return;
        };
        match event {
            Event::Plan { runs } => {
                t.runs = runs
                    .iter()
                    .map(|name| RunTally {
                        name: name.clone(),
                        ..RunTally::default()
                    })
                    .collect();
                if self.log {
                    eprintln!("campaign: {} runs ({})", runs.len(), runs.join(", "));
                }
            }
            Event::Skipped { run, entry } => {
                t.skipped += 1;
                if let Some(r) = t.run(run) {
                    (r.completed, r.ended) = (true, true);
                    r.points = entry.points;
                    r.bifurcations = entry.bifurcations.len();
                    r.transient = entry.is_transient();
                }
                if self.log {
                    eprintln!(
                        "{run}: completed before ({}), not redone",
                        entry.count_text()
                    );
                }
            }
            Event::Point { run, progress } => {
                let bars = self.bars.as_ref();
                if let Some(r) = t.run(run) {
                    r.fraction = progress.fraction;
                    r.points = progress.points;
                    r.bifurcations = progress.bifurcations;
                    r.omega = Some(progress.omega_rad_s);
                    if let Some(b) = bars {
                        let bar = r.bar.get_or_insert_with(|| {
                            let bar = b.multi.add(ProgressBar::new(1000));
                            bar.set_style(b.style.clone());
                            bar.set_prefix(run.to_string());
                            bar
                        });
                        bar.set_position((progress.fraction.clamp(0.0, 1.0) * 1000.0) as u64);
                        bar.set_message(progress_message(progress, "ω "));
                    }
                }
                if self.log && t.last_log.elapsed() >= super::LOG_EVERY {
                    t.last_log = Instant::now();
                    let running: Vec<String> = t
                        .runs
                        .iter()
                        .filter(|r| !r.ended)
                        .filter_map(|r| r.omega.map(|w| format!("{} at {w:.1} rad/s", r.name)))
                        .collect();
                    eprintln!(
                        "campaign: {} after {:.0} s; running: {}",
                        t.summary(),
                        t.start.elapsed().as_secs_f64(),
                        running.join(", ")
                    );
                }
            }
            Event::Finished { run, entry } => {
                if let Some(r) = t.run(run) {
                    r.ended = true;
                    r.completed = entry.status == "completed";
                    r.points = entry.points;
                    r.bifurcations = entry.bifurcations.len();
                    r.transient = entry.is_transient();
                    if let Some(bar) = &r.bar {
                        bar.set_position(1000);
                        bar.set_message(format!(
                            "{}, {}, {} bifurcations",
                            entry.status,
                            entry.count_text(),
                            entry.bifurcations.len()
                        ));
                    }
                }
                if self.log {
                    eprintln!(
                        "{run}: {}, {}, {} bifurcations, {:.1} s ({}/{} runs completed)",
                        entry.status,
                        entry.count_text(),
                        entry.bifurcations.len(),
                        entry.seconds,
                        t.completed(),
                        t.runs.len()
                    );
                }
            }
        }
        if let Some(b) = &self.bars {
            b.overall
                .set_position((t.fraction() * 1000.0).round() as u64);
            b.overall.set_message(t.summary());
        }
    }

    /// The campaign so far, as on its bar: runs completed, points, bifurcations.
    fn summary(&self) -> String {
        self.state.lock().map(|t| t.summary()).unwrap_or_default()
    }

    /// Takes the bars off the terminal (the table of runs follows).
    fn clear(&self) {
        if let Some(b) = &self.bars {
            if let Ok(t) = self.state.lock() {
                for bar in t.runs.iter().filter_map(|r| r.bar.as_ref()) {
                    bar.finish_and_clear();
                }
            }
            b.overall.finish_and_clear();
        }
    }
}
