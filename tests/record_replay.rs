//! The `replay` tool, in-process (`Cli::try_parse_from`) and as a process.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{png_pixels, replay_in_process};

use num_complex::Complex64;
use tmrotor::cli::replay::{self, stability};
use tmrotor::derive::{DeriveError, StabilityRederive};
use tmrotor::record::synthetic::{self, SyntheticOptions};
use tmrotor::record::{PointRecord, read_recording};
use tmrotor::stability::FloquetResult;

fn recording(dir: &Path, finish: bool) -> PathBuf {
    let path = dir.join(if finish { "run.mcap" } else { "cut.mcap" });
    let options = SyntheticOptions {
        points_per_side: 8,
        ..Default::default()
    };
    synthetic::write_mcap(&path, &options, finish).expect("write");
    path
}

#[test]
fn branch_csv_has_one_row_per_point_with_recorded_values() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = recording(dir.path(), true);
    let rec = read_recording(&path).expect("read");
    let file = path.to_str().expect("utf-8 path");
    let (res, out, _) = replay_in_process(&["branch", file, "--csv"]);
    res.expect("branch");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines[0],
        "index,omega_rad_s,branch,arc_length,stable,bifurcation,spectral_radius,unstable_count,\
         real_above_one,residual_mech,residual_therm,newton_iterations,half_order_share,amp_rms_node1_m"
    );
    assert_eq!(lines.len(), rec.points.len() + 1);
    for (line, p) in lines[1..].iter().zip(&rec.points) {
        let cols: Vec<&str> = line.split(',').collect();
        assert_eq!(cols[0].parse::<u64>().expect("index"), p.index);
        assert_eq!(cols[2], "0");
        assert_eq!(cols[1].parse::<f64>().expect("omega"), p.omega_rad_s);
        assert_eq!(cols[13].parse::<f64>().expect("amp"), p.amplitude_rms_m[0]);
        assert_eq!(
            cols[4],
            if p.stable == Some(true) {
                "true"
            } else {
                "false"
            }
        );
        assert_eq!(
            cols[5],
            p.bifurcation.map_or("", |b| b.key()),
            "bifurcation column"
        );
        assert_eq!(cols[6].parse::<f64>().expect("radius"), p.spectral_radius());
    }
    assert_eq!(out.matches("saddle_node").count(), 2);
}

/// `replay export` writes every table with one row per point (per multiplier, per
/// bifurcation, per entity), the values as recorded, and the embedded model text.
#[test]
fn export_writes_every_table_with_the_recorded_values() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = recording(dir.path(), true);
    let rec = read_recording(&path).expect("read");
    let out_dir = dir.path().join("tables");
    let (res, out, _) = replay_in_process(&[
        "export",
        path.to_str().expect("utf-8"),
        "--out",
        out_dir.to_str().expect("utf-8"),
    ]);
    res.expect("export");
    assert!(out.contains("branch.csv"), "{out}");
    let read = |name: &str| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(out_dir.join(name)).expect(name);
        text.lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect()
    };
    let col = |table: &[Vec<String>], name: &str| -> usize {
        table[0]
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", table[0]))
    };
    let header_ok = |h: &str| {
        h.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
    };
    let n = rec.points.len();
    for name in [
        "branch.csv",
        "temperatures.csv",
        "clearances.csv",
        "bearing_loads.csv",
        "thermal_forces.csv",
    ] {
        let t = read(name);
        assert_eq!(t.len(), n + 1, "{name}: one row per point");
        assert!(t[0].iter().all(|h| header_ok(h)), "{name}: {:?}", t[0]);
        assert!(t.iter().all(|r| r.len() == t[0].len()), "{name}: ragged");
    }
    let temps = read("temperatures.csv");
    let id = rec.run.thermal_nodes[0].id;
    let c = col(&temps, &format!("tnode{id}_mean_c"));
    for (row, p) in temps[1..].iter().zip(&rec.points) {
        assert_eq!(row[c].parse::<f64>().expect("T"), p.temperatures[0].mean_c);
    }
    let bearing = &tmrotor::derive::table::bearing_keys(&rec.run.bearings)[0];
    let cl = read("clearances.csv");
    let c = col(&cl, &format!("{bearing}_delta_v_m"));
    for (row, p) in cl[1..].iter().zip(&rec.points) {
        assert_eq!(
            row[c].parse::<f64>().expect("dv"),
            p.clearances[0].delta_v_m
        );
    }
    let loads = read("bearing_loads.csv");
    let c = col(&loads, &format!("{bearing}_max_n"));
    for (row, p) in loads[1..].iter().zip(&rec.points) {
        let max = p.bearing_loads[0]
            .radial_n
            .iter()
            .copied()
            .fold(f64::MIN, f64::max);
        assert_eq!(row[c].parse::<f64>().expect("load"), max);
    }
    let m = read("multipliers.csv");
    let total: usize = rec.points.iter().map(|p| p.multipliers.len()).sum();
    assert_eq!(m.len(), total + 1);
    let b = read("bifurcations.csv");
    assert_eq!(b.len(), rec.bifurcations.len() + 1);
    assert!(b[1..].iter().all(|r| r[1] == "saddle_node"), "{b:?}");
    let nodes = read("nodes.csv");
    let expected = rec.run.nodes.len() + rec.run.thermal_nodes.len() + rec.run.bearings.len();
    assert_eq!(nodes.len(), expected + 1);
    assert_eq!(
        std::fs::read_to_string(out_dir.join("model.toml")).expect("model"),
        rec.run.model_text
    );
    // An output that exists and is not a directory is named as such, for tables and figures.
    let file = out_dir.join("branch.csv");
    for sub in ["export", "plot"] {
        let (res, _, _) = replay_in_process(&[
            sub,
            path.to_str().expect("utf-8"),
            "--out",
            file.to_str().expect("utf-8"),
        ]);
        let e = format!("{:#}", res.expect_err("not a directory"));
        assert!(
            e.contains("is not a directory") && e.contains("branch.csv"),
            "{sub}: {e}"
        );
    }
}

