//! Campaigns: parallel runs, manifest with checksums, resume, shards and merge.

use std::path::Path;

use tmrotor::campaign::{self, sha256_file};

mod common;
use common::{SMALL_CAMPAIGN, has_colour, png_pixels};

fn write_campaign(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("c.toml");
    std::fs::write(&path, SMALL_CAMPAIGN).expect("write campaign");
    path
}

#[test]
fn campaign_runs_resumes_shards_and_merges() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    assert_eq!(m.runs.len(), 3);
    let out = dir.path().join("out");
    for r in &m.runs {
        assert_eq!(r.status, "completed", "{r:?}");
        assert!(r.points >= 1);
        // where its time went
        assert!(
            r.time.starts_with("corrector ") && r.time.contains(", recording "),
            "{r:?}"
        );
        // how the branch ended: at the bound or at max_points = 3
        assert!(
            r.ended == "reached ω = 402.000 rad/s"
                || (r.ended == "stopped at the maximum number of points" && r.points == 3),
            "{r:?}"
        );
        assert_eq!(
            sha256_file(&out.join(&r.recording)).expect("recording"),
            r.sha256
        );
    }
    // Resume: nothing changes, completed runs are skipped (same seconds as before).
    let again = campaign::run(&file, Some(2), None, None, &quiet).expect("resume");
    for (x, y) in m.runs.iter().zip(&again.runs) {
        assert_eq!(x.seconds, y.seconds, "run {} was redone", x.name);
        assert_eq!(x.ended, y.ended, "read back from the manifest");
        assert_eq!(
            x.refused_steps, y.refused_steps,
            "read back from the manifest"
        );
    }
    // A manifest written before refused steps were recorded still reads (0 refused).
    let text = std::fs::read_to_string(out.join("manifest.toml")).expect("manifest");
    assert!(text.contains("refused_steps"), "{text}");
    let older: String = text
        .lines()
        .filter(|l| !l.starts_with("refused_steps"))
        .map(|l| format!("{l}\n"))
        .collect();
    let older: campaign::Manifest = toml::from_str(&older).expect("older manifest");
    assert!(older.runs.iter().all(|r| r.refused_steps == 0));
    // A damaged recording is redone.
    std::fs::write(out.join("b.mcap"), b"garbage").expect("damage");
    let redo = campaign::run(&file, Some(2), None, None, &quiet).expect("redo");
    let b = redo.runs.iter().find(|r| r.name == "b").expect("b");
    assert_ne!(b.sha256, sha256_file(&file).unwrap_or_default());
    assert_eq!(
        b.sha256,
        sha256_file(&out.join("b.mcap")).expect("b recording")
    );

    // Shards partition the runs deterministically; merge joins them.
    let s0 = campaign::run(&file, Some(1), Some((0, 2)), None, &quiet).expect("shard 0");
    let s1 = campaign::run(&file, Some(1), Some((1, 2)), None, &quiet).expect("shard 1");
    let names = |m: &campaign::Manifest| m.runs.iter().map(|r| r.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&s0), ["a", "c"]);
    assert_eq!(names(&s1), ["b"]);
    let merged = campaign::merge_manifests(&out).expect("merge");
    assert_eq!(names(&merged), ["a", "b", "c"]);
}

/// `(kind, run)` pairs, or `(run, points)` pairs.
type Pairs<T> = Vec<(String, T)>;

