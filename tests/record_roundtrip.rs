//! Write → read round trips of the MCAP sink against the in-memory sink, the re-derived
//! quantities against the closed-form synthetic values, and the sink's checks.

mod common;

use std::collections::BTreeMap;

use mcap::MessageStream;
use prost_reflect::{DescriptorPool, DynamicMessage};
use tmrotor::derive;
use tmrotor::record::synthetic::{self, SyntheticOptions};
use tmrotor::record::{
    McapOptions, McapSink, MemorySink, RecordError, RunStatus, Sink, read_recording, record_run,
};

fn write_both(options: &SyntheticOptions, path: &std::path::Path) -> MemorySink {
    write_both_with(options, path, McapOptions::default())
}

fn write_both_with(
    options: &SyntheticOptions,
    path: &std::path::Path,
    mcap: McapOptions,
) -> MemorySink {
    let data = synthetic::generate(options);
    let mut mem = MemorySink::new();
    let mut file = McapSink::create(path, mcap).expect("create");
    for sink in [&mut mem as &mut dyn Sink, &mut file as &mut dyn Sink] {
        sink.begin_run(&data.run).expect("begin");
        let mut bifs = data.bifurcations.iter().peekable();
        for p in &data.points {
            sink.write_point(p).expect("point");
            while let Some(b) = bifs.next_if(|b| b.after_point + 1 == p.index) {
                sink.write_bifurcation(b).expect("bifurcation");
            }
        }
        sink.finish(RunStatus::Completed).expect("finish");
    }
    mem
}

/// A lean recording leaves out /orbits and /scene and reads back with everything else
/// equal; the orbits re-derived from its /harmonics equal the ones a full recording
/// stores, and its period is the basis's.
#[test]
fn lean_recording_reads_back_and_rederives_the_orbits() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (full_path, lean_path) = (dir.path().join("full.mcap"), dir.path().join("lean.mcap"));
    let options = SyntheticOptions::default();
    write_both(&options, &full_path);
    write_both_with(&options, &lean_path, McapOptions::lean());
    let full = read_recording(&full_path).expect("full");
    let lean = read_recording(&lean_path).expect("lean");
    assert!(lean.complete, "notes: {:?}", lean.notes);
    let topics: Vec<&str> = lean.topics.iter().map(|t| t.topic.as_str()).collect();
    assert!(
        !topics.contains(&"/orbits") && !topics.contains(&"/scene"),
        "{topics:?}"
    );
    assert!(topics.contains(&"/harmonics"), "{topics:?}");
    assert_eq!(lean.points.len(), full.points.len());
    assert_eq!(lean.bifurcations, full.bifurcations);
    for (l, f) in lean.points.iter().zip(&full.points) {
        assert!(l.orbits.is_empty());
        assert!((l.period_s - f.period_s).abs() <= 1e-15 * f.period_s);
        let mut l = l.clone();
        l.orbits.clone_from(&f.orbits);
        l.period_s = f.period_s;
        assert_eq!(&l, f);
        let samples = f.orbits[0].x_m.len();
        let orbits =
            derive::orbits(&lean.run, &l.coeffs_mech, l.omega_rad_s, samples).expect("orbits");
        // Relative to the orbit's size: near a zero crossing a sample is a difference of
        // terms of the orbit's size.
        for (got, want) in orbits.iter().zip(&f.orbits) {
            let scale = want
                .x_m
                .iter()
                .chain(&want.y_m)
                .fold(0.0_f64, |m, v| m.max(v.abs()));
            for (a, b) in got
                .x_m
                .iter()
                .zip(&want.x_m)
                .chain(got.y_m.iter().zip(&want.y_m))
            {
                assert!(
                    (a - b).abs() <= 1e-12 * scale,
                    "{a} vs {b} (orbit size {scale})"
                );
            }
        }
    }
    let size = |p: &std::path::Path| std::fs::metadata(p).expect("size").len();
    assert!(
        size(&lean_path) < size(&full_path) / 2,
        "{} vs {}",
        size(&lean_path),
        size(&full_path)
    );
}

