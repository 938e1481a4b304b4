//! Reads a recording back into domain types.
//!
//! The file is scanned front to back (not through the summary section), so a file cut
//! short — a killed process, a full disk — yields every point that was completely written;
//! [`Recording::complete`] is then false and [`Recording::notes`] says what was missing.
//! A file that is not MCAP, is damaged (bad CRC, undecodable chunk or message), or is an
//! MCAP file from another program gets a [`ReadError`] naming the file and the reason.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mcap::read::{ChunkFlattener, Options};
use mcap::records::Record;
use prost::Message;
use thiserror::Error;

use super::convert::{PointParts, bifurcation_record_from_pb, point_from_pb, run_info_from_pb};
use super::pb::tmrotor::v1 as pb;
use super::schema::{self, names};
use super::types::{BifurcationRecord, PointRecord, RunInfo, RunStatus};

/// Errors reading a recording. Every variant names the file.
#[derive(Debug, Error)]
pub enum ReadError {
    #[error("cannot read {file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file} is not an MCAP file: {reason}")]
    NotMcap { file: PathBuf, reason: String },
    #[error("{file} is damaged: {reason}")]
    Corrupt { file: PathBuf, reason: String },
    #[error("{file} is not a tmrotor recording: {reason}")]
    Foreign { file: PathBuf, reason: String },
}

/// Messages per topic found in a recording.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicCount {
    pub topic: String,
    pub schema: String,
    pub messages: u64,
}

/// A recording read back.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The file it came from.
    pub file: PathBuf,
    pub run: RunInfo,
    /// Completely written points, in index order.
    pub points: Vec<PointRecord>,
    pub bifurcations: Vec<BifurcationRecord>,
    /// Status written by `finish`; `None` when the file was cut before it.
    pub status: Option<RunStatus>,
    /// True when the file ends properly (data end, footer, end magic) and has a status.
    pub complete: bool,
    /// What was missing or skipped, for the user.
    pub notes: Vec<String>,
    /// The sweep's warnings about the branch (`/log` entries written by
    /// [`super::Sink::write_note`]), in order.
    pub warnings: Vec<String>,
    /// Message counts per topic (from the scan, not from the summary).
    pub topics: Vec<TopicCount>,
    /// MCAP metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Names of the attachments.
    pub attachments: Vec<String>,
}

impl Recording {
    /// ω range `(min, max)` of the points, rad/s.
    pub fn omega_range(&self) -> Option<(f64, f64)> {
        let mut it = self.points.iter().map(|p| p.omega_rad_s);
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), w| (lo.min(w), hi.max(w))))
    }

    /// The point with index `index`.
    pub fn point(&self, index: u64) -> Option<&PointRecord> {
        self.points.iter().find(|p| p.index == index)
    }
}

/// Reads the recording at `path`.
///
/// Only regular files are read: a directory, a device (`/dev/zero`) or a FIFO is refused at
/// once, before anything is read (such inputs would otherwise block or grow without end).
pub fn read_recording(path: impl AsRef<Path>) -> Result<Recording, ReadError> {
    let path = path.as_ref();
    let meta = std::fs::metadata(path).map_err(|source| ReadError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, FIFO or socket)"
        };
        return Err(ReadError::NotMcap {
            file: path.to_path_buf(),
            reason: format!("it is {what}; a recording is a regular .mcap file"),
        });
    }
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    read_recording_bytes(&bytes, path)
}

#[derive(Default)]
struct Channel {
    topic: String,
    schema: String,
    encoding: String,
    count: u64,
}