/// The events of one campaign invocation, as `(kind, run)` in order (`Plan` with all
/// names joined); points only counted per run.
fn events_of(file: &Path, threads: usize) -> (Pairs<String>, Pairs<usize>) {
    let events = std::sync::Mutex::new(Vec::new());
    let points = std::sync::Mutex::new(Vec::<(String, usize)>::new());
    let record = |e: campaign::Event<'_>| {
        let (kind, run) = match e {
            campaign::Event::Plan { runs } => ("plan", runs.join(",")),
            campaign::Event::Skipped { run, entry } => {
                assert_eq!(entry.status, "completed");
                ("skipped", run.to_string())
            }
            campaign::Event::Point { run, progress } => {
                let mut p = points.lock().expect("points");
                match p.iter_mut().find(|(r, _)| r == run) {
                    Some((_, n)) => *n = (*n).max(progress.points),
                    None => p.push((run.to_string(), progress.points)),
                }
                return;
            }
            campaign::Event::Finished { run, entry } => {
                // the entry is the manifest's, with its points
                let p = points.lock().expect("points");
                let seen = p.iter().find(|(r, _)| r == run).map_or(0, |(_, n)| *n);
                assert_eq!(entry.points, seen, "{run}");
                ("finished", run.to_string())
            }
        };
        events.lock().expect("events").push((kind.to_string(), run));
    };
    campaign::run(file, Some(threads), None, None, &record).expect("campaign");
    (
        events.into_inner().expect("events"),
        points.into_inner().expect("points"),
    )
}

#[test]
fn a_campaign_tells_its_plan_each_run_it_ends_and_each_it_skips() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let (events, points) = events_of(&file, 2);
    assert_eq!(events[0], ("plan".into(), "a,b,c".into()));
    let mut finished: Vec<&str> = events[1..]
        .iter()
        .map(|(kind, run)| {
            assert_eq!(kind, "finished");
            run.as_str()
        })
        .collect();
    finished.sort_unstable();
    assert_eq!(finished, ["a", "b", "c"]);
    assert_eq!(points.len(), 3, "{points:?}");
    // resumed: every run is skipped, none computes a point
    let (events, points) = events_of(&file, 2);
    let expected: Vec<(String, String)> = [("plan", "a,b,c"), ("skipped", "a"), ("skipped", "b")]
        .into_iter()
        .chain([("skipped", "c")])
        .map(|(k, r)| (k.to_string(), r.to_string()))
        .collect();
    let mut sorted = events.clone();
    sorted[1..].sort();
    assert_eq!(sorted, expected);
    assert!(points.is_empty(), "{points:?}");
}

#[test]
fn a_campaign_writing_to_a_file_logs_runs_and_progress_lines() {
    let exe = env!("CARGO_BIN_EXE_tmrotor");
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    // stderr is a pipe, not a terminal: lines instead of bars
    let run = Command::new(exe)
        .args(["campaign", "--no-figures"])
        .arg(&file)
        .output()
        .expect("run tmrotor");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.starts_with("campaign: 3 runs (a, b, c)\n"),
        "{stderr}"
    );
    for name in ["a", "b", "c"] {
        assert!(
            stderr
                .lines()
                .any(|l| l.starts_with(&format!("{name}: completed, ")) && l.contains(" points, ")),
            "{stderr}"
        );
    }
    assert!(stderr.contains("(3/3 runs completed)"), "{stderr}");
    assert!(
        !stderr.contains('\u{1b}'),
        "terminal escapes in a file: {stderr}"
    );
    // resumed: the runs are named as done before
    let run = Command::new(exe)
        .args(["campaign", "--no-figures"])
        .arg(&file)
        .output()
        .expect("run tmrotor");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("a: completed before ("), "{stderr}");
    // and --quiet says nothing
    let run = Command::new(exe)
        .args(["campaign", "-q", "--no-figures"])
        .arg(&file)
        .output()
        .expect("run tmrotor");
    assert!(
        run.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

#[test]
fn an_interrupt_starts_no_further_run_and_keeps_earlier_recordings() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let out = dir.path().join("out");
    // Ctrl-C during run "a" (one run at a time): "a" stops where it is, "b" and "c" are
    // never started.
    let flag = Arc::new(AtomicBool::new(false));
    let during_a = |e: campaign::Event<'_>| {
        if let campaign::Event::Point { run: "a", .. } = e {
            flag.store(true, Ordering::Relaxed);
        }
    };
    let m = campaign::run(&file, Some(1), None, Some(flag.clone()), &during_a).expect("run");
    let status =
        |m: &campaign::Manifest| m.runs.iter().map(|r| r.status.clone()).collect::<Vec<_>>();
    assert_eq!(status(&m), ["interrupted", "pending", "pending"]);
    assert!(out.join("a.mcap").exists());
    assert!(!out.join("b.mcap").exists(), "b was started");
    assert!(!out.join("c.mcap").exists(), "c was started");
    let a_hash = sha256_file(&out.join("a.mcap")).expect("a recording");
    // Interrupted again before anything starts: the manifest still describes a's
    // recording, which is left as it was.
    let m = campaign::run(&file, Some(1), None, Some(flag.clone()), &during_a).expect("rerun");
    assert_eq!(status(&m), ["interrupted", "pending", "pending"]);
    assert_eq!(m.runs[0].sha256, a_hash);
    assert_eq!(sha256_file(&out.join("a.mcap")).expect("a"), a_hash);
    // Without an interrupt everything completes.
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(1), None, None, &quiet).expect("resume");
    assert_eq!(status(&m), ["completed", "completed", "completed"]);
}