#[test]
fn orbit_rederives_closed_form_histories_at_any_sampling() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = recording(dir.path(), true);
    let file = path.to_str().expect("utf-8 path");
    let rec = read_recording(&path).expect("read");
    let p = &rec.points[5];
    let (res, out, err) = replay_in_process(&[
        "orbit",
        file,
        "--point",
        "5",
        "--node",
        "1",
        "--samples",
        "37",
    ]);
    res.expect("orbit");
    assert!(err.contains("cannot be re-derived"), "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "t_s,node1_x_m,node1_y_m,tnode52_c");
    assert_eq!(lines.len(), 38);
    // A sampling that would not fit in memory is refused before anything is allocated.
    let (res, _, _) =
        replay_in_process(&["orbit", file, "--point", "5", "--samples", "100000000000"]);
    let e = res.expect_err("too many samples").to_string();
    assert!(
        e.contains("--samples 100000000000") && e.contains("MB"),
        "{e}"
    );
    // Independent reference: the synthetic closed form x = a cos(ωt − φ) + c cos(λωt),
    // recovered from the stored harmonic-1 coefficients (a cos φ, a sin φ).
    let nc = rec.run.n_coeffs();
    let nh = rec.run.harmonics.len();
    let h1 = rec
        .run
        .harmonics
        .iter()
        .position(|r| r.num == 1 && r.den == 1)
        .expect("ω");
    let (ac, as_) = (p.coeffs_mech[1 + h1], p.coeffs_mech[1 + nh + h1]);
    let c = synthetic::LAMBDA_AMPLITUDE_M;
    let w = p.omega_rad_s;
    for line in &lines[1..] {
        let v: Vec<f64> = line
            .split(',')
            .map(|s| s.parse().expect("number"))
            .collect();
        let t = v[0];
        let x = ac * (w * t).cos() + as_ * (w * t).sin() + c * (1.2 * w * t).cos();
        assert!(
            (v[1] - x).abs() < 1e-12 * p.amplitude_rms_m[0],
            "x at t = {t}"
        );
        let temp = p.temperatures[0].mean_c + 0.1 * (0.5 * w * t).cos();
        assert!((v[3] - temp).abs() < 1e-9, "T at t = {t}");
    }
    assert_eq!(nc, 9);

    let (res, _, _) = replay_in_process(&["orbit", file, "--point", "999"]);
    let e = res.expect_err("no such point").to_string();
    assert!(e.contains("no point 999"), "{e}");
    let (res, _, _) = replay_in_process(&["orbit", file, "--point", "1", "--node", "7"]);
    assert!(
        res.expect_err("no such node")
            .to_string()
            .contains("no dynamic node 7")
    );
}

struct Perturbed(f64);
impl StabilityRederive for Perturbed {
    fn floquet(&self, p: &PointRecord) -> Result<FloquetResult, DeriveError> {
        // Reverse the order (matching must not depend on it) and shift by a known amount.
        Ok(FloquetResult::new(
            p.multipliers
                .iter()
                .rev()
                .map(|m| m + Complex64::new(0.0, self.0))
                .collect(),
        ))
    }
}