#[test]
fn thermal_run_reads_back_identical() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    let mem = write_both(&SyntheticOptions::default(), &path);
    let rec = read_recording(&path).expect("read");
    assert!(rec.complete, "notes: {:?}", rec.notes);
    assert_eq!(rec.status, Some(RunStatus::Completed));
    assert_eq!(Some(&rec.run), mem.run.as_ref());
    assert_eq!(rec.points.len(), mem.points.len());
    assert!(rec.points.len() > 30);
    assert_eq!(rec.points, mem.points);
    assert_eq!(rec.bifurcations, mem.bifurcations);
    assert_eq!(rec.bifurcations.len(), 2);
    let counts: BTreeMap<_, _> = rec
        .topics
        .iter()
        .map(|t| (t.topic.as_str(), t.messages))
        .collect();
    let n = mem.points.len() as u64;
    for topic in [
        "/summary",
        "/harmonics",
        "/orbits",
        "/temperatures",
        "/clearance",
        "/bearing_loads",
        "/thermal_forces",
        "/floquet",
        "/scene",
    ] {
        assert_eq!(counts.get(topic), Some(&n), "{topic}");
    }
    assert_eq!(counts.get("/bifurcations"), Some(&2));
    assert_eq!(counts.get("/run_info"), Some(&1));
    // start + 2 bifurcations + end
    assert_eq!(counts.get("/log"), Some(&4));
    assert!(rec.attachments.contains(&"synthetic.toml".to_string()));
    assert_eq!(
        rec.metadata["tmrotor.settings"]["hb.order"], "1",
        "settings metadata"
    );
}

#[test]
fn mechanical_run_has_no_thermal_topics_and_reads_back_identical() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("mech.mcap");
    let options = SyntheticOptions {
        thermal: false,
        stability: false,
        points_per_side: 5,
        ..Default::default()
    };
    let mem = write_both(&options, &path);
    let rec = read_recording(&path).expect("read");
    assert!(rec.complete);
    assert_eq!(rec.points, mem.points);
    assert!(rec.points.iter().all(|p| p.stable.is_none()));
    let topics: Vec<&str> = rec.topics.iter().map(|t| t.topic.as_str()).collect();
    for absent in [
        "/temperatures",
        "/clearance",
        "/bearing_loads",
        "/thermal_forces",
        "/floquet",
        "/bifurcations",
    ] {
        assert!(
            !topics.contains(&absent),
            "{absent} should not be published"
        );
    }
}

#[test]
fn rederived_orbits_and_amplitudes_equal_recorded_closed_form_values() {
    let data = synthetic::generate(&SyntheticOptions::default());
    for p in &data.points {
        let samples = p.orbits[0].x_m.len();
        let orbits =
            derive::orbits(&data.run, &p.coeffs_mech, p.omega_rad_s, samples).expect("orbits");
        let scale = p.amplitude_rms_m[0];
        for (got, want) in orbits[0].x_m.iter().zip(&p.orbits[0].x_m) {
            assert!((got - want).abs() <= 1e-12 * scale, "x: {got} vs {want}");
        }
        for (got, want) in orbits[0].y_m.iter().zip(&p.orbits[0].y_m) {
            assert!((got - want).abs() <= 1e-12 * scale, "y: {got} vs {want}");
        }
        // Eq. 35 by Parseval vs the closed form sqrt(a² + c²) …
        let amp = derive::amplitude_rms(&data.run, &p.coeffs_mech).expect("amplitude");
        assert!((amp[0] - p.amplitude_rms_m[0]).abs() <= 1e-12 * scale);
        // … and vs the discrete mean over the recorded orbit samples (exact for
        // trigonometric polynomials of degree < samples/2).
        let o = &p.orbits[0];
        let n = o.x_m.len() as f64;
        let (mx, my) = (o.x_m.iter().sum::<f64>() / n, o.y_m.iter().sum::<f64>() / n);
        let ms = o
            .x_m
            .iter()
            .zip(&o.y_m)
            .map(|(x, y)| (x - mx).powi(2) + (y - my).powi(2))
            .sum::<f64>()
            / n;
        assert!((ms.sqrt() - amp[0]).abs() <= 1e-10 * scale);
        // Temperature: mean exact, extremes within the sampling of a cos(ωt/2) term.
        let t = derive::temperature_stats(&data.run, &p.coeffs_therm, p.omega_rad_s, 2000)
            .expect("temperatures");
        let want = p.temperatures[0];
        assert_eq!(t[0].mean_c, want.mean_c);
        assert!((t[0].max_c - want.max_c).abs() < 1e-6);
        assert!((t[0].min_c - want.min_c).abs() < 1e-3);
    }
}

