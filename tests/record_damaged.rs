//! Recordings cut short, killed writers, damaged and foreign files.

use std::path::Path;

use tmrotor::record::reader::{ReadError, read_recording_bytes};
use tmrotor::record::synthetic::{self, SyntheticOptions};
use tmrotor::record::{RunStatus, read_recording};

mod common;

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

/// Offsets of the chunk records of a file written by tmrotor (zstd chunks: the opcode, the
/// record length, and the compression string 37 bytes in).
fn chunk_offsets(bytes: &[u8]) -> Vec<usize> {
    let sig = b"\x04\x00\x00\x00zstd";
    (37..bytes.len().saturating_sub(sig.len()))
        .filter(|&i| &bytes[i..i + sig.len()] == sig && bytes[i - 37] == 0x06)
        .map(|i| i - 37)
        .collect()
}

fn chunk_len(bytes: &[u8], at: usize) -> usize {
    let mut a = [0u8; 8];
    a.copy_from_slice(&bytes[at + 1..at + 9]);
    9 + u64::from_le_bytes(a) as usize
}

/// What is read from a damaged file is exactly what was written, point by point; a file
/// that lost anything is never complete.
fn assert_intact_subset(
    rec: &tmrotor::record::Recording,
    points: &[tmrotor::record::PointRecord],
    what: &str,
) {
    for p in &rec.points {
        let want = points.iter().find(|q| q.index == p.index).expect("index");
        assert_eq!(
            p, want,
            "{what}: point {} altered; notes {:?}; topics {:?}",
            p.index, rec.notes, rec.topics
        );
    }
    if rec.complete {
        assert_eq!(
            rec.points.len(),
            points.len(),
            "{what}: complete but points lost"
        );
    }
}

#[test]
fn a_damaged_chunk_costs_its_point_only_and_is_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), true);
    let clean = std::fs::read(&path).expect("read");
    let chunks = chunk_offsets(&clean);
    assert!(
        chunks.len() > points.len(),
        "one chunk per point plus the run's"
    );
    // Flip one byte inside the compressed data of every chunk that holds a point.
    let mut lost_total = 0;
    for &at in &chunks[1..] {
        let mut bytes = clean.clone();
        bytes[at + 60] ^= 0x5a;
        let rec = read_recording_bytes(&bytes, &path).expect("a damaged chunk is not fatal");
        assert!(!rec.complete);
        assert!(
            rec.notes
                .iter()
                .any(|n| n.contains(&format!("chunk at byte {at}"))),
            "{:?}",
            rec.notes
        );
        assert_intact_subset(&rec, &points, &format!("flip in chunk at {at}"));
        let lost = points.len() - rec.points.len();
        assert!(lost <= 1, "one chunk, one point: lost {lost}");
        lost_total += lost;
        if lost == 1 {
            let gone = points
                .iter()
                .find(|p| rec.point(p.index).is_none())
                .expect("lost point");
            if gone.index + 1 < points.len() as u64 {
                assert_eq!(rec.missing, vec![gone.index], "{:?}", rec.notes);
            }
        }
    }
    assert!(lost_total >= points.len() - 1, "every point chunk was hit");
}

#[test]
fn a_bogus_chunk_length_skips_to_the_next_chunk() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), true);
    let mut bytes = std::fs::read(&path).expect("read");
    let chunks = chunk_offsets(&bytes);
    let at = chunks[5];
    bytes[at + 1..at + 9].copy_from_slice(&(u64::MAX / 3).to_le_bytes());
    let rec = read_recording_bytes(&bytes, &path).expect("read");
    assert!(!rec.complete);
    assert_intact_subset(&rec, &points, "bogus length");
    assert_eq!(rec.points.len(), points.len() - 1, "{:?}", rec.notes);
    assert_eq!(rec.missing.len(), 1, "{:?}", rec.notes);
    assert!(
        rec.notes
            .iter()
            .any(|n| n.contains("runs past the end of the file")),
        "{:?}",
        rec.notes
    );
}

#[test]
fn a_cut_out_last_point_is_not_complete() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), true);
    let clean = std::fs::read(&path).expect("read");
    let full = read_recording_bytes(&clean, &path).expect("full");
    // The chunk of the last point: the last chunk that holds a /summary.
    let chunks = chunk_offsets(&clean);
    let last = chunks
        .iter()
        .rev()
        .copied()
        .find(|&at| {
            let mut bytes = clean[..at].to_vec();
            bytes.extend_from_slice(&clean[at + chunk_len(&clean, at)..]);
            read_recording_bytes(&bytes, &path)
                .is_ok_and(|r| r.points.len() + 1 == full.points.len())
        })
        .expect("a chunk holding the last point");
    let mut bytes = clean[..last].to_vec();
    bytes.extend_from_slice(&clean[last + chunk_len(&clean, last)..]);
    let rec = read_recording_bytes(&bytes, &path).expect("read");
    assert!(!rec.complete, "{:?}", rec.notes);
    assert_intact_subset(&rec, &points, "cut-out last chunk");
    assert!(rec.missing.is_empty(), "no later point shows the gap");
}

