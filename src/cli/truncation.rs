//! `tmrotor truncation`: the paper's truncation study (Section 5.1, Figs. 5–6), a table of
//! amplitudes, temperatures and Eq. 36 residuals per truncation order at points A–D.

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;

use super::sweep::{StudyArgs, parse_range};
use crate::sweep::StudySettings;
use crate::truncation::{self, TruncationOptions};

/// Study parameters and what to compare. The study defaults are those of `tmrotor sweep`
/// (q_l = 2 L/min, 25 °C, ω from 300 to 700 rad/s); the paper does not state the flow
/// rate of its truncation study.
#[derive(Debug, Clone, Args)]
pub struct TruncationArgs {
    /// Model, study file (its `order` is ignored, see --orders, and stability is not
    /// computed), flow rate and temperatures.
    #[command(flatten)]
    pub base: StudyArgs,
    /// Range START:END (rad/s) traced from START for every order [default: 300:700].
    #[arg(long, value_name = "START:END", allow_hyphen_values = true)]
    pub range: Option<String>,
    /// Truncation orders to compare, comma-separated (a study file's `order` is ignored;
    /// stability is not computed).
    #[arg(long, default_value = "1,2,3,4")]
    pub orders: String,
    /// Target speeds (rad/s), comma-separated; default: points A–D of the paper.
    #[arg(long, default_value = "400,484,530,584")]
    pub omega: String,
    /// Dynamic nodes (model ids), comma-separated [default: 8,14 for the dual rotor; for
    /// another model its disks' nodes, then its bearings' shaft-side nodes].
    #[arg(long)]
    pub nodes: Option<String>,
    /// Thermal nodes (1-based), comma-separated [default: 41,58 for the dual rotor; none
    /// for another model].
    #[arg(long)]
    pub thermal_nodes: Option<String>,
    /// Report every distinct solution on the branch at a target speed, not only the first.
    #[arg(long)]
    pub all_solutions: bool,
    /// Residual samples per period [default: 16 × the AFT's default].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub samples: Option<usize>,
    /// CSV (SI units, RMS and max columns, the nonlinear force per node): `--csv` prints
    /// it instead of the markdown table, `--csv FILE` writes it to FILE as well.
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub csv: Option<PathBuf>,
    /// No progress on stderr.
    #[arg(long, short)]
    pub quiet: bool,
}

fn parse_list<T: std::str::FromStr>(
    option: &str,
    text: &str,
    what: &str,
) -> anyhow::Result<Vec<T>> {
    let items: Vec<&str> = text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    if items.is_empty() {
        anyhow::bail!("{option} {text:?}: expected a comma-separated list of {what}");
    }
    items
        .iter()
        .map(|s| {
            s.parse()
                .map_err(|_| anyhow::anyhow!("{option} {text:?}: {s:?} is not {what}"))
        })
        .collect()
}