#[test]
fn log_time_increases_strictly_along_the_branch_and_every_message_decodes_with_its_embedded_schema()
{
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    write_both(&SyntheticOptions::default(), &path);
    let bytes = std::fs::read(&path).expect("read");
    let mut last_summary_time = None;
    let mut last_summary_index = None;
    let mut decoded = 0;
    for msg in MessageStream::new(&bytes).expect("stream") {
        let msg = msg.expect("message");
        let schema = msg.channel.schema.as_ref().expect("schema");
        assert_eq!(schema.encoding, "protobuf");
        assert_eq!(msg.channel.message_encoding, "protobuf");
        let pool = DescriptorPool::decode(schema.data.as_ref()).expect("descriptor set");
        let desc = pool
            .get_message_by_name(&schema.name)
            .expect("message in set");
        let dynamic = DynamicMessage::decode(desc, msg.data.as_ref()).expect("decodes");
        decoded += 1;
        if msg.channel.topic == "/summary" {
            let index = dynamic
                .get_field_by_name("index")
                .and_then(|v| v.as_u64())
                .expect("index");
            if let (Some(t), Some(i)) = (last_summary_time, last_summary_index) {
                assert!(msg.log_time > t && index > i);
            }
            last_summary_time = Some(msg.log_time);
            last_summary_index = Some(index);
        }
    }
    assert!(decoded > 300);
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    assert!(!summary.chunk_indexes.is_empty());
    assert!(
        summary
            .chunk_indexes
            .iter()
            .all(|c| c.compression == "zstd"),
        "chunks must be zstd-compressed"
    );
    assert!(summary.stats.is_some());
}

#[test]
fn sink_rejects_misuse_with_reasons() {
    let data = synthetic::generate(&SyntheticOptions {
        points_per_side: 3,
        ..Default::default()
    });
    let mut sink = MemorySink::new();
    assert!(matches!(
        sink.write_point(&data.points[0]),
        Err(RecordError::NotStarted(_))
    ));
    sink.begin_run(&data.run).expect("begin");
    sink.write_point(&data.points[1]).expect("point");
    assert!(matches!(
        sink.write_point(&data.points[0]),
        Err(RecordError::NonIncreasingIndex {
            index: 0,
            previous: 1
        })
    ));
    let mut bad = data.points[2].clone();
    bad.coeffs_mech.pop();
    let err = sink.write_point(&bad).expect_err("size mismatch");
    assert!(err.to_string().contains("coeffs_mech"), "{err}");
    sink.finish(RunStatus::Completed).expect("finish");
    assert!(matches!(
        sink.write_point(&data.points[2]),
        Err(RecordError::Finished)
    ));
}

#[derive(Debug)]
struct SweepError(String);
impl std::fmt::Display for SweepError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl From<RecordError> for SweepError {
    fn from(e: RecordError) -> Self {
        Self(e.to_string())
    }
}

#[test]
fn a_failing_run_is_still_finished_with_its_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("failed.mcap");
    let data = synthetic::generate(&SyntheticOptions {
        points_per_side: 4,
        ..Default::default()
    });
    let mut sink = McapSink::create(&path, McapOptions::default()).expect("create");
    let result: Result<(), SweepError> = record_run(&mut sink, &data.run, |s| {
        s.write_point(&data.points[0])?;
        s.write_point(&data.points[1])?;
        Err(SweepError("Newton diverged at ω = 451 rad/s".into()))
    });
    assert!(result.is_err());
    drop(sink);
    let rec = read_recording(&path).expect("read");
    assert!(rec.complete);
    assert_eq!(rec.points.len(), 2);
    assert_eq!(
        rec.status,
        Some(RunStatus::Failed("Newton diverged at ω = 451 rad/s".into()))
    );
}

#[test]
fn a_dropped_sink_finishes_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("dropped.mcap");
    let data = synthetic::generate(&SyntheticOptions {
        points_per_side: 4,
        ..Default::default()
    });
    {
        let mut sink = McapSink::create(&path, McapOptions::default()).expect("create");
        sink.begin_run(&data.run).expect("begin");
        sink.write_point(&data.points[0]).expect("point");
    }
    let rec = read_recording(&path).expect("read");
    assert!(rec.complete);
    assert!(matches!(rec.status, Some(RunStatus::Failed(_))));
    assert_eq!(rec.points.len(), 1);
}