/// Reads a recording held in memory; `file` is only used in messages.
pub fn read_recording_bytes(bytes: &[u8], file: &Path) -> Result<Recording, ReadError> {
    let file_buf = file.to_path_buf();
    let not_mcap = |reason: String| ReadError::NotMcap {
        file: file_buf.clone(),
        reason,
    };
    let corrupt = |reason: String| ReadError::Corrupt {
        file: file_buf.clone(),
        reason,
    };
    let foreign = |reason: String| ReadError::Foreign {
        file: file_buf.clone(),
        reason,
    };
    if bytes.len() < mcap::MAGIC.len() || !bytes.starts_with(mcap::MAGIC) {
        return Err(not_mcap(format!(
            "it does not start with the MCAP magic bytes ({} bytes long)",
            bytes.len()
        )));
    }

    let reader = ChunkFlattener::new_with_options(
        bytes,
        Options::IgnoreEndMagic | Options::ValidateChunkCrcs,
    )
    .map_err(|e| corrupt(e.to_string()))?;

    let mut schemas: BTreeMap<u16, (String, String)> = BTreeMap::new();
    let mut channels: BTreeMap<u16, Channel> = BTreeMap::new();
    let mut metadata = BTreeMap::new();
    let mut attachments: Vec<(String, Vec<u8>)> = Vec::new();
    let mut run_msg: Option<pb::RunInfo> = None;
    let mut parts: BTreeMap<u64, PointParts> = BTreeMap::new();
    let mut bif_msgs: Vec<pb::Bifurcation> = Vec::new();
    let mut warnings: Vec<String> = Vec::new();
    let mut notes = Vec::new();
    let (mut saw_data_end, mut saw_footer, mut cut_short) = (false, false, false);

    for record in reader {
        let record = match record {
            Ok(r) => r,
            Err(mcap::McapError::UnexpectedEof) => {
                cut_short = true;
                break;
            }
            Err(e) => {
                return Err(corrupt(match e {
                    mcap::McapError::BadChunkCrc { .. } => format!("{e} (a chunk was altered)"),
                    other => other.to_string(),
                }));
            }
        };
        match record {
            Record::Schema { header, .. } => {
                schemas.insert(header.id, (header.name.clone(), header.encoding.clone()));
            }
            Record::Channel(c) => {
                let (schema, _) = schemas.get(&c.schema_id).cloned().unwrap_or_default();
                channels.entry(c.id).or_insert(Channel {
                    topic: c.topic.clone(),
                    schema,
                    encoding: c.message_encoding.clone(),
                    count: 0,
                });
            }
            Record::Message { header, data } => {
                let Some(ch) = channels.get_mut(&header.channel_id) else {
                    return Err(corrupt(format!(
                        "message {} refers to unknown channel {}",
                        header.sequence, header.channel_id
                    )));
                };
                ch.count += 1;
                if ch.encoding != "protobuf" {
                    continue;
                }
                let topic = ch.topic.clone();
                decode_message(
                    &topic,
                    &data,
                    &mut run_msg,
                    &mut parts,
                    &mut bif_msgs,
                    &mut warnings,
                )
                .map_err(|reason| corrupt(format!("{topic}: {reason}")))?;
            }
            Record::Attachment { header, data, .. } => {
                attachments.push((header.name.clone(), data.into_owned()));
            }
            Record::Metadata(m) => {
                metadata.insert(m.name.clone(), m.metadata.clone());
            }
            Record::DataEnd(_) => saw_data_end = true,
            Record::Footer(_) => saw_footer = true,
            _ => {}
        }
    }

    let run_msg = run_msg.ok_or_else(|| {
        let topics: Vec<String> = channels.values().map(|c| c.topic.clone()).collect();
        foreign(if topics.is_empty() {
            "it holds no channels (no /run_info message)".to_string()
        } else {
            format!(
                "no /run_info message of schema {} (topics found: {})",
                schema::RUN_INFO.name,
                topics.join(", ")
            )
        })
    })?;
    let model_text = match attachments.iter().find(|(n, _)| *n == run_msg.model_name) {
        Some((_, data)) => String::from_utf8_lossy(data).into_owned(),
        None => {
            notes.push(format!(
                "the model file attachment {:?} is missing",
                run_msg.model_name
            ));
            String::new()
        }
    };
    let run = run_info_from_pb(&run_msg, model_text)
        .map_err(|reason| corrupt(format!("/run_info: {reason}")))?;

    let mut points = Vec::with_capacity(parts.len());
    for (index, p) in &parts {
        match point_from_pb(&run, p) {
            Ok(point) => points.push(point),
            Err(reason) if p.summary.is_none() => {
                notes.push(format!("point {index} skipped: {reason}"));
            }
            Err(reason) => return Err(corrupt(format!("point {index}: {reason}"))),
        }
    }
    let bifurcations = bif_msgs
        .iter()
        .map(bifurcation_record_from_pb)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|reason| corrupt(format!("/bifurcations: {reason}")))?;

    let status = metadata
        .get(names::METADATA_STATUS)
        .and_then(|m| m.get("status"))
        .map(|s| RunStatus::from_label(s));
    if cut_short {
        notes.push("the file ends in the middle of a record (cut short)".into());
    }
    let end_magic = bytes.len() >= 2 * mcap::MAGIC.len() && bytes.ends_with(mcap::MAGIC);
    if !end_magic {
        notes.push("the file does not end with the MCAP magic bytes".into());
    }
    if !saw_data_end || !saw_footer {
        notes.push("the file has no summary/footer: it was not finished".into());
    }
    if status.is_none() {
        notes.push("no run status: the run did not finish writing".into());
    }
    let complete = !cut_short && end_magic && saw_data_end && saw_footer && status.is_some();

    Ok(Recording {
        file: file.to_path_buf(),
        run,
        points,
        bifurcations,
        status,
        complete,
        notes,
        warnings,
        topics: channels
            .into_values()
            .map(|c| TopicCount {
                topic: c.topic,
                schema: c.schema,
                messages: c.count,
            })
            .collect(),
        metadata,
        attachments: attachments.into_iter().map(|(n, _)| n).collect(),
    })
}

