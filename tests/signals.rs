//! A sweep stopped by Ctrl-C (SIGINT) or by a termination signal (SIGTERM: what a cluster
//! scheduler sends at a job's time limit) ends cleanly: a complete recording of the points
//! computed so far with status `interrupted`, and exit status 130 so that scripts and
//! schedulers see the work is not complete. A sweep that finishes says what it took.
#![cfg(unix)]

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tmrotor::record::{RunStatus, read_recording};

const BIN: &str = env!("CARGO_BIN_EXE_tmrotor");

fn stopped_by(signal: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sweep.mcap");
    let mut child = Command::new(BIN)
        .args(["sweep", "--output"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the sweep starts");
    // the recording is written as sweep.mcap.partial while the run goes on, renamed to
    // sweep.mcap when it ends; a few points after it appears, the signal
    let partial = dir.path().join("sweep.mcap.partial");
    let start = Instant::now();
    while !partial.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no recording");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_secs(4));
    assert!(
        child.try_wait().expect("status").is_none(),
        "the sweep ended before the signal"
    );
    // the shell's built-in kill: no separate kill binary needed
    let kill = Command::new("sh")
        .args(["-c", &format!("kill {signal} {}", child.id())])
        .status()
        .expect("sh runs");
    assert!(kill.success());
    let output = child.wait_with_output().expect("the sweep ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{signal}: {stderr}");
    assert!(
        stderr.contains("interrupted: the sweep stopped after"),
        "{stderr}"
    );
    // stderr is a pipe: a plain line on what runs instead of a progress bar
    assert!(
        stderr.starts_with("sweep: ω 300 → 700 rad/s, order 3, writing ")
            && stderr.contains("sweep.mcap.partial until the run ends"),
        "{stderr}"
    );
    assert!(
        !stderr.contains('\u{1b}'),
        "terminal escapes in a pipe: {stderr}"
    );
    let rec = read_recording(&out).expect("a readable recording");
    assert!(!partial.exists(), "renamed into place");
    assert!(
        !dir.path().join("sweep.mcap.lock").exists(),
        "the lock is released"
    );
    assert!(rec.complete, "{signal}: {:?}", rec.notes);
    assert_eq!(rec.status, Some(RunStatus::Interrupted));
    assert!(!rec.points.is_empty(), "{signal}: no point kept");
    // every point the sweep counted is in the recording, in order
    let counted: usize = stderr
        .split("the sweep stopped after ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("a point count in the message");
    assert_eq!(rec.points.len(), counted, "{signal}: {stderr}");
    let indices: Vec<u64> = rec.points.iter().map(|p| p.index).collect();
    let expected: Vec<u64> = (0..counted as u64).collect();
    assert_eq!(indices, expected, "{signal}: points in order, none missing");
}

#[test]
fn sigterm_stops_a_sweep_with_a_complete_recording() {
    stopped_by("-TERM");
}

#[test]
fn sigint_stops_a_sweep_with_a_complete_recording() {
    stopped_by("-INT");
}

/// The sweep's summary as a process: the points and time, the time line, and (on Linux)
/// the CPU time with its share of one core.
#[test]
fn a_finished_sweep_reports_its_time_and_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("short.mcap");
    let run = Command::new(BIN)
        .args([
            "sweep",
            "--omega",
            "300:310",
            "--order",
            "1",
            "--no-thermal",
            "-q",
        ])
        .arg("--output")
        .arg(&out)
        .output()
        .expect("the sweep runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let lines: Vec<&str> = stdout.lines().collect();
    // plain words, no debug formatting: "12 points in 1.3 s, completed → short.mcap"
    assert!(
        lines[0].contains(" points in ") && lines[0].contains(", completed → "),
        "{stdout}"
    );
    assert!(!stdout.contains("(Completed)"), "{stdout}");
    // the stability verdicts counted
    let counts: Vec<usize> = lines[1]
        .trim()
        .split(", ")
        .filter_map(|part| part.split(' ').next()?.parse().ok())
        .collect();
    assert!(
        lines[1].contains(" stable, ") && lines[1].ends_with(" unstable") && counts.len() == 2,
        "{stdout}"
    );
    let points: usize = lines[0]
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .expect("point count");
    assert_eq!(counts[0] + counts[1], points, "{stdout}");
    // the kernel's instruction set only with -v
    assert!(
        lines[2].starts_with("  time: corrector ") && !lines[2].contains("kernel"),
        "{stdout}"
    );
    assert!(
        lines
            .last()
            .is_some_and(|l| l.starts_with("next: replay info ")),
        "{stdout}"
    );
    if cfg!(target_os = "linux") {
        assert!(
            lines[3].starts_with("  CPU ") && lines[3].contains("% of one core"),
            "{stdout}"
        );
    }
}

/// A second interrupt right after the first stops at once, says so, and leaves every point
/// already written readable in the in-progress file (or, when the first interrupt had already
/// finished the recording, the complete one).
#[test]
fn a_second_interrupt_stops_at_once_and_keeps_the_points_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sweep.mcap");
    let partial = dir.path().join("sweep.mcap.partial");
    let child = Command::new(BIN)
        .args(["sweep", "-q", "--output"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the sweep starts");
    let start = Instant::now();
    while !partial.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no recording");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_secs(4));
    let pid = child.id();
    let kill = Command::new("sh")
        .args(["-c", &format!("kill -INT {pid}; kill -INT {pid}")])
        .status()
        .expect("sh runs");
    assert!(kill.success());
    let output = child.wait_with_output().expect("the sweep ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    let rec = if partial.exists() {
        assert!(
            stderr.contains("second interrupt: stopping at once"),
            "{stderr}"
        );
        read_recording(&partial).expect("the in-progress file reads")
    } else {
        read_recording(&out).expect("the recording reads")
    };
    assert!(!rec.points.is_empty(), "{stderr}");
}

/// A transient run stopped by SIGINT keeps every revolution it wrote, in a complete
/// recording with status `interrupted`, and exits with 130.
#[test]
fn sigint_stops_a_transient_with_a_complete_recording() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("t.mcap");
    let child = Command::new(BIN)
        .args(["transient", "--ramp", "300:700", "--accel", "1", "-o"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the transient starts");
    let partial = dir.path().join("t.mcap.partial");
    let start = Instant::now();
    while !partial.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no recording");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_secs(2));
    let kill = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", child.id())])
        .status()
        .expect("sh runs");
    assert!(kill.success());
    let output = child.wait_with_output().expect("the run ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("the transient stopped after"), "{stderr}");
    let rec = read_recording(&out).expect("a readable recording");
    assert!(rec.complete, "{:?}", rec.notes);
    assert_eq!(rec.status, Some(RunStatus::Interrupted));
    let t = rec.transient.expect("transient records");
    let counted: usize = stderr
        .split("the transient stopped after ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("a revolution count");
    assert!(counted > 0);
    assert_eq!(t.revolutions.len(), counted, "{stderr}");
    assert!(t.missing.is_empty());
}