#[test]
fn campaign_file_errors_name_the_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, "[[runs]]\nname = \"x\"\nflow_rate = 3.0\n").expect("write");
    let err = campaign::load(&path).expect_err("unknown key");
    let msg = err.to_string();
    assert!(
        msg.contains("bad.toml") && msg.contains("runs[0]") && msg.contains("flow_rate"),
        "{msg}"
    );
    std::fs::write(&path, "[[runs]]\nname = \"x\"\n[[runs]]\nname = \"x\"\n").expect("write");
    assert!(
        campaign::load(&path)
            .expect_err("duplicate")
            .to_string()
            .contains("unique")
    );
}

#[test]
fn a_grid_gives_every_combination_named_by_its_values() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("grid.toml");
    std::fs::write(
        &path,
        r#"
[defaults]
order = 1
[grid]
name = "q{flow_l_min}-{cooling_temp_c}C"
flow_l_min = [20.0, 2.5]
cooling_temp_c = [25.0, 50.0, 60]
[[runs]]
name = "extra"
flow_l_min = 1.0
"#,
    )
    .expect("write");
    let (_, runs, out) = campaign::load(&path).expect("grid");
    let got: Vec<(&str, f64, f64, u32)> = runs
        .iter()
        .map(|r| {
            let s = &r.settings;
            (
                r.name.as_str(),
                s.operating.flow_l_min,
                s.operating.cooling_temp_c,
                s.harmonic.order,
            )
        })
        .collect();
    // keys alphabetically, the first (cooling_temp_c) slowest; the listed run after
    assert_eq!(
        got,
        [
            ("q20-25C", 20.0, 25.0, 1),
            ("q2.5-25C", 2.5, 25.0, 1),
            ("q20-50C", 20.0, 50.0, 1),
            ("q2.5-50C", 2.5, 50.0, 1),
            ("q20-60C", 20.0, 60.0, 1),
            ("q2.5-60C", 2.5, 60.0, 1),
            ("extra", 1.0, 25.0, 1),
        ]
    );
    assert_eq!(out, dir.path().join("grid-out"));
    // without a template: key=value parts
    std::fs::write(
        &path,
        "[grid]\nflow_l_min = [20.0]\nthermal = [true, false]\n",
    )
    .expect("write");
    let (_, runs, _) = campaign::load(&path).expect("grid");
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        ["flow_l_min=20_thermal=true", "flow_l_min=20_thermal=false"]
    );
    assert!(runs[0].settings.operating.thermal && !runs[1].settings.operating.thermal);
}