#[test]
fn a_cut_out_chunk_is_named_and_counted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), true);
    let clean = std::fs::read(&path).expect("read");
    let at = chunk_offsets(&clean)[6];
    let mut bytes = clean[..at].to_vec();
    bytes.extend_from_slice(&clean[at + chunk_len(&clean, at)..]);
    let rec = read_recording_bytes(&bytes, &path).expect("read");
    assert!(!rec.complete, "{:?}", rec.notes);
    assert_intact_subset(&rec, &points, "cut-out chunk");
    assert_eq!(rec.points.len(), points.len() - 1);
    assert_eq!(rec.missing.len(), 1);
    // The data section's CRC (and the summary, whose offsets no longer fit) say so.
    assert!(
        rec.notes.iter().any(|n| n.contains("data section: CRC")),
        "{:?}",
        rec.notes
    );
    assert!(
        rec.notes.iter().any(|n| n.starts_with("points missing: ")),
        "{:?}",
        rec.notes
    );
}

/// A fixed-seed corpus of damaged files: truncations, flipped bytes and hostile length
/// fields. No input may panic, hang or over-allocate; what is read is exactly what was
/// written; a file that lost anything is never complete. `TMROTOR_MUTANTS=N` runs N
/// mutants instead of 400 (the `fuzz/` target runs longer).
#[test]
fn mutation_corpus_never_panics_and_never_claims_a_damaged_file_complete() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, points) = sample(dir.path(), true);
    let clean = std::fs::read(&path).expect("read");
    let full = read_recording_bytes(&clean, &path).expect("clean");
    let n: usize = std::env::var("TMROTOR_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(400);
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut readable, mut incomplete) = (0, 0);
    for k in 0..n {
        let mut bytes = clean.clone();
        let what = match k % 4 {
            0 => {
                let cut = (next() as usize) % bytes.len();
                bytes.truncate(cut);
                format!("truncated at {cut}")
            }
            1 => {
                let flips = 1 + (next() as usize) % 4;
                for _ in 0..flips {
                    let at = (next() as usize) % bytes.len();
                    bytes[at] ^= 1 << (next() % 8);
                }
                format!("{flips} flipped bits (mutant {k})")
            }
            2 => {
                let at = (next() as usize) % (bytes.len() - 8);
                let hostile = [u64::MAX, 1 << 58, 0x7fff_ffff, u64::from(u32::MAX)];
                let v = hostile[(next() as usize) % hostile.len()];
                bytes[at..at + 8].copy_from_slice(&v.to_le_bytes());
                format!("hostile length {v} at {at}")
            }
            _ => {
                let at = (next() as usize) % (bytes.len() - 4);
                bytes[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
                format!("hostile u32 at {at}")
            }
        };
        match read_recording_bytes(&bytes, &path) {
            Ok(rec) => {
                readable += 1;
                incomplete += usize::from(!rec.complete);
                assert_intact_subset(&rec, &points, &what);
                if rec.complete {
                    assert_eq!(rec.bifurcations, full.bifurcations, "{what}");
                }
            }
            Err(e) => assert!(e.to_string().contains("full.mcap"), "{what}: {e}"),
        }
    }
    assert!(readable > n / 2, "{readable} of {n} mutants readable");
    assert!(incomplete > n / 2, "{incomplete} of {n} mutants incomplete");
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

/// `replay recover` writes every intact point of a damaged file into a clean recording:
/// read back, it has no damage, the same points, bifurcations and warnings, and a note of
/// the lost point; an existing output is refused.
#[test]
fn recover_writes_the_intact_points_into_a_clean_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, _) = sample(dir.path(), true);
    let mut bytes = std::fs::read(&path).expect("read");
    let at = chunk_offsets(&bytes)[5];
    bytes[at + 60] ^= 0x5a;
    let damaged = dir.path().join("damaged.mcap");
    std::fs::write(&damaged, &bytes).expect("write");
    let before = read_recording(&damaged).expect("damaged");
    assert_eq!(before.missing.len(), 1);

    let target = dir.path().join("recovered.mcap");
    let run = |args: &[&str]| {
        let (res, out, _) = common::replay_in_process(args);
        (res, out)
    };
    let args = [
        "recover",
        damaged.to_str().expect("utf-8"),
        target.to_str().expect("utf-8"),
    ];
    let (res, out) = run(&args);
    res.expect("recover");
    assert!(out.contains("points lost: "), "{out}");
    let after = read_recording(&target).expect("recovered");
    assert!(
        after.notes.iter().all(|n| !n.starts_with("damaged")),
        "{:?}",
        after.notes
    );
    assert_eq!(after.points, before.points);
    assert_eq!(after.bifurcations, before.bifurcations);
    assert_eq!(after.missing, before.missing, "the gap stays visible");
    assert_eq!(after.status, Some(RunStatus::Completed));
    assert!(
        after
            .warnings
            .iter()
            .any(|w| w.contains("recovered by replay recover")),
        "{:?}",
        after.warnings
    );
    // An existing output is never overwritten.
    let (res, _) = run(&args);
    let err = res.expect_err("exists");
    assert!(err.to_string().contains("exists"), "{err}");
}