impl TruncationArgs {
    /// Study settings and study options these arguments describe, checked.
    pub fn resolve(&self) -> anyhow::Result<(StudySettings, TruncationOptions)> {
        let mut s = self.base.settings()?;
        if let Some(r) = &self.range {
            (s.sweep.omega_start, s.sweep.omega_end) = parse_range("--range", r)?;
            if s.sweep.omega_end <= s.sweep.omega_start {
                anyhow::bail!(
                    "--range {r:?}: END must exceed START (the branch is traced upwards)"
                );
            }
        }
        s.floquet.stability = false;
        let orders: Vec<u32> = parse_list("--orders", &self.orders, "a whole number")?;
        if let Some(k) = orders.iter().find(|&&k| k == 0 || k > 12) {
            anyhow::bail!(
                "--orders {:?}: order {k} must be between 1 and 12",
                self.orders
            );
        }
        let omegas: Vec<f64> = parse_list("--omega", &self.omega, "a number (rad/s)")?;
        let (lo, hi) = (
            s.sweep.omega_start.min(s.sweep.omega_end),
            s.sweep.omega_start.max(s.sweep.omega_end),
        );
        if let Some(w) = omegas
            .iter()
            .find(|w| !(w.is_finite() && **w >= lo && **w <= hi))
        {
            anyhow::bail!(
                "--omega {:?}: {w} rad/s is outside the traced range {lo}–{hi} rad/s (see --range)",
                self.omega
            );
        }
        if let Some(0) = self.samples {
            anyhow::bail!("--samples 0: need a positive sample count");
        }
        let opts = TruncationOptions {
            orders,
            omegas_rad_s: omegas,
            // empty: the model's own defaults (`truncation::default_dynamic_nodes`)
            dynamic_nodes: match &self.nodes {
                Some(text) => parse_list("--nodes", text, "a node id")?,
                None => Vec::new(),
            },
            thermal_nodes: match &self.thermal_nodes {
                Some(text) => parse_list("--thermal-nodes", text, "a node number")?,
                None => Vec::new(),
            },
            residual_samples: self.samples,
            all_solutions: self.all_solutions,
        };
        Ok((s, opts))
    }
}

/// Runs the study, progress on stderr, the table on `out`.
pub fn run(args: &TruncationArgs, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    let (settings, opts) = args.resolve()?;
    // a bar on a terminal; plain lines (order starts, crossings, order ends) always
    let bar = if args.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(1000);
        b.set_style(super::bar_style("{elapsed_precise} [{bar:30}] {msg}"));
        b
    };
    let say = |line: String| {
        if args.quiet {
            return;
        }
        if bar.is_hidden() {
            eprintln!("{line}");
        } else {
            bar.println(line);
        }
    };
    let start = std::time::Instant::now();
    let mut last_order = None;
    let report = truncation::run(&settings, &opts, |p| {
        if last_order != Some(p.order_index) {
            last_order = Some(p.order_index);
            say(format!(
                "[{:6.1} s] order {} ({}/{}): tracing {}–{} rad/s",
                start.elapsed().as_secs_f64(),
                p.order,
                p.order_index + 1,
                p.n_orders,
                settings.sweep.omega_start,
                settings.sweep.omega_end
            ));
        }
        for w in &p.crossed {
            say(format!(
                "[{:6.1} s] order {}: branch crosses ω = {w} rad/s (point {})",
                start.elapsed().as_secs_f64(),
                p.order,
                p.points
            ));
        }
        bar.set_position((p.fraction * 1000.0) as u64);
        bar.set_message(format!(
            "order {}: ω {:.1} rad/s, {} points, {} target crossings",
            p.order, p.omega_rad_s, p.points, p.crossings
        ));
    });
    bar.finish_and_clear();
    let report = report?;
    if !args.quiet {
        for o in &report.orders {
            eprintln!(
                "order {}: {} points ({} rejected steps) in {:.1} s, finished: {:?}",
                o.order, o.points, o.rejected_steps, o.seconds, o.finish
            );
        }
        if report.thermal_nodes.is_empty() {
            eprintln!(
                "no thermal columns: the study has no thermal network, or names none of its nodes (--thermal-nodes)"
            );
        }
    }
    for m in &report.missed {
        eprintln!(
            "warning: order {}, ω = {} rad/s, crossing {}: {}",
            m.order, m.omega_rad_s, m.crossing, m.reason
        );
    }
    for (order, w) in &report.unreached {
        eprintln!("warning: order {order}: the branch never reached ω = {w} rad/s");
    }
    let csv = truncation::csv(&report);
    match &args.csv {
        Some(path) if path.as_os_str() == "-" => write!(out, "{csv}")?,
        Some(path) => {
            std::fs::write(path, &csv)
                .with_context(|| format!("--csv: writing {}", path.display()))?;
            write!(out, "{}", truncation::markdown(&report))?;
        }
        None => write!(out, "{}", truncation::markdown(&report))?,
    }
    Ok(())
}