#[test]
fn grid_errors_name_the_key_or_the_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("bad.toml");
    let err = |text: &str| {
        std::fs::write(&path, text).expect("write");
        campaign::load(&path).expect_err(text).to_string()
    };
    for (text, expected) in [
        (
            "[grid]\nflow_l_min = 2.0\n",
            "grid.flow_l_min: must be an array",
        ),
        (
            "[grid]\nflow_l_min = []\n",
            "grid.flow_l_min: has no values",
        ),
        (
            "[grid]\nflow_l_min = [[1.0]]\n",
            "grid.flow_l_min: values must be",
        ),
        (
            "[grid]\nname = \"q{flow}\"\nflow_l_min = [1.0]\n",
            "{flow} in \"q{flow}\" is not a key",
        ),
        (
            "[grid]\nname = \"q{flow_l_min\"\nflow_l_min = [1.0]\n",
            "unclosed",
        ),
        (
            "[grid]\nname = 3\nflow_l_min = [1.0]\n",
            "grid.name: must be a string",
        ),
        ("[grid]\nname = \"x\"\n", "grid: no keys"),
        (
            "[grid]\nname = \"same\"\nflow_l_min = [1.0, 2.0]\n",
            "unique",
        ),
        (
            "[grid]\nflow_l_min = [1.0]\n[[runs]]\nname = \"flow_l_min=1\"\n",
            "runs[0]",
        ),
        (
            "[grid]\nflow_l_min = [\"fast\"]\n",
            "grid run flow_l_min=fast: ",
        ),
        ("[grid]\nflow_rate = [1.0]\n", "flow_rate"),
        ("output_dir = \"o\"\n", "no runs"),
    ] {
        let msg = err(text);
        assert!(
            msg.contains("bad.toml") && msg.contains(expected),
            "{text:?}: {msg}"
        );
    }
    // A grid too large is refused before it is expanded (three axes of 1000 values).
    let axis = |n: usize| {
        let v: Vec<String> = (0..n).map(|i| format!("{}.0", i + 1)).collect();
        format!("[{}]", v.join(", "))
    };
    let big = format!(
        "[grid]\nflow_l_min = {}\ncooling_temp_c = {}\nambient_temp_c = {}\n",
        axis(1000),
        axis(1000),
        axis(1000)
    );
    let msg = err(&big);
    assert!(
        msg.contains("bad.toml") && msg.contains("1000 × 1000 × 1000 runs is more than the 10000"),
        "{msg}"
    );
}

// ---------------------------------------------------------------------------------------
// Figures: `campaign plot DIR` overlays the runs.

use std::process::Command;

use tmrotor::campaign::CampaignError;
use tmrotor::figure::PALETTE;
use tmrotor::figure::campaign::{FigureOptions, plot_campaign};

/// Two short coupled runs (thermal network on, so temperatures and clearances are
/// recorded), order 1, no stability.
fn write_thermal_campaign(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("t.toml");
    std::fs::write(
        &path,
        r#"
output_dir = "out"
[defaults]
order = 1
omega_start = 400.0
omega_end = 440.0
max_points = 12
stability = false
[[runs]]
name = "q20"
flow_l_min = 20.0
[[runs]]
name = "q2"
flow_l_min = 2.0
"#,
    )
    .expect("write campaign");
    path
}

const FIGURES: [&str; 10] = [
    "amplitude_node8.png",
    "clearance_variation.png",
    "effective_clearance.png",
    "bearing_loads_mean.png",
    "rolling_element_temperatures.png",
    "temperature_node58.png",
    "node_temperatures_q20.png",
    "node_temperatures_q2.png",
    "temperature_extremes.png",
    "bearing_temperatures_omega402.png",
];

fn options() -> FigureOptions {
    FigureOptions {
        omega_rad_s: 402.0,
        output: tmrotor::figure::Output {
            formats: vec![tmrotor::figure::Format::Png],
            title: false,
        },
        ..FigureOptions::default()
    }
}

