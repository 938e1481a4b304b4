//! Reads a recording back into domain types.
//!
//! The file is streamed front to back by [`super::scan`] (not through the summary
//! section), with memory bounded by its largest record: a file cut short — a killed
//! process, a full disk — yields every point that was completely written, and a damaged
//! file every point whose chunk is intact (one point per chunk). [`Recording::complete`]
//! is then false, [`Recording::missing`] names the lost point indices and
//! [`Recording::notes`] says what was wrong, including counts of the summary section that
//! disagree with what was read. A file that is not MCAP, has no readable run description,
//! or is an MCAP file from another program gets a [`ReadError`] naming the file and the
//! reason.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use prost::Message;
use thiserror::Error;

use super::convert::{
    PointParts, Presence, bifurcation_record_from_pb, branch_record_from_pb, point_from_pb,
    run_info_from_pb,
};
use super::pb::tmrotor::v1 as pb;
use super::scan;
use super::schema::{self, names};
use super::transient::{Revolution, Samples, TransientInfo};
use super::types::{
    BifurcationRecord, BranchRecord, PointRecord, RunInfo, RunStatus, TruncationCheck,
};

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
    /// Branches beside the run's own (`/branches`), in order: branch `k` at `k − 1`.
    pub branches: Vec<BranchRecord>,
    /// Status written by `finish`; `None` when the file was cut before it.
    pub status: Option<RunStatus>,
    /// True when the file ends properly (data end, footer, end magic), has a status, and
    /// nothing in it was damaged, missing or disagreed with its summary's counts.
    pub complete: bool,
    /// Indices of points lost before the last one read (in damaged or missing chunks).
    pub missing: Vec<u64>,
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
    /// The records of a transient run (`tmrotor transient`); `None` for a sweep.
    pub transient: Option<TransientRecords>,
    /// The run's events re-solved at higher truncation orders (`/truncation`), in order;
    /// empty when the sweep did not check them (recordings of earlier versions, checks
    /// turned off, nothing located).
    pub truncation: Vec<TruncationCheck>,
}

/// The records of a transient run read back, in time order.
#[derive(Clone, Debug, Default)]
pub struct TransientRecords {
    pub info: Option<TransientInfo>,
    pub revolutions: Vec<Revolution>,
    pub samples: Vec<Samples>,
    /// Revolution numbers lost before the last one read (damaged chunks).
    pub missing: Vec<u64>,
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

    /// The run as the points of `branch` see it (its basis); `None` for a branch the
    /// recording does not describe.
    pub fn run_of(&self, branch: u32) -> Option<std::borrow::Cow<'_, RunInfo>> {
        match branch {
            0 => Some(std::borrow::Cow::Borrowed(&self.run)),
            k => self
                .branches
                .iter()
                .find(|b| b.branch == k)
                .map(|b| std::borrow::Cow::Owned(b.run_of(&self.run))),
        }
    }

    /// The truncation check of located bifurcation `b` of the run's branch
    /// (`/truncation`), if the sweep made one.
    pub fn truncation_of(&self, b: &BifurcationRecord) -> Option<&TruncationCheck> {
        if b.branch != 0 {
            return None;
        }
        self.truncation
            .iter()
            .find(|c| c.kind == Some(b.kind) && c.number == b.number)
    }

    /// Whether located bifurcation `b` vanished at a higher truncation order: an artefact
    /// of the truncation, not a result of the model.
    pub fn vanished(&self, b: &BifurcationRecord) -> bool {
        self.truncation_of(b)
            .is_some_and(|c| c.verdict().vanished())
    }

    /// The recording with the run's own branch only (branch 0): the points and located
    /// bifurcations of switched branches left out, and the bifurcations that vanished at a
    /// higher truncation order ([`Self::vanished`]). The campaign's figures, maps and the
    /// reproduction report read runs this way: their statements are about the results on
    /// the branch the sweep followed in ω.
    pub fn own_branch(mut self) -> Self {
        self.points.retain(|p| p.branch == 0);
        let bifurcations = std::mem::take(&mut self.bifurcations);
        self.bifurcations = bifurcations
            .into_iter()
            .filter(|b| b.branch == 0 && !self.vanished(b))
            .collect();
        self.branches.clear();
        self
    }

    /// The branch numbers of the recording: 0, then those of [`Self::branches`].
    pub fn branch_numbers(&self) -> Vec<u32> {
        std::iter::once(0)
            .chain(self.branches.iter().map(|b| b.branch))
            .collect()
    }
}

