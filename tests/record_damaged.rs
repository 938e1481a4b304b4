//! Recordings cut short, killed writers, damaged and foreign files.

use std::path::Path;

use tmrotor::record::reader::{ReadError, read_recording_bytes};
use tmrotor::record::synthetic::{self, SyntheticOptions};
use tmrotor::record::{RunStatus, read_recording};

fn sample(dir: &Path, finish: bool) -> (std::path::PathBuf, Vec<tmrotor::record::PointRecord>) {
    let path = dir.join(if finish { "full.mcap" } else { "killed.mcap" });
    let options = SyntheticOptions {
        points_per_side: 8,
        ..Default::default()
    };
    synthetic::write_mcap(&path, &options, finish).expect("write");
    (path, synthetic::generate(&options).points)
}

#[test]
fn file_cut_at_many_offsets_reads_a_prefix_and_says_incomplete() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), true);
    let bytes = std::fs::read(&path).expect("read");
    let full = read_recording_bytes(&bytes, &path).expect("full");
    assert!(full.complete);
    assert_eq!(full.points, points);

    let mut previous = 0;
    let mut readable_cuts = 0;
    for k in 1..40 {
        let cut = bytes.len() * k / 40;
        match read_recording_bytes(&bytes[..cut], &path) {
            Ok(rec) => {
                readable_cuts += 1;
                assert!(
                    !rec.complete,
                    "cut at {cut} of {} claims complete",
                    bytes.len()
                );
                assert!(!rec.notes.is_empty());
                if rec.status.is_some() {
                    // Cut inside the summary section: the data section is whole.
                    assert_eq!(rec.points.len(), points.len(), "cut at {cut}");
                }
                // What is read is exactly the first points, unchanged.
                assert_eq!(rec.points[..], points[..rec.points.len()], "cut at {cut}");
                assert!(rec.points.len() >= previous, "more data, fewer points");
                previous = rec.points.len();
            }
            Err(e) => {
                // Only a cut before the run description may fail, and then clearly.
                assert!(
                    matches!(e, ReadError::Foreign { .. } | ReadError::NotMcap { .. }),
                    "cut at {cut}: {e}"
                );
                assert!(
                    previous == 0,
                    "cut at {cut} failed after readable cuts: {e}"
                );
                assert!(e.to_string().contains("full.mcap"));
            }
        }
    }
    assert!(readable_cuts > 30);
    assert!(
        previous >= points.len() - 2,
        "late cuts lose at most the last points"
    );
    // Cutting the last byte only loses the end magic: every point is still there.
    let rec = read_recording_bytes(&bytes[..bytes.len() - 1], &path).expect("read");
    assert_eq!(rec.points.len(), points.len());
    assert!(!rec.complete);
}

#[test]
fn killed_writer_loses_no_written_point() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), false);
    let rec = read_recording(&path).expect("read");
    assert!(!rec.complete);
    assert_eq!(rec.status, None);
    assert_eq!(rec.points, points, "every flushed point must be readable");
    assert_eq!(rec.bifurcations.len(), 2);
}

#[test]
fn damaged_chunk_is_a_clear_error_naming_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, _) = sample(dir.path(), true);
    let mut bytes = std::fs::read(&path).expect("read");
    // Flip bytes in the middle of the data section (inside a compressed chunk).
    let mid = bytes.len() / 2;
    for b in &mut bytes[mid..mid + 16] {
        *b ^= 0x5a;
    }
    let err = read_recording_bytes(&bytes, &path).expect_err("damaged");
    assert!(matches!(err, ReadError::Corrupt { .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.contains("full.mcap") && text.contains("damaged"),
        "{text}"
    );
}

#[test]
fn foreign_files_are_rejected_with_the_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let text = dir.path().join("notes.mcap");
    std::fs::write(&text, "omega = 300\n").expect("write");
    let err = read_recording(&text).expect_err("text file");
    assert!(matches!(err, ReadError::NotMcap { .. }));
    assert!(err.to_string().contains("notes.mcap") && err.to_string().contains("magic"));

    let missing = dir.path().join("missing.mcap");
    let err = read_recording(&missing).expect_err("missing");
    assert!(matches!(err, ReadError::Io { .. }) && err.to_string().contains("missing.mcap"));

    // A valid MCAP file from someone else.
    let other = dir.path().join("other.mcap");
    {
        let mut w = mcap::Writer::new(std::io::BufWriter::new(
            std::fs::File::create(&other).expect("create"),
        ))
        .expect("writer");
        let ch = w
            .add_channel(0, "/chatter", "json", &Default::default())
            .expect("channel");
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: ch,
                sequence: 0,
                log_time: 1,
                publish_time: 1,
            },
            b"{\"data\": 1}",
        )
        .expect("message");
        w.finish().expect("finish");
    }
    let err = read_recording(&other).expect_err("foreign");
    assert!(matches!(err, ReadError::Foreign { .. }), "{err}");
    assert!(err.to_string().contains("/chatter"), "{err}");
}

#[test]
fn completed_status_survives_the_round_trip() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, _) = sample(dir.path(), true);
    assert_eq!(
        read_recording(&path).expect("read").status,
        Some(RunStatus::Completed)
    );
}