#[test]
fn campaign_plot_overlays_the_runs_and_marks_incomplete_ones() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_thermal_campaign(dir.path());
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    assert!(
        m.runs
            .iter()
            .all(|r| r.status == "completed" && r.points >= 3)
    );
    let out = dir.path().join("out");
    let figs = out.join("figs");

    let done = plot_campaign(&out, &figs, &options()).expect("plot");
    let written: Vec<String> = done
        .written
        .iter()
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    assert_eq!(written, FIGURES);
    assert_eq!(
        done.legends,
        [
            "q20: flow 20 L/min, cooling 25 °C",
            "q2: flow 2 L/min, cooling 25 °C"
        ]
    );
    for name in FIGURES {
        let (w, h, px) = png_pixels(&figs.join(name));
        assert_eq!((w, h), (1200, 800), "{name}");
        let ink = px.chunks(3).filter(|p| *p != [255, 255, 255]).count();
        // Curves alone (no font: no text, no grid) cover about 1 %.
        assert!(
            ink > 1200 * 800 / 200,
            "{name}: only {ink} non-white pixels"
        );
        if name.starts_with("node_temperatures_") {
            // one run per figure, a colour per part of a bearing
            continue;
        }
        // Both runs are drawn, each in its own colour.
        assert!(has_colour(&px, PALETTE[0]), "{name}: run q20 missing");
        assert!(has_colour(&px, PALETTE[1]), "{name}: run q2 missing");
    }

    // A run cut short (a killed process) is plotted as far as it goes and marked.
    let cut = out.join("q2.mcap");
    let bytes = std::fs::read(&cut).expect("read");
    std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).expect("truncate");
    let readable = tmrotor::record::read_recording(&cut).expect("cut file reads");
    assert!(!readable.complete && readable.points.len() >= 2);
    let done = plot_campaign(&out, &figs, &options()).expect("plot with a cut run");
    assert_eq!(done.legends[0], "q20: flow 20 L/min, cooling 25 °C");
    assert_eq!(
        done.legends[1],
        "q2: flow 2 L/min, cooling 25 °C (incomplete)"
    );
    assert!(
        done.notes
            .iter()
            .any(|n| n.contains("run q2 is incomplete") && n.contains("cut short")),
        "{:?}",
        done.notes
    );
    let (_, _, px) = png_pixels(&figs.join("amplitude_node8.png"));
    assert!(has_colour(&px, PALETTE[1]), "the cut run is still drawn");

    // A node that was not recorded is an error naming it.
    let bad = FigureOptions {
        nodes: vec![99],
        ..options()
    };
    let msg = plot_campaign(&out, &figs, &bad)
        .expect_err("node 99")
        .to_string();
    assert!(
        msg.contains("node 99") && msg.contains("manifest.toml"),
        "{msg}"
    );
}

#[test]
fn campaign_plot_errors_name_the_file_and_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_thermal_campaign(dir.path());
    let out = dir.path().join("out");
    let figs = dir.path().join("figs");
    let err = |e: CampaignError| e.to_string();

    // No manifest yet.
    std::fs::create_dir_all(&out).expect("mkdir");
    let msg = err(plot_campaign(&out, &figs, &options()).expect_err("no manifest"));
    assert!(
        msg.contains("manifest.toml") && msg.contains("cannot read the campaign manifest"),
        "{msg}"
    );
    // A manifest that is not one.
    std::fs::write(out.join("manifest.toml"), "runs = 3\n").expect("write");
    let msg = err(plot_campaign(&out, &figs, &options()).expect_err("bad manifest"));
    assert!(
        msg.contains("manifest.toml") && msg.contains("not a campaign manifest"),
        "{msg}"
    );
    // (a campaign refuses to run over it: moved away)
    std::fs::remove_file(out.join("manifest.toml")).expect("remove");

    let quiet = |_: campaign::Event<'_>| {};
    campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    // A recording that is missing…
    let rec = out.join("q2.mcap");
    std::fs::remove_file(&rec).expect("remove");
    let msg = err(plot_campaign(&out, &figs, &options()).expect_err("missing recording"));
    assert!(
        msg.contains("q2.mcap") && msg.contains("run q2") && msg.contains("cannot read"),
        "{msg}"
    );
    // A run the manifest lists as not started has no recording yet: it stays in the
    // legend, nothing drawn.
    let manifest_path = out.join("manifest.toml");
    let text = std::fs::read_to_string(&manifest_path).expect("manifest");
    let mut manifest: campaign::Manifest = toml::from_str(&text).expect("parse");
    manifest.runs[1].status = "pending".into();
    std::fs::write(&manifest_path, toml::to_string(&manifest).expect("toml")).expect("write");
    let done = plot_campaign(&out, &figs, &options()).expect("pending run");
    assert_eq!(
        done.legends[1],
        "q2: flow 2 L/min, cooling 25 °C (incomplete: no recording)"
    );
    assert!(
        done.notes
            .iter()
            .any(|n| n.contains("run q2 has no recording"))
    );
    // At most q2's legend sample is orange (none without a font), no curve.
    let (_, _, px) = png_pixels(&figs.join("amplitude_node8.png"));
    let count =
        |c: plotters::style::RGBColor| px.chunks(3).filter(|p| *p == [c.0, c.1, c.2]).count();
    assert!(count(PALETTE[0]) > 500, "q20 drawn");
    assert!(count(PALETTE[1]) < 200, "q2 in the legend only");
    std::fs::remove_dir_all(&figs).expect("clean");

    // A damaged recording is an error whatever the status.
    std::fs::write(&rec, b"this is not MCAP").expect("write");
    let msg = err(plot_campaign(&out, &figs, &options()).expect_err("corrupt recording"));
    assert!(
        msg.contains("q2.mcap") && msg.contains("not an MCAP file"),
        "{msg}"
    );
    assert!(!figs.join("amplitude_node8.png").exists());
}