#[test]
fn stability_reports_largest_deviation_or_says_it_is_unavailable() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = recording(dir.path(), true);
    let rec = read_recording(&path).expect("read");
    let c = stability::compare(&rec, &Perturbed(1e-7)).expect("compare");
    assert_eq!(c.compared, rec.points.len());
    // the progress is told after every point, with the number to do
    let mut told = Vec::new();
    let again = stability::compare_with(&rec, &Perturbed(1e-7), |done, total| {
        told.push((done, total))
    })
    .expect("compare");
    assert_eq!(again, c);
    let n = rec.points.len();
    assert_eq!(told, (1..=n).map(|k| (k, n)).collect::<Vec<_>>());
    let (dev, _) = c.max_deviation.expect("deviation");
    assert!((dev - 1e-7).abs() < 1e-12, "{dev}");
    assert!(c.flag_changes.is_empty());

    let (res, _, _) = replay_in_process(&["stability", path.to_str().expect("utf-8")]);
    let e = res.expect_err("no model to rebuild");
    assert!(e.downcast_ref::<replay::NotAvailable>().is_some());
    assert!(e.to_string().contains("cannot be recomputed"), "{e}");
    // an impossible audit product is refused before anything is recomputed
    let (res, _, _) = replay_in_process(&[
        "stability",
        path.to_str().expect("utf-8"),
        "--sip-intervals",
        "513",
    ]);
    let e = res.expect_err("odd interval count");
    assert!(e.to_string().contains("--sip-intervals 513"), "{e}");
}

#[test]
fn info_on_complete_and_cut_recordings() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = recording(dir.path(), true);
    let (res, out, err) = replay_in_process(&["info", path.to_str().expect("utf-8")]);
    res.expect("info");
    assert!(err.is_empty());
    for want in [
        "state:       complete",
        "completed",
        "saddle-node",
        "/summary",
        "hb.order = 1",
        "ω range",
    ] {
        assert!(out.contains(want), "missing {want:?} in\n{out}");
    }
    let cut = recording(dir.path(), false);
    let (res, out, err) = replay_in_process(&["info", cut.to_str().expect("utf-8")]);
    res.expect("info on an unfinished file");
    assert!(
        out.contains("INCOMPLETE") && err.contains("incomplete"),
        "{out}\n{err}"
    );
}

#[test]
fn plot_binary_writes_pngs_with_stable_and_unstable_colours_and_handles_bad_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = recording(dir.path(), true);
    let figs = dir.path().join("figs");
    let exe = env!("CARGO_BIN_EXE_replay");
    for font in [None, Some("none")] {
        let mut cmd = Command::new(exe);
        cmd.arg("plot").arg(&path).arg("--out").arg(&figs);
        if let Some(f) = font {
            cmd.env("TMROTOR_FONT", f);
        }
        let out = cmd.output().expect("run replay");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for name in ["amplitude_node1.png", "clearance.png", "temperatures.png"] {
            let (w, h, px) = png_pixels(&figs.join(name));
            assert_eq!((w, h), (1100, 650));
            if name.starts_with("amplitude") {
                let has = |r: u8, g: u8, b: u8| px.chunks(3).any(|p| p == [r, g, b]);
                assert!(has(31, 119, 180), "stable colour missing");
                assert!(has(214, 39, 40), "unstable colour missing");
            }
        }
    }

    let junk = dir.path().join("junk.mcap");
    std::fs::write(&junk, b"not a recording").expect("write");
    let out = Command::new(exe)
        .arg("info")
        .arg(&junk)
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("junk.mcap") && stderr.contains("not an MCAP file"),
        "{stderr}"
    );

    let out = Command::new(exe)
        .arg("stability")
        .arg(&path)
        .output()
        .expect("run");
    assert_eq!(
        out.status.code(),
        Some(2),
        "not available has its own exit code"
    );
}

/// `replay branch … | head`: the reader closes the pipe early; replay ends quietly with
/// status 0 instead of an error about a broken pipe.
#[test]
fn a_closed_pipe_ends_replay_quietly() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_replay");
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("long.mcap");
    let made = Command::new(bin)
        .args(["synthetic", "--points", "3000"])
        .arg(&file)
        .output()
        .expect("synthetic recording");
    assert!(made.status.success(), "{made:?}");
    let mut child = Command::new(bin)
        .args(["branch", "--csv"])
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("replay runs");
    let mut first = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("a line");
    // the reader is dropped here: the pipe is closed with most of the output unread
    assert!(first.starts_with("index,omega"), "{first}");
    let out = child.wait_with_output().expect("replay ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("error"), "{stderr}");
}