/// A recording with a second branch (`/branches`): the synthetic run, then a branch on the
/// doubled basis (the synthetic points with a half-order harmonic added) written after it.
/// Read back, every point keeps its branch and its basis's coefficients, the branch its
/// origin and harmonics, and the quantities re-derived with the branch's basis are the
/// recorded ones.
#[test]
fn a_second_branch_on_its_own_basis_round_trips() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("branches.mcap");
    let two = common::TwoBranches::new();
    let mut mem = MemorySink::new();
    let mut file = McapSink::create(&path, McapOptions::default()).expect("create");
    for sink in [&mut mem as &mut dyn Sink, &mut file as &mut dyn Sink] {
        sink.begin_run(&two.data.run).expect("begin");
        for p in &two.data.points {
            sink.write_point(p).expect("point");
        }
        // a point of a branch not yet described is refused
        let err = sink
            .write_point(&two.branch_points[0])
            .expect_err("undescribed");
        assert!(matches!(err, RecordError::InvalidPoint { .. }), "{err}");
        let mut wrong = two.branch.clone();
        wrong.branch = 2;
        sink.write_branch(&wrong).expect_err("branch 2 before 1");
        sink.write_branch(&two.branch).expect("branch");
        for p in &two.branch_points {
            sink.write_point(p).expect("branch point");
        }
        sink.finish(RunStatus::Completed).expect("finish");
    }
    assert_eq!(mem.branches, vec![two.branch.clone()]);
    let rec = read_recording(&path).expect("read");
    assert!(rec.complete, "{:?}", rec.notes);
    assert_eq!(rec.branches, vec![two.branch.clone()]);
    assert_eq!(rec.branch_numbers(), vec![0, 1]);
    assert_eq!(
        rec.points.len(),
        two.data.points.len() + two.branch_points.len()
    );
    for (got, want) in rec.points.iter().zip(mem.points.iter()) {
        assert_eq!(got.index, want.index);
        assert_eq!(got.branch, want.branch);
        assert_eq!(got.coeffs_mech, want.coeffs_mech);
        assert_eq!(got.period_s, want.period_s);
    }
    let on_branch: Vec<_> = rec.points.iter().filter(|p| p.branch == 1).collect();
    assert_eq!(on_branch.len(), two.branch_points.len());
    let run1 = rec.run_of(1).expect("branch 1");
    assert_eq!(run1.harmonics, two.doubled.harmonics());
    for p in on_branch {
        assert_eq!(
            p.coeffs_mech.len(),
            two.data.run.n_mech * two.doubled.n_coeffs()
        );
        let orbits = derive::orbits(&run1, &p.coeffs_mech, p.omega_rad_s, 64).expect("orbits");
        for (a, b) in orbits.iter().zip(&p.orbits) {
            for (x, y) in a.x_m.iter().zip(&b.x_m) {
                assert!((x - y).abs() < 1e-15, "{x} vs {y}");
            }
        }
    }
    assert!(rec.run_of(2).is_none());

    // replay: info lists the branches, the branch table has the column, recover keeps them
    let file_arg = path.to_str().expect("utf-8 path");
    let (r, out, _) = common::replay_in_process(&["info", file_arg]);
    r.expect("info");
    assert!(out.contains("branches:    2"), "{out}");
    assert!(out.contains("branch 1: period_doubled"), "{out}");
    let (r, out, _) = common::replay_in_process(&["branch", file_arg, "--csv"]);
    r.expect("branch");
    assert!(out.starts_with("index,omega_rad_s,branch,"), "{out}");
    let ones = out
        .lines()
        .filter(|l| l.split(',').nth(2) == Some("1"))
        .count();
    assert_eq!(ones, two.branch_points.len());
    let copy = dir.path().join("copy.mcap");
    let (r, _, _) =
        common::replay_in_process(&["recover", file_arg, copy.to_str().expect("utf-8")]);
    r.expect("recover");
    let back = read_recording(&copy).expect("read the copy");
    assert_eq!(back.branches, rec.branches);
    assert_eq!(back.points.len(), rec.points.len());
}