#[test]
fn campaign_command_writes_figures_unless_told_not_to() {
    let exe = env!("CARGO_BIN_EXE_tmrotor");
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_thermal_campaign(dir.path());
    let out = dir.path().join("out");

    let run = Command::new(exe)
        .args(["campaign", "-q", "--no-figures"])
        .arg(&file)
        .output()
        .expect("run tmrotor");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(!out.join("figures").exists());

    // Resumes (both runs complete), then draws into figures/.
    let run = Command::new(exe)
        .args(["campaign", "-q"])
        .arg(&file)
        .output()
        .expect("run tmrotor");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("wrote") && stdout.contains("amplitude_node8.png"),
        "{stdout}"
    );
    assert!(out.join("figures/clearance_variation.png").exists());
    // the closing line: the runs, the wall time and (on Linux) the CPU time
    let last = stdout.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("campaign: 2/2 runs completed (2 before), ") && last.contains(" in "),
        "{stdout}"
    );
    if cfg!(target_os = "linux") {
        assert!(last.contains("% of one core"), "{last}");
    }

    // `campaign plot` with its options; a missing directory is an error naming the file.
    let figs = dir.path().join("plots");
    let run = Command::new(exe)
        .args(["campaign", "plot"])
        .arg(&out)
        .arg("--out")
        .arg(&figs)
        .args(["--node", "1", "--node", "8", "--omega", "410"])
        .output()
        .expect("run tmrotor");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for name in [
        "amplitude_node1.png",
        "amplitude_node8.png",
        "bearing_temperatures_omega410.png",
    ] {
        assert_eq!(png_pixels(&figs.join(name)).0, 1200, "{name}");
    }
    let run = Command::new(exe)
        .args(["campaign", "plot"])
        .arg(dir.path().join("nowhere"))
        .output()
        .expect("run tmrotor");
    assert_eq!(run.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("nowhere/manifest.toml") && stderr.contains("No such file"),
        "{stderr}"
    );
}