fn decode<M: Message + Default>(data: &[u8]) -> Result<M, String> {
    M::decode(data).map_err(|e| format!("protobuf decoding failed: {e}"))
}

fn decode_message(
    topic: &str,
    data: &[u8],
    run: &mut Option<pb::RunInfo>,
    parts: &mut BTreeMap<u64, PointParts>,
    bifs: &mut Vec<pb::Bifurcation>,
    warnings: &mut Vec<String>,
) -> Result<(), String> {
    match topic {
        t if t == schema::TOPIC_RUN_INFO.name => {
            if run.is_some() {
                return Err("more than one run in one file".into());
            }
            *run = Some(decode(data)?);
        }
        t if t == schema::TOPIC_SUMMARY.name => {
            let m: pb::PointSummary = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().summary = Some(m);
        }
        t if t == schema::TOPIC_HARMONICS.name => {
            let m: pb::Harmonics = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().harmonics = Some(m);
        }
        t if t == schema::TOPIC_ORBITS.name => {
            let m: pb::Orbits = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().orbits = Some(m);
        }
        t if t == schema::TOPIC_TEMPERATURES.name => {
            let m: pb::Temperatures = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().temperatures = Some(m);
        }
        t if t == schema::TOPIC_CLEARANCE.name => {
            let m: pb::Clearances = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().clearances = Some(m);
        }
        t if t == schema::TOPIC_BEARING_LOADS.name => {
            let m: pb::BearingLoads = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().bearing_loads = Some(m);
        }
        t if t == schema::TOPIC_THERMAL_FORCES.name => {
            let m: pb::ThermalForces = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().thermal_forces = Some(m);
        }
        t if t == schema::TOPIC_FLOQUET.name => {
            let m: pb::Floquet = decode(data)?;
            let index = m.index;
            parts.entry(index).or_default().floquet = Some(m);
        }
        t if t == schema::TOPIC_BIFURCATIONS.name => bifs.push(decode(data)?),
        t if t == schema::TOPIC_LOG.name => {
            let m: super::pb::foxglove::Log = decode(data)?;
            if m.name == super::convert::AUDIT_LOG_NAME {
                warnings.push(m.message);
            }
        }
        _ => {} // /scene and unknown topics are not needed to rebuild the run
    }
    Ok(())
}