/// What to keep of a recording in memory.
#[derive(Clone, Copy, Debug)]
pub struct ReadOptions {
    /// Keep the stored `/orbits` samples (default true). Without them a point's `orbits`
    /// are empty (as from a lean recording) and `derive::orbits` re-derives them:
    /// replay reads this way, which keeps its memory well below the file's size.
    pub orbits: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self { orbits: true }
    }
}

/// Reads the recording at `path`, keeping everything ([`read_recording_with`]).
pub fn read_recording(path: impl AsRef<Path>) -> Result<Recording, ReadError> {
    read_recording_with(path, ReadOptions::default())
}

/// Reads the recording at `path`.
///
/// Only regular files are read: a directory, a device (`/dev/zero`) or a FIFO is refused at
/// once, before anything is read (such inputs would otherwise block or grow without end).
pub fn read_recording_with(
    path: impl AsRef<Path>,
    options: ReadOptions,
) -> Result<Recording, ReadError> {
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
    let file = std::fs::File::open(path).map_err(|source| ReadError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    read_from(std::io::BufReader::new(file), meta.len(), path, options)
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
    read_from(
        std::io::Cursor::new(bytes),
        bytes.len() as u64,
        file,
        ReadOptions::default(),
    )
}

/// What the scan collects before the run is rebuilt.
#[derive(Default)]
struct Collected {
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, Channel>,
    /// Messages of channels not (yet) defined: their definition may come later (the
    /// summary section repeats every channel) when the chunk that held it is damaged.
    pending: Vec<(u16, Vec<u8>)>,
    metadata: BTreeMap<String, BTreeMap<String, String>>,
    attachments: Vec<(String, Vec<u8>)>,
    run: Option<pb::RunInfo>,
    parts: BTreeMap<u64, PointParts>,
    bifs: Vec<pb::Bifurcation>,
    branches: Vec<pb::BranchInfo>,
    truncation: Vec<pb::TruncationCheck>,
    warnings: Vec<String>,
    /// Messages that did not decode: topic and reason.
    undecodable: Vec<String>,
    statistics: Option<(u32, BTreeMap<u16, u64>)>,
    saw_data_end: bool,
    saw_footer: bool,
    /// Count `/orbits` messages without decoding them ([`ReadOptions::orbits`]).
    skip_orbits: bool,
    /// The run description as soon as it is read (without the model text), so that each
    /// point is built when its `/summary` arrives and its messages are freed: memory then
    /// holds the points, not every message of the file.
    run_early: Option<RunInfo>,
    /// Transient records (`/transient/*`), when the file has any.
    transient: Option<TransientRecords>,
    /// Points built as their `/summary` arrived, with which optional messages they had.
    built: BTreeMap<u64, (PointRecord, Presence)>,
}

impl Collected {
    fn message(&mut self, channel_id: u16, data: &[u8]) {
        let Some(ch) = self.channels.get_mut(&channel_id) else {
            self.pending.push((channel_id, data.to_vec()));
            return;
        };
        ch.count += 1;
        if ch.encoding != "protobuf" || (self.skip_orbits && ch.topic == schema::TOPIC_ORBITS.name)
        {
            return;
        }
        let topic = ch.topic.clone();
        if topic.starts_with("/transient/") {
            if let Err(reason) = self.transient_message(&topic, data) {
                self.undecodable.push(format!("{topic}: {reason}"));
            }
            return;
        }
        if topic == schema::TOPIC_TRUNCATION.name {
            match decode(data) {
                Ok(m) => self.truncation.push(m),
                Err(reason) => self.undecodable.push(format!("{topic}: {reason}")),
            }
            return;
        }
        match decode_message(
            &topic,
            data,
            &mut self.run,
            &mut self.parts,
            &mut self.bifs,
            &mut self.branches,
            &mut self.warnings,
        ) {
            Ok(Some(summary_of)) => self.build(summary_of),
            Ok(None) => {}
            Err(reason) => self.undecodable.push(format!("{topic}: {reason}")),
        }
    }

    /// Keeps one message of a transient run.
    fn transient_message(&mut self, topic: &str, data: &[u8]) -> Result<(), String> {
        let rec = self.transient.get_or_insert_with(TransientRecords::default);
        match topic {
            t if t == schema::TOPIC_TRANSIENT_INFO.name => rec.info = Some(decode(data)?),
            t if t == schema::TOPIC_REVOLUTIONS.name => rec.revolutions.push(decode(data)?),
            t if t == schema::TOPIC_SAMPLES.name => rec.samples.push(decode(data)?),
            _ => {}
        }
        Ok(())
    }

    /// Builds point `index` from its messages (the `/summary` is written last), unless the
    /// run description is not known yet; then it is built at the end.
    fn build(&mut self, index: u64) {
        if self.run_early.is_none() {
            self.run_early = self
                .run
                .as_ref()
                .and_then(|m| run_info_from_pb(m, String::new()).ok());
        }
        let Some(run) = &self.run_early else {
            return;
        };
        let Some(parts) = self.parts.remove(&index) else {
            return;
        };
        let Some(run) = branch_run(run, &self.branches, &parts) else {
            // its branch is not described (yet): said at the end
            self.parts.insert(index, parts);
            return;
        };
        match point_from_pb(&run, &parts) {
            Ok(point) => {
                self.built.insert(index, (point, parts.present()));
            }
            Err(_) => {
                // Said at the end, with the other points that cannot be built.
                self.parts.insert(index, parts);
            }
        }
    }

    fn item(&mut self, item: scan::Item<'_>) {
        match item {
            scan::Item::Schema { id, name, .. } => {
                self.schemas.insert(id, name);
            }
            scan::Item::Channel {
                id,
                schema_id,
                topic,
                encoding,
            } => {
                let schema = self.schemas.get(&schema_id).cloned().unwrap_or_default();
                self.channels.entry(id).or_insert(Channel {
                    topic,
                    schema,
                    encoding,
                    count: 0,
                });
            }
            scan::Item::Message { channel_id, data } => self.message(channel_id, data),
            scan::Item::Attachment { name, data } => self.attachments.push((name, data.to_vec())),
            scan::Item::Metadata { name, map } => {
                self.metadata.insert(name, map);
            }
            scan::Item::Statistics {
                chunk_count,
                channel_message_counts,
            } => self.statistics = Some((chunk_count, channel_message_counts)),
            scan::Item::DataEnd => self.saw_data_end = true,
            scan::Item::Footer => self.saw_footer = true,
        }
    }
}

/// Reads a recording from `r` (`size` bytes): every intact point, past damaged or missing
/// chunks (see [`super::scan`]); what was lost is said in the notes, and such a file is
/// never complete.
fn read_from<R: std::io::Read + std::io::Seek>(
    r: R,
    size: u64,
    file: &Path,
    options: ReadOptions,
) -> Result<Recording, ReadError> {
    let file_buf = file.to_path_buf();
    let corrupt = |reason: String| ReadError::Corrupt {
        file: file_buf.clone(),
        reason,
    };
    let mut c = Collected {
        skip_orbits: !options.orbits,
        ..Collected::default()
    };
    let report = match scan::scan(r, size, |item| {
        c.item(item);
        Ok::<(), std::convert::Infallible>(())
    }) {
        Ok(Ok(report)) => report,
        Ok(Err(never)) => match never {},
        Err(scan::ScanError::NotMcap(reason)) => {
            return Err(ReadError::NotMcap {
                file: file_buf.clone(),
                reason,
            });
        }
        Err(scan::ScanError::Io(source)) => {
            return Err(ReadError::Io {
                file: file_buf.clone(),
                source,
            });
        }
    };
    c.decode_pending();
    let mut notes = Vec::new();
    let damaged = !report.damage.is_empty() || !c.undecodable.is_empty();
    notes.extend(report.damage.iter().map(|d| format!("damaged: {d}")));
    notes.extend(
        c.undecodable
            .iter()
            .map(|d| format!("undecodable message: {d}")),
    );
    let run = c.run_description(file, damaged, &mut notes)?;
    let late = c.drop_late_parts(&mut notes);
    let damaged = damaged || late;
    let (points, lost) = c
        .points(&run, damaged, &mut notes)
        .map_err(|(index, reason)| corrupt(format!("point {index}: {reason}")))?;
    let (branches, bifurcations, truncation) = c.records(&mut notes);
    // Points are numbered 0, 1, … along the branch: a gap is a lost point.
    let present: std::collections::BTreeSet<u64> = points.iter().map(|p| p.index).collect();
    let last = present.iter().next_back().copied();
    let missing: Vec<u64> = match last {
        Some(last) => (0..last).filter(|i| !present.contains(i)).collect(),
        None => Vec::new(),
    };
    if !missing.is_empty() {
        notes.push(format!("points missing: {}", index_ranges(&missing)));
    }
    let transient = c.transient_with_gaps(&mut notes);
    let transient_gap = transient.as_ref().is_some_and(|t| !t.missing.is_empty());
    let count_mismatch = c.counts_disagree(report.chunks as u64, &mut notes);
    let status = c
        .metadata
        .get(names::METADATA_STATUS)
        .and_then(|m| m.get("status"))
        .map(|s| RunStatus::from_label(s));
    if let Some(cut) = &report.cut {
        notes.push(format!(
            "the file ends in the middle of a record (cut short at {cut})"
        ));
    }
    if !report.end_magic {
        notes.push("the file does not end with the MCAP magic bytes".into());
    }
    if !c.saw_data_end || !c.saw_footer {
        notes.push("the file has no summary/footer: it was not finished".into());
    }
    if status.is_none() {
        notes.push("no run status: the run did not finish writing".into());
    }
    let complete = report.cut.is_none()
        && !damaged
        && missing.is_empty()
        && !transient_gap
        && lost.is_empty()
        && !count_mismatch
        && report.end_magic
        && c.saw_data_end
        && c.saw_footer
        && status.is_some();

    Ok(Recording {
        file: file.to_path_buf(),
        run,
        points,
        bifurcations,
        branches,
        status,
        complete,
        missing,
        notes,
        warnings: c.warnings,
        topics: c
            .channels
            .into_values()
            .map(|c| TopicCount {
                topic: c.topic,
                schema: c.schema,
                messages: c.count,
            })
            .collect(),
        metadata: c.metadata,
        attachments: c.attachments.into_iter().map(|(n, _)| n).collect(),
        transient,
        truncation,
    })
}

impl Collected {
    /// Decodes the messages whose channel was defined only later (or in the summary
    /// section); those of a channel no intact record defines are undecodable.
    fn decode_pending(&mut self) {
        for (id, data) in std::mem::take(&mut self.pending) {
            if self.channels.contains_key(&id) {
                self.message(id, &data);
            } else {
                self.undecodable.push(format!(
                    "a message of channel {id}, which no intact record defines"
                ));
            }
        }
    }

    /// The run description (`/run_info` and the model file it names): a file without it
    /// is foreign, or corrupt when damaged.
    fn run_description(
        &mut self,
        file: &Path,
        damaged: bool,
        notes: &mut Vec<String>,
    ) -> Result<RunInfo, ReadError> {
        let corrupt = |reason: String| ReadError::Corrupt {
            file: file.to_path_buf(),
            reason,
        };
        let run_msg = self.run.take().ok_or_else(|| {
            let topics: Vec<String> = self.channels.values().map(|c| c.topic.clone()).collect();
            let what = if topics.is_empty() {
                "it holds no channels (no /run_info message)".to_string()
            } else {
                format!(
                    "no /run_info message of schema {} (topics found: {})",
                    schema::RUN_INFO.name,
                    topics.join(", ")
                )
            };
            if damaged {
                corrupt(format!("{what}; {}", notes.join("; ")))
            } else {
                ReadError::Foreign {
                    file: file.to_path_buf(),
                    reason: what,
                }
            }
        })?;
        let model_text = match self
            .attachments
            .iter()
            .find(|(n, _)| *n == run_msg.model_name)
        {
            Some((_, data)) => String::from_utf8_lossy(data).into_owned(),
            None => {
                notes.push(format!(
                    "the model file attachment {:?} is missing",
                    run_msg.model_name
                ));
                String::new()
            }
        };
        run_info_from_pb(&run_msg, model_text)
            .map_err(|reason| corrupt(format!("/run_info: {reason}")))
    }

    /// Drops the messages of a point that arrive after its /summary (which is written
    /// last): they come from a damaged stretch. Whether there were any.
    fn drop_late_parts(&mut self, notes: &mut Vec<String>) -> bool {
        let late: Vec<u64> = self
            .parts
            .keys()
            .filter(|i| self.built.contains_key(i))
            .copied()
            .collect();
        for index in &late {
            self.parts.remove(index);
            notes.push(format!(
                "damaged: a message of point {index} after its /summary was ignored"
            ));
        }
        !late.is_empty()
    }

    /// The points, built and assembled from their messages (consumed as they are built: the
    /// messages and the points are not held twice), and the indices of those lost. In a
    /// damaged file, a point without a message that other points have lost it (its
    /// channel's definition, or the message itself, was in a damaged stretch). An
    /// unreadable point of an undamaged file is an error (its index and the reason).
    #[allow(clippy::type_complexity)]
    fn points(
        &mut self,
        run: &RunInfo,
        damaged: bool,
        notes: &mut Vec<String>,
    ) -> Result<(Vec<PointRecord>, Vec<u64>), (u64, String)> {
        let mut usual: BTreeMap<&str, usize> = BTreeMap::new();
        if damaged {
            let present = self
                .parts
                .values()
                .filter(|p| p.summary.is_some())
                .map(|p| p.present())
                .chain(self.built.values().map(|(_, present)| *present));
            for flags in present {
                for (topic, has) in flags {
                    *usual.entry(topic).or_default() += usize::from(has);
                }
            }
        }
        let absent_in = |present: &[(&'static str, bool)]| -> Vec<&'static str> {
            present
                .iter()
                .filter(|(topic, has)| !has && usual.get(topic).is_some_and(|&n| n > 0))
                .map(|(topic, _)| *topic)
                .collect()
        };
        let mut points = Vec::with_capacity(self.parts.len() + self.built.len());
        let mut lost = Vec::new();
        for (index, (point, present)) in std::mem::take(&mut self.built) {
            let absent = absent_in(&present);
            if absent.is_empty() {
                points.push(point);
            } else {
                notes.push(format!(
                    "point {index} lost: its {} message is missing",
                    absent.join(", ")
                ));
                lost.push(index);
            }
        }
        for (index, p) in std::mem::take(&mut self.parts) {
            let absent = absent_in(&p.present());
            if p.summary.is_some() && !absent.is_empty() {
                notes.push(format!(
                    "point {index} lost: its {} message is missing",
                    absent.join(", ")
                ));
                lost.push(index);
                continue;
            }
            let point = match branch_run(run, &self.branches, &p) {
                Some(branch) => point_from_pb(&branch, &p),
                None => Err(format!(
                    "its branch {} is not described on /branches",
                    p.summary.as_ref().map_or(0, |s| s.branch)
                )),
            };
            match point {
                Ok(point) => points.push(point),
                Err(reason) if p.summary.is_none() => {
                    notes.push(format!("point {index} skipped: {reason}"));
                }
                Err(reason) if damaged => {
                    notes.push(format!("point {index} lost: {reason}"));
                    lost.push(index);
                }
                Err(reason) => return Err((index, reason)),
            }
        }
        points.sort_by_key(|p| p.index);
        Ok((points, lost))
    }

    /// The branches, bifurcations and truncation checks; an unreadable one is noted and
    /// left out.
    fn records(
        &self,
        notes: &mut Vec<String>,
    ) -> (
        Vec<BranchRecord>,
        Vec<BifurcationRecord>,
        Vec<TruncationCheck>,
    ) {
        let mut branches = Vec::with_capacity(self.branches.len());
        for b in &self.branches {
            match branch_record_from_pb(b) {
                Ok(b) => branches.push(b),
                Err(reason) => notes.push(format!("a /branches message is unreadable: {reason}")),
            }
        }
        let mut bifurcations = Vec::with_capacity(self.bifs.len());
        for b in &self.bifs {
            match bifurcation_record_from_pb(b) {
                Ok(b) => bifurcations.push(b),
                Err(reason) => {
                    notes.push(format!("a /bifurcations message is unreadable: {reason}"))
                }
            }
        }
        let mut truncation = Vec::with_capacity(self.truncation.len());
        for m in &self.truncation {
            match super::convert::truncation_check_from_pb(m) {
                Ok(t) => truncation.push(t),
                Err(reason) => notes.push(format!("a /truncation message is unreadable: {reason}")),
            }
        }
        (branches, bifurcations, truncation)
    }

    /// A transient run's records, with the revolutions missing from them (numbered 1, 2,
    /// …: a gap is a lost revolution).
    fn transient_with_gaps(&mut self, notes: &mut Vec<String>) -> Option<TransientRecords> {
        let mut transient = self.transient.take();
        if let Some(t) = &mut transient {
            let present: std::collections::BTreeSet<u64> =
                t.revolutions.iter().map(|r| r.index).collect();
            let last = present.iter().next_back().copied().unwrap_or(0);
            t.missing = (1..last).filter(|i| !present.contains(i)).collect();
            if !t.missing.is_empty() {
                notes.push(format!("revolutions missing: {}", index_ranges(&t.missing)));
            }
        }
        transient
    }

    /// Whether the summary section's counts disagree with what was read (`read_chunks`
    /// chunks read whole), each disagreement noted.
    fn counts_disagree(&self, read_chunks: u64, notes: &mut Vec<String>) -> bool {
        let mut mismatch = false;
        if let Some((chunk_count, counts)) = &self.statistics {
            if u64::from(*chunk_count) != read_chunks {
                mismatch = true;
                notes.push(format!(
                    "the summary counts {chunk_count} chunks, {read_chunks} were read whole"
                ));
            }
            for (id, want) in counts {
                if let Some(ch) = self.channels.get(id)
                    && ch.count != *want
                {
                    mismatch = true;
                    notes.push(format!(
                        "the summary counts {want} {} messages, {} were read",
                        ch.topic, ch.count
                    ));
                }
            }
        }
        mismatch
    }
}

/// `0–3, 7, 9–10` for `[0, 1, 2, 3, 7, 9, 10]`.
pub fn index_ranges(indices: &[u64]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if j == i {
            indices[i].to_string()
        } else {
            format!("{}–{}", indices[i], indices[j])
        });
        i = j + 1;
    }
    parts.join(", ")
}

/// The run as the point of `parts` sees it: the run's, or its branch's (`None` when the
/// branch is not among `branches` or its harmonics do not read).
fn branch_run<'a>(
    run: &'a RunInfo,
    branches: &[pb::BranchInfo],
    parts: &PointParts,
) -> Option<std::borrow::Cow<'a, RunInfo>> {
    let k = parts
        .summary
        .as_ref()
        .map(|s| s.branch)
        .or_else(|| parts.harmonics.as_ref().map(|h| h.branch))
        .unwrap_or(0);
    if k == 0 {
        return Some(std::borrow::Cow::Borrowed(run));
    }
    let b = branches.iter().find(|b| b.branch == k)?;
    let b = branch_record_from_pb(b).ok()?;
    Some(std::borrow::Cow::Owned(b.run_of(run)))
}

fn decode<M: Message + Default>(data: &[u8]) -> Result<M, String> {
    M::decode(data).map_err(|e| format!("protobuf decoding failed: {e}"))
}

/// Decodes one message into its place; returns the point index when it was a point's
/// `/summary` (the last message of a point).
fn decode_message(
    topic: &str,
    data: &[u8],
    run: &mut Option<pb::RunInfo>,
    parts: &mut BTreeMap<u64, PointParts>,
    bifs: &mut Vec<pb::Bifurcation>,
    branches: &mut Vec<pb::BranchInfo>,
    warnings: &mut Vec<String>,
) -> Result<Option<u64>, String> {
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
            return Ok(Some(index));
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
        t if t == schema::TOPIC_BRANCHES.name => branches.push(decode(data)?),
        t if t == schema::TOPIC_LOG.name => {
            let m: super::pb::foxglove::Log = decode(data)?;
            if m.name == super::convert::AUDIT_LOG_NAME {
                warnings.push(m.message);
            }
        }
        _ => {} // /scene and unknown topics are not needed to rebuild the run
    }
    Ok(None)
}