/// Synthetic recordings (closed-form 2-DoF rotor with a fold pair, stability recorded) in
/// a hand-written manifest: unstable parts are drawn dashed and lighter, figures whose data
/// the runs lack are skipped with a note.
#[test]
fn campaign_plot_draws_unstable_parts_differently() {
    use tmrotor::record::synthetic::{self, SyntheticOptions};
    let dir = tempfile::tempdir().expect("tempdir");
    let mut manifest = campaign::Manifest::default();
    for (name, points, flow) in [("a", 10, 20.0), ("b", 14, 2.0)] {
        let options = SyntheticOptions {
            points_per_side: points,
            ..Default::default()
        };
        let rec = dir.path().join(format!("{name}.mcap"));
        synthetic::write_mcap(&rec, &options, true).expect("write");
        let mut settings = toml::Table::new();
        settings.insert("flow_l_min".into(), toml::Value::Float(flow));
        settings.insert("cooling_temp_c".into(), toml::Value::Float(25.0));
        manifest.runs.push(campaign::ManifestEntry {
            name: name.into(),
            status: "completed".into(),
            recording: format!("{name}.mcap"),
            sha256: sha256_file(&rec).expect("sha"),
            settings,
            ..Default::default()
        });
    }
    std::fs::write(
        dir.path().join("manifest.toml"),
        toml::to_string(&manifest).expect("toml"),
    )
    .expect("write manifest");
    let figs = dir.path().join("figs");
    let done = plot_campaign(dir.path(), &figs, &FigureOptions::default()).expect("plot");
    // No node 8 in these recordings: the first recorded node is drawn.
    assert_eq!(
        done.written[0].file_name().expect("name"),
        "amplitude_node1.png"
    );
    let (_, _, px) = png_pixels(&done.written[0]);
    for (k, c) in PALETTE[..2].iter().enumerate() {
        assert!(has_colour(&px, *c), "run {k}: stable part");
        let light = tmrotor::figure::lighter(*c, 0.35);
        assert!(has_colour(&px, light), "run {k}: unstable part, lighter");
    }
    assert!(
        done.notes
            .iter()
            .any(|n| n.contains("rolling_element_temperatures not written")),
        "{:?}",
        done.notes
    );
}

#[test]
fn the_example_campaign_files_load() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let (_, paper, _) = campaign::load(&examples.join("paper_campaign.toml")).expect("paper");
    let names: Vec<&str> = paper.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["q20", "q10", "q5", "q2", "q1", "q2-50C"]);
    let (_, grid, out) = campaign::load(&examples.join("grid_campaign.toml")).expect("grid");
    assert_eq!(grid.len(), 10);
    assert_eq!(
        (grid[0].name.as_str(), grid[9].name.as_str()),
        ("q20-25C", "q1-50C")
    );
    assert!(grid.iter().all(|r| r.settings.harmonic.order == 3));
    assert_eq!(out, examples.join("grid_campaign-out"));
}

#[test]
fn a_damaged_manifest_stops_the_campaign_and_keeps_the_recordings() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    let out = dir.path().join("out");
    let manifest = out.join("manifest.toml");
    let text = std::fs::read_to_string(&manifest).expect("manifest");
    // cut in the middle, as by a full disk
    std::fs::write(&manifest, &text[..text.len() / 2]).expect("truncate");
    let err = campaign::run(&file, Some(2), None, None, &quiet)
        .expect_err("damaged manifest")
        .to_string();
    assert!(
        err.contains("manifest.toml") && err.contains("not a campaign manifest"),
        "{err}"
    );
    assert!(err.contains("recordings beside it are kept"), "{err}");
    for r in &m.runs {
        assert_eq!(
            sha256_file(&out.join(&r.recording)).expect("recording"),
            r.sha256,
            "{} was touched",
            r.name
        );
    }
    // a damaged shard manifest is named by merge
    std::fs::write(out.join("manifest-shard-0-of-2.toml"), "runs = 3").expect("write");
    let err = campaign::merge_manifests(&out)
        .expect_err("merge")
        .to_string();
    assert!(
        err.contains("manifest-shard-0-of-2.toml") && err.contains("not a campaign manifest"),
        "{err}"
    );
}

