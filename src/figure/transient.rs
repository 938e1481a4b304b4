//! `replay transient`: transient runs (`tmrotor transient`) against a sweep's branch: the
//! RMS amplitude of one node over ω, each run over the branch with its stable and unstable
//! parts, the speeds where each run changes fastest (its jumps), and a CSV of the runs.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

use crate::figure::{self, BranchStyle, Chart, Figure, LegendAt, Series};
use crate::record::Recording;
use crate::record::reader::TransientRecords;

/// Where a run's amplitude changes fastest: the largest change over one amplitude window.
#[derive(Clone, Debug, PartialEq)]
pub struct Jump {
    /// Speed at the window's middle, rad/s.
    pub omega_rad_s: f64,
    /// Time at the window's middle, s.
    pub time_s: f64,
    /// Amplitude change over the window, m (negative: a drop).
    pub change_m: f64,
}

/// The steepest change of node `k`'s amplitude over `window` revolutions, after the first
/// window (whose amplitude is built from fewer revolutions).
pub fn steepest_change(t: &TransientRecords, k: usize, window: usize) -> Option<Jump> {
    let r = &t.revolutions;
    let w = window.max(1);
    (w..r.len().checked_sub(w)?)
        .filter_map(|i| {
            let (a, b) = (&r[i], &r[i + w]);
            let change = b.amplitude_rms_m.get(k)? - a.amplitude_rms_m.get(k)?;
            let mid = &r[i + w / 2];
            Some(Jump {
                omega_rad_s: mid.omega_rad_s,
                time_s: mid.time_s,
                change_m: change,
            })
        })
        .max_by(|a, b| a.change_m.abs().total_cmp(&b.change_m.abs()))
}

/// Runs `replay transient`.
pub fn run(
    runs: &[(PathBuf, Recording)],
    branch: Option<&Recording>,
    node: Option<u32>,
    dir: &Path,
    output: &figure::Output,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let Some((_, first)) = runs.first() else {
        bail!("no transient recording given");
    };
    let nodes = &first.run.nodes;
    let k = match node {
        Some(id) => nodes
            .iter()
            .position(|n| n.id == id)
            .with_context(|| format!("--node {id}: the recording has no dynamic node {id}"))?,
        None => nodes.iter().position(|n| n.id == 8).unwrap_or(0),
    };
    let node_name = nodes.get(k).map_or("?".to_string(), |n| n.name.clone());
    crate::input::ensure_dir(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut chart = Chart {
        x_desc: figure::OMEGA.into(),
        y_desc: format!("RMS amplitude, {node_name} (µm)"),
        ..Chart::default()
    };
    if let Some(b) = branch {
        let pts = b.points.iter().filter(|p| p.branch == 0).map(|p| {
            (
                p.omega_rad_s,
                p.amplitude_rms_m.get(k).map(|a| a * 1e6),
                p.stable,
            )
        });
        chart
            .series
            .extend(figure::branch_series(pts, BranchStyle::Colours));
    }
    let mut csv = String::from("run,revolution,time_s,omega_rad_s,amplitude_rms_m\n");
    writeln!(
        out,
        "{:<28} {:>10} {:>12} {:>12} {:>14}",
        "run", "revolutions", "ω end", "steepest at", "change (µm)"
    )?;
    for (i, (path, rec)) in runs.iter().enumerate() {
        let Some(t) = &rec.transient else {
            bail!(
                "{} is not a transient recording (tmrotor transient)",
                path.display()
            );
        };
        let window = t
            .info
            .as_ref()
            .map_or(1, |i| i.window_revolutions.max(1) as usize);
        let name = path
            .file_stem()
            .map_or("run".to_string(), |s| s.to_string_lossy().into_owned());
        let points: Vec<(f64, f64)> = t
            .revolutions
            .iter()
            .skip(window)
            .filter_map(|r| r.amplitude_rms_m.get(k).map(|a| (r.omega_rad_s, a * 1e6)))
            .collect();
        for r in &t.revolutions {
            if let Some(a) = r.amplitude_rms_m.get(k) {
                csv.push_str(&format!(
                    "{name},{},{},{},{}\n",
                    r.index, r.time_s, r.omega_rad_s, a
                ));
            }
        }
        let jump = steepest_change(t, k, window);
        writeln!(
            out,
            "{:<28} {:>10} {:>12.3} {:>12} {:>14}",
            name,
            t.revolutions.len(),
            t.revolutions.last().map_or(f64::NAN, |r| r.omega_rad_s),
            jump.as_ref()
                .map_or("-".into(), |j| format!("{:.3}", j.omega_rad_s)),
            jump.as_ref()
                .map_or("-".into(), |j| format!("{:+.3}", j.change_m * 1e6)),
        )?;
        // run colours other than the branch's stable and unstable ones
        let colour = (0..)
            .map(figure::colour)
            .filter(|c| ![figure::STABLE, figure::UNSTABLE, figure::NOT_ASSESSED].contains(c))
            .nth(i)
            .unwrap_or(figure::colour(i));
        chart.series.push(Series {
            label: Some(name),
            width: 1,
            ..Series::new(points, colour)
        });
    }
    if let Some(b) = branch {
        for bif in b.bifurcations.iter().filter(|b| b.branch == 0) {
            writeln!(
                out,
                "branch: {} at ω = {:.3} rad/s",
                bif.kind.label(),
                bif.omega_rad_s
            )?;
        }
    }
    let legend = Figure::legend_from_series(std::slice::from_ref(&chart));
    let fig = Figure {
        title: format!("transient runs over the branch, {node_name}"),
        panels: vec![chart],
        grid: None,
        legend,
        legend_at: LegendAt::Right,
        size: (1200, 700),
    };
    let written = figure::write_figure(&dir.join("transient_amplitude"), &fig, output)?;
    let csv_path = dir.join("transient_amplitude.csv");
    std::fs::write(&csv_path, csv).with_context(|| format!("writing {}", csv_path.display()))?;
    for f in written.files.iter().chain(std::iter::once(&csv_path)) {
        writeln!(out, "wrote {}", f.display())?;
    }
    Ok(())
}
