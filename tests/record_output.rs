//! Safe outputs: one writer per recording and per campaign directory (an OS lock that names
//! its holder), recordings written as `<target>.partial` and renamed into place when the
//! run ends, an earlier recording kept when a run fails before its first point, the
//! in-progress file readable meanwhile, and a killed writer's file never overwritten.

use std::path::Path;

use tmrotor::campaign;
use tmrotor::record::output::{lock, lock_path, partial_path};
use tmrotor::record::synthetic::{SyntheticOptions, generate, write_mcap};
use tmrotor::record::{McapOptions, McapSink, RecordError, RunStatus, Sink, read_recording};

fn sha(path: &Path) -> String {
    campaign::sha256_file(path).expect("readable")
}

#[test]
fn a_second_writer_of_a_recording_stops_at_once_naming_the_lock_and_its_holder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("run.mcap");
    let first = McapSink::create(&target, McapOptions::default()).expect("first writer");
    assert_eq!(first.path(), partial_path(&target));
    let err = match McapSink::create(&target, McapOptions::default()) {
        Ok(_) => panic!("a second writer was let in"),
        Err(e) => e,
    };
    assert!(matches!(err, RecordError::Locked { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("run.mcap.lock")
            && msg.contains(&format!("tmrotor process {}", std::process::id())),
        "{msg}"
    );
    // the first writer's file is untouched by the attempt, and once it ends the lock is free
    drop(first);
    assert!(!lock_path(&target).exists(), "the lock file is removed");
    McapSink::create(&target, McapOptions::default()).expect("the output is free again");
}

#[test]
fn a_run_without_points_keeps_an_earlier_recording_and_one_with_points_replaces_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("precious.mcap");
    let options = SyntheticOptions {
        points_per_side: 3,
        ..SyntheticOptions::default()
    };
    write_mcap(&target, &options, true).expect("a complete recording");
    let before = sha(&target);
    // a run that fails before its first point
    let data = generate(&options);
    let mut sink = McapSink::create(&target, McapOptions::default()).expect("sink");
    sink.begin_run(&data.run).expect("begin");
    sink.finish(RunStatus::Failed("the start did not converge".into()))
        .expect("finish");
    assert!(!sink.committed());
    assert_eq!(sha(&target), before, "the earlier recording is kept");
    assert!(!partial_path(&target).exists() && !lock_path(&target).exists());
    // a run with points replaces it, atomically, when it ends
    let mut sink = McapSink::create(&target, McapOptions::default()).expect("sink");
    sink.begin_run(&data.run).expect("begin");
    sink.write_point(&data.points[0]).expect("point");
    // meanwhile the in-progress file is readable, and the old recording still in place
    let partial = read_recording(partial_path(&target)).expect("in-progress file");
    assert_eq!(partial.points.len(), 1);
    assert!(!partial.complete);
    assert_eq!(sha(&target), before);
    sink.finish(RunStatus::Interrupted).expect("finish");
    assert!(sink.committed());
    let rec = read_recording(&target).expect("new recording");
    assert_eq!(rec.points.len(), 1);
    assert_eq!(rec.status, Some(RunStatus::Interrupted));
    assert!(!partial_path(&target).exists() && !lock_path(&target).exists());
}

#[test]
fn a_killed_writers_file_is_moved_aside_not_overwritten() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("run.mcap");
    // what a killed process leaves: the partial file (its lock died with it)
    std::fs::write(partial_path(&target), b"points of a killed run").expect("write");
    let sink = McapSink::create(&target, McapOptions::default()).expect("sink");
    let kept = sink.stale_partial().expect("moved aside").to_path_buf();
    assert!(
        kept.file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with("run.killed-") && n.ends_with(".mcap")),
        "{}",
        kept.display()
    );
    assert_eq!(
        std::fs::read(&kept).expect("kept"),
        b"points of a killed run"
    );
}

#[test]
fn a_second_campaign_on_the_same_directory_stops_before_running() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("c.toml");
    std::fs::write(
        &file,
        "output_dir = \"out\"\n[defaults]\norder = 1\nomega_start = 400.0\n\
         omega_end = 401.0\nmax_points = 2\nstability = false\nthermal = false\n\
         [[runs]]\nname = \"a\"\n",
    )
    .expect("write");
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).expect("dir");
    let held = lock(&out.join(campaign::CAMPAIGN_LOCK), "campaign").expect("lock");
    let quiet = |_: campaign::Event<'_>| {};
    let msg = campaign::run(&file, Some(1), None, None, &quiet)
        .expect_err("refused")
        .to_string();
    assert!(
        msg.contains("c.toml") && msg.contains("campaign.lock") && msg.contains("is held"),
        "{msg}"
    );
    assert!(!out.join("a.mcap").exists() && !out.join("manifest.toml").exists());
    drop(held);
    let m = campaign::run(&file, Some(1), None, None, &quiet).expect("free again");
    assert_eq!(m.runs[0].status, "completed");
    assert!(!out.join(campaign::CAMPAIGN_LOCK).exists());
}

/// Two sweep processes to the same output: the second ends at once with the lock's holder.
#[cfg(unix)]
#[test]
fn two_sweeps_to_one_output_the_second_stops_at_once() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let bin = env!("CARGO_BIN_EXE_tmrotor");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sweep.mcap");
    let mut first = Command::new(bin)
        .args(["sweep", "-q", "--output"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("first sweep");
    let start = Instant::now();
    while !partial_path(&out).exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no partial file");
        std::thread::sleep(Duration::from_millis(20));
    }
    let t = Instant::now();
    let second = Command::new(bin)
        .args(["sweep", "-q", "--output"])
        .arg(&out)
        .output()
        .expect("second sweep");
    let waited = t.elapsed();
    let _ = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", first.id())])
        .status();
    let _ = first.wait();
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success(), "{err}");
    assert!(
        err.contains("sweep.mcap.lock") && err.contains(&format!("tmrotor process {}", first.id())),
        "{err}"
    );
    assert!(waited < Duration::from_secs(10), "{waited:?}");
    // the first sweep's recording is intact
    let rec = read_recording(&out).expect("first recording");
    assert!(rec.complete && !rec.points.is_empty());
}

/// A directory, a device or a FIFO is refused at once, not read until memory runs out.
#[cfg(unix)]
#[test]
fn only_regular_files_are_read() {
    let dir = tempfile::tempdir().expect("tempdir");
    let msg = read_recording(dir.path())
        .expect_err("a directory")
        .to_string();
    assert!(msg.contains("it is a directory"), "{msg}");
    let msg = read_recording("/dev/zero")
        .expect_err("a device")
        .to_string();
    assert!(msg.contains("not a regular file"), "{msg}");
    let fifo = dir.path().join("pipe");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if made {
        let msg = read_recording(&fifo).expect_err("a FIFO").to_string();
        assert!(msg.contains("not a regular file"), "{msg}");
    }
}