#[test]
fn a_grid_of_twelve_runs_is_drawn_in_twelve_colours() {
    use tmrotor::figure::campaign::run_colour;
    // twenty distinct colours, then again
    let colours: Vec<_> = (0..20).map(run_colour).collect();
    for (i, a) in colours.iter().enumerate() {
        assert!(
            colours[i + 1..].iter().all(|b| b != a),
            "colour {i} repeats"
        );
    }
    assert_eq!(run_colour(20), run_colour(0));
    assert_eq!(run_colour(0), PALETTE[0]);
    // a campaign of twelve short runs: the eleventh and twelfth have colours of their own
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("g.toml");
    std::fs::write(
        &path,
        r#"
[defaults]
order = 1
omega_start = 400.0
omega_end = 440.0
max_points = 6
stability = false
[grid]
name = "q{flow_l_min}-{cooling_temp_c}C"
flow_l_min = [20.0, 10.0, 5.0, 2.0, 1.0, 0.5]
cooling_temp_c = [25.0, 50.0]
"#,
    )
    .expect("write");
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&path, None, None, None, &quiet).expect("campaign");
    assert_eq!(m.runs.len(), 12);
    let out = dir.path().join("g-out");
    let figs = out.join("figs");
    plot_campaign(&out, &figs, &options()).expect("plot");
    let (_, _, px) = png_pixels(&figs.join("amplitude_node8.png"));
    for k in 0..12 {
        assert!(
            has_colour(&px, run_colour(k)),
            "run {k} not drawn in its colour"
        );
    }
}

#[test]
fn a_dry_run_lists_what_would_run_and_writes_nothing() {
    let exe = env!("CARGO_BIN_EXE_tmrotor");
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let out = dir.path().join("out");
    let dry = |extra: &[&str]| {
        let run = Command::new(exe)
            .args(["campaign", "--dry-run"])
            .args(extra)
            .arg(&file)
            .output()
            .expect("run tmrotor");
        let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
        assert!(
            run.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&run.stderr)
        );
        stdout
    };
    let listed = dry(&[]);
    assert!(
        listed.contains(": 3 runs, 3 to run, 0 complete"),
        "{listed}"
    );
    for name in ["a", "b", "c"] {
        assert!(
            listed
                .lines()
                .any(|l| l.contains(&format!(" {name}  run "))),
            "{listed}"
        );
    }
    assert!(
        listed.contains("ambient 30 °C"),
        "run b's own setting: {listed}"
    );
    assert!(!out.exists(), "a dry run wrote {}", out.display());
    // a shard lists its runs with their positions in the file
    let shard = dry(&["--shard", "1/2"]);
    assert!(shard.contains("shard 1/2: 1 run, 1 to run"), "{shard}");
    assert!(shard.contains("#1   b"), "{shard}");
    // after a campaign: complete runs would be skipped, a damaged one run again
    let quiet = |_: campaign::Event<'_>| {};
    campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    std::fs::write(out.join("c.mcap"), b"garbage").expect("damage");
    let (planned, _) = campaign::plan(&file, None).expect("plan");
    let skip: Vec<(&str, bool)> = planned
        .iter()
        .map(|p| (p.run.name.as_str(), p.skip))
        .collect();
    assert_eq!(skip, [("a", true), ("b", true), ("c", false)]);
    let listed = dry(&[]);
    assert!(listed.contains("3 runs, 1 to run, 2 complete"), "{listed}");
    assert!(listed.contains("skip: completed"), "{listed}");
    // and a setting the sweep refuses is found by the dry run too
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[grid]\nflow_l_min = [2.0, -1.0]\n").expect("write");
    let err = campaign::plan(&bad, None)
        .expect_err("negative flow")
        .to_string();
    assert!(err.contains("run flow_l_min=-1"), "{err}");
}

/// `lean = true` in a campaign file writes recordings without /orbits and /scene; they
/// read back with every point.
#[test]
fn a_lean_campaign_leaves_out_orbits_and_scene() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let text = std::fs::read_to_string(&file).expect("read");
    std::fs::write(&file, format!("lean = true\n{text}")).expect("write");
    let quiet = |_: campaign::Event<'_>| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    for r in &m.runs {
        let rec = tmrotor::record::read_recording(dir.path().join("out").join(&r.recording))
            .expect("recording");
        assert!(rec.complete && rec.points.len() == r.points, "{r:?}");
        let topics: Vec<&str> = rec.topics.iter().map(|t| t.topic.as_str()).collect();
        assert!(
            !topics.contains(&"/orbits") && !topics.contains(&"/scene"),
            "{topics:?}"
        );
        assert!(
            rec.points
                .iter()
                .all(|p| p.orbits.is_empty() && p.period_s > 0.0)
        );
    }
}
