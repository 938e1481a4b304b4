//! The MCAP file sink.
//!
//! # File layout
//! * Profile: none (protobuf has no MCAP profile); every channel has message encoding
//!   `protobuf`, every schema encoding `protobuf`, name = fully qualified message name, data
//!   = `FileDescriptorSet` with imports ([`super::schema`]).
//! * Chunks: zstd-compressed, with message indexes, chunk indexes, statistics and a
//!   summary section when the file is finished.
//! * Self-contained: the model file is an attachment (its file name, media type
//!   `application/toml`), the settings are an attachment `settings.toml` and the metadata
//!   record `tmrotor.settings`; the metadata record `tmrotor.run` holds the tool name and
//!   version, model name and SHA-256 and the creation time; `tmrotor.status` is written by
//!   `finish` (`completed`, `interrupted`, `failed: <reason>`).
//!
//! # Clock
//! Log (and publish) times are not wall-clock times: they count along the branch, so that
//! they increase strictly with the point index whatever the solver's speed. `/run_info` is
//! at 0; point `i` at `(i + 1)` ms; a bifurcation located after point `i` at `(i + 1.5)` ms;
//! the closing `/log` entry 1 ms after the last point. The time axis of a viewer therefore
//! walks the branch; plot against ω with the message path `/summary.omega_rad_s` as x-axis.
//! The wall-clock creation time is in the `tmrotor.run` metadata.
//!
//! # Crash safety
//! After every point (all its topics) and every bifurcation the current chunk is closed and
//! the file flushed to the operating system ([`McapOptions::flush_every`] = 1 point by
//! default), so a killed process loses at most the point being written. The `/summary`
//! message of a point is written last: a reader treats a point without it as cut off. On
//! [`Sink::finish`] (also called from `Drop` with a `failed` status if the owner forgot)
//! the summary section and footer are written.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use mcap::records::MessageHeader;
use mcap::{Attachment, WriteOptions, Writer};
use prost::Message;

use super::RecordError;
use super::convert::{
    AUDIT_LOG_NAME, SceneOptions, bifurcation_record_to_pb, frame_transform_to_pb, log_to_pb,
    named_log_to_pb, point_to_pb, run_info_to_pb, scene_to_pb, sha256_hex,
};
use super::pb::foxglove::log::Level;
use super::schema::{self, Topic, names};
use super::sink::{Sink, SinkChecks};
use super::transient::{Revolution, Samples, TransientInfo, TransientSink, time_ns};
use super::types::{
    BifurcationRecord, BranchRecord, PointRecord, RunInfo, RunStatus, TruncationCheck,
};

/// One millisecond in nanoseconds: the step of the branch clock.
pub const CLOCK_STEP_NS: u64 = 1_000_000;

/// Log time of point `index` (see the module docs).
pub fn point_time_ns(index: u64) -> u64 {
    index.saturating_add(1).saturating_mul(CLOCK_STEP_NS)
}

/// Log time of a bifurcation located after point `after_point`.
pub fn bifurcation_time_ns(after_point: u64) -> u64 {
    point_time_ns(after_point).saturating_add(CLOCK_STEP_NS / 2)
}

/// Options of the MCAP sink.
#[derive(Clone, Debug)]
pub struct McapOptions {
    /// Close the chunk and flush the file after this many points. Default 1: at most the
    /// point being written is lost when the process is killed.
    pub flush_every: u32,
    /// Target uncompressed chunk size, bytes, for chunks that grow between flushes.
    /// Default 1 MiB (the mcap crate's default).
    pub chunk_size: u64,
    /// zstd level; 0 is the library default (3).
    pub compression_level: u32,
    /// Publish `/orbits` (whirl orbits sampled over a period). Default true; replay and the
    /// Python package re-derive them from `/harmonics` when they are left out.
    pub orbits: bool,
    /// Publish `/scene` (`foxglove.SceneUpdate` whirl orbits). Default true.
    pub scene: bool,
    /// Scene scale and frame.
    pub scene_options: SceneOptions,
}

impl Default for McapOptions {
    fn default() -> Self {
        Self {
            flush_every: 1,
            chunk_size: 1 << 20,
            compression_level: 0,
            orbits: true,
            scene: true,
            scene_options: SceneOptions::default(),
        }
    }
}

impl McapOptions {
    /// A lean recording: without `/orbits` and `/scene`, which replay re-derives from
    /// `/harmonics` (about a fifth of the size of a full recording; the 3D view of a viewer
    /// then has nothing to draw).
    pub fn lean() -> Self {
        Self {
            orbits: false,
            scene: false,
            ..Self::default()
        }
    }
}

/// The MCAP writer settings every tmrotor file shares: zstd chunks and the library string
/// naming the tool's version.
pub fn writer_options() -> WriteOptions {
    WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .library(format!(
            "tmrotor/{}; {}",
            env!("CARGO_PKG_VERSION"),
            mcap::LIBRARY_IDENTIFIER
        ))
}

/// The channels of one MCAP file: each topic's schema and channel registered at its first
/// message, its id reused after.
#[derive(Debug, Default)]
pub struct Channels(BTreeMap<&'static str, u16>);

impl Channels {
    /// The channel id of `topic` in `writer`, registering its schema and channel first
    /// if this is its first message.
    pub fn id<W: std::io::Write + std::io::Seek>(
        &mut self,
        writer: &mut Writer<W>,
        topic: Topic,
    ) -> Result<u16, mcap::McapError> {
        if let Some(&id) = self.0.get(topic.name) {
            return Ok(id);
        }
        let schema =
            writer.add_schema(topic.schema.name, "protobuf", topic.schema.descriptor_set)?;
        let id = writer.add_channel(schema, topic.name, "protobuf", &BTreeMap::new())?;
        self.0.insert(topic.name, id);
        Ok(id)
    }
}

/// Writes a run into an MCAP file. See the module docs for the layout, and
/// [`super::output`] for the lock and the temporary name the file is written under.
pub struct McapSink {
    /// The `.partial` file being written.
    path: PathBuf,
    /// Where the recording goes when the run ends.
    target: PathBuf,
    /// The writer lock of `target`, held until the recording is in place.
    lock: Option<super::output::WriterLock>,
    /// A `.partial` of a killed earlier writer, moved aside to this name.
    stale: Option<PathBuf>,
    /// Whether the finished recording replaced `target` (false until then, and when a run
    /// without points left an earlier recording in place).
    committed: bool,
    writer: Option<Writer<BufWriter<File>>>,
    options: McapOptions,
    checks: SinkChecks,
    /// The run, shared so that writing a point does not copy it.
    run: Option<std::sync::Arc<RunInfo>>,
    channels: Channels,
    sequence: u32,
    since_flush: u32,
    last_time_ns: u64,
    /// Notes written with [`Sink::write_note`], counted into the closing status.
    warnings: u32,
    /// Revolutions of a transient run written so far.
    revolutions: u64,
}

impl McapSink {
    /// Starts a recording for `target`: takes its writer lock (another writer of the same
    /// target is [`RecordError::Locked`]), moves a `.partial` of a killed writer aside, and
    /// writes `<target>.partial`, renamed to `target` when the run ends
    /// ([`super::output`]).
    pub fn create(target: impl AsRef<Path>, options: McapOptions) -> Result<Self, RecordError> {
        let target = target.as_ref().to_path_buf();
        let lock = super::output::lock(
            &super::output::lock_path(&target),
            &format!("recording {}", target.display()),
        )?;
        let stale = super::output::keep_stale_partial(&target)?;
        let path = super::output::partial_path(&target);
        let file = File::create(&path).map_err(|source| RecordError::Create {
            path: path.clone(),
            source,
        })?;
        let writer = writer_options()
            .compression_level(options.compression_level)
            .compression_threads(0)
            .chunk_size(Some(options.chunk_size))
            .create(BufWriter::new(file))
            .map_err(|source| RecordError::Mcap {
                path: path.clone(),
                source,
            })?;
        Ok(Self {
            path,
            target,
            lock: Some(lock),
            stale,
            committed: false,
            writer: Some(writer),
            options,
            checks: SinkChecks::default(),
            run: None,
            channels: Channels::default(),
            sequence: 0,
            since_flush: 0,
            warnings: 0,
            last_time_ns: 0,
            revolutions: 0,
        })
    }

    /// The file being written (`<target>.partial` until the run ends).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Stops writing as a killed process would: the `.partial` file keeps what was flushed,
    /// without closing status or summary, and the writer lock is released. For tests of
    /// readers and recovery; returns the `.partial` file.
    pub fn abandon(mut self) -> PathBuf {
        if let Some(w) = self.writer.take() {
            // a dropped writer would finish the file: leak it, as a killed process does
            std::mem::forget(w);
        }
        self.path.clone()
    }

    /// Where the recording goes when the run ends.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// A recording a killed earlier writer left, moved aside to this name when this one
    /// started.
    pub fn stale_partial(&self) -> Option<&Path> {
        self.stale.as_deref()
    }

    /// Whether the finished recording is at [`Self::target`] (false before the end, and
    /// when a run without points left an earlier recording in place).
    pub fn committed(&self) -> bool {
        self.committed
    }

    fn err(&self, source: mcap::McapError) -> RecordError {
        RecordError::Mcap {
            path: self.path.clone(),
            source,
        }
    }

    fn writer(&mut self) -> Result<&mut Writer<BufWriter<File>>, RecordError> {
        self.writer.as_mut().ok_or(RecordError::Finished)
    }

    fn channel(&mut self, topic: Topic) -> Result<u16, RecordError> {
        let Some(w) = self.writer.as_mut() else {
            return Err(RecordError::Finished);
        };
        let added = self.channels.id(w, topic);
        added.map_err(|e| self.err(e))
    }

    fn publish(
        &mut self,
        topic: Topic,
        time_ns: u64,
        msg: &impl Message,
    ) -> Result<(), RecordError> {
        let channel_id = self.channel(topic)?;
        let header = MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: time_ns,
            publish_time: time_ns,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.last_time_ns = self.last_time_ns.max(time_ns);
        let data = msg.encode_to_vec();
        let res = self.writer()?.write_to_known_channel(&header, &data);
        res.map_err(|e| self.err(e))
    }

    fn flush(&mut self) -> Result<(), RecordError> {
        self.since_flush = 0;
        let res = self.writer()?.flush();
        res.map_err(|e| self.err(e))
    }

    fn attach(&mut self, name: &str, media_type: &str, text: &str) -> Result<(), RecordError> {
        let attachment = Attachment {
            log_time: 0,
            create_time: 0,
            name: name.to_string(),
            media_type: media_type.to_string(),
            data: std::borrow::Cow::Borrowed(text.as_bytes()),
        };
        let res = self.writer()?.attach(&attachment);
        res.map_err(|e| self.err(e))
    }

    fn metadata(
        &mut self,
        name: &str,
        entries: BTreeMap<String, String>,
    ) -> Result<(), RecordError> {
        let md = mcap::records::Metadata {
            name: name.to_string(),
            metadata: entries,
        };
        let res = self.writer()?.write_metadata(&md);
        res.map_err(|e| self.err(e))
    }

    fn close(&mut self, status: &RunStatus) -> Result<(), RecordError> {
        let time_ns = self.last_time_ns.saturating_add(CLOCK_STEP_NS);
        let level = match status {
            RunStatus::Completed => Level::Info,
            RunStatus::Interrupted => Level::Warning,
            RunStatus::Failed(_) => Level::Error,
        };
        let points = match (self.checks.last_index(), self.revolutions) {
            (Some(i), _) => format!("last point {i}"),
            (None, 0) => "no points".to_string(),
            (None, 1) => "1 revolution".to_string(),
            (None, r) => format!("{r} revolutions"),
        };
        let warned = match self.warnings {
            0 => String::new(),
            1 => ", 1 warning".to_string(),
            n => format!(", {n} warnings"),
        };
        let text = format!("run {} ({points}{warned})", status.label());
        let logged = self.publish(
            schema::TOPIC_LOG,
            time_ns,
            &log_to_pb(time_ns, level, &text),
        );
        let status_md = self.metadata(
            names::METADATA_STATUS,
            BTreeMap::from([
                ("status".to_string(), status.label()),
                ("warnings".to_string(), self.warnings.to_string()),
            ]),
        );
        let mut writer = self.writer.take().ok_or(RecordError::Finished)?;
        let finished = writer.finish().map_err(|e| self.err(e));
        let mut inner = writer.into_inner();
        let flushed = inner
            .flush()
            .and_then(|()| inner.get_ref().sync_all())
            .map_err(|source| RecordError::Mcap {
                path: self.path.clone(),
                source: source.into(),
            });
        drop(inner);
        let written = logged.and(status_md).and(finished.map(|_| ())).and(flushed);
        // into place (or, without points over an earlier recording, away), then unlock
        let has_points = self.checks.last_index().is_some() || self.revolutions > 0;
        let committed = super::output::commit(&self.target, has_points);
        self.lock = None;
        self.committed = *committed.as_ref().unwrap_or(&false);
        written.and(committed.map(|_| ()))
    }
}

impl McapSink {
    /// The start every recording shares: the run checked and kept, the model and settings
    /// attached, the run and settings metadata (with the recording's `clock`).
    fn start(&mut self, run: &RunInfo, clock: &str) -> Result<(), RecordError> {
        self.checks.begin(run)?;
        self.run = Some(std::sync::Arc::new(run.clone()));
        let model_name = if run.model_name.is_empty() {
            "model.toml".to_string()
        } else {
            run.model_name.clone()
        };
        self.attach(&model_name, names::MODEL_MEDIA_TYPE, &run.model_text)?;
        self.attach(
            names::SETTINGS_ATTACHMENT,
            names::MODEL_MEDIA_TYPE,
            &run.settings_toml,
        )?;
        let created = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0);
        self.metadata(
            names::METADATA_RUN,
            BTreeMap::from([
                ("tool_name".to_string(), run.tool_name.clone()),
                ("tool_version".to_string(), run.tool_version.clone()),
                ("model_name".to_string(), model_name),
                ("model_sha256".to_string(), sha256_hex(&run.model_text)),
                ("created_unix_s".to_string(), created.to_string()),
                ("clock".to_string(), clock.to_string()),
            ]),
        )?;
        self.metadata(
            names::METADATA_SETTINGS,
            run.settings.iter().cloned().collect(),
        )?;
        Ok(())
    }
}

impl Sink for McapSink {
    fn begin_run(&mut self, run: &RunInfo) -> Result<(), RecordError> {
        self.start(run, "branch clock: point i at (i+1) ms")?;
        self.publish(schema::TOPIC_RUN_INFO, 0, &run_info_to_pb(run))?;
        if self.options.scene {
            let frame = frame_transform_to_pb(&self.options.scene_options.frame_id);
            self.publish(schema::TOPIC_TF, 0, &frame)?;
        }
        let text = format!(
            "run started: {} {}, model {}, {} nodes, {} thermal nodes, {} bearings",
            run.tool_name,
            run.tool_version,
            run.model_name,
            run.nodes.len(),
            run.thermal_nodes.len(),
            run.bearings.len()
        );
        self.publish(schema::TOPIC_LOG, 0, &log_to_pb(0, Level::Info, &text))?;
        self.flush()
    }

    fn write_point(&mut self, point: &PointRecord) -> Result<(), RecordError> {
        self.checks.point(point)?;
        let run = self
            .run
            .clone()
            .ok_or(RecordError::NotStarted("write_point"))?;
        let t = point_time_ns(point.index);
        let m = point_to_pb(&run, point);
        self.publish(schema::TOPIC_HARMONICS, t, &m.harmonics)?;
        if self.options.orbits {
            self.publish(schema::TOPIC_ORBITS, t, &m.orbits)?;
        }
        if let Some(msg) = &m.temperatures {
            self.publish(schema::TOPIC_TEMPERATURES, t, msg)?;
        }
        if let Some(msg) = &m.clearances {
            self.publish(schema::TOPIC_CLEARANCE, t, msg)?;
        }
        if let Some(msg) = &m.bearing_loads {
            self.publish(schema::TOPIC_BEARING_LOADS, t, msg)?;
        }
        if let Some(msg) = &m.thermal_forces {
            self.publish(schema::TOPIC_THERMAL_FORCES, t, msg)?;
        }
        if let Some(msg) = &m.floquet {
            self.publish(schema::TOPIC_FLOQUET, t, msg)?;
        }
        if self.options.scene {
            let scene = scene_to_pb(&run, point, t, &self.options.scene_options);
            self.publish(schema::TOPIC_SCENE, t, &scene)?;
        }
        // Last: its presence marks the point as completely written.
        self.publish(schema::TOPIC_SUMMARY, t, &m.summary)?;
        self.since_flush += 1;
        if self.since_flush >= self.options.flush_every.max(1) {
            self.flush()?;
        }
        Ok(())
    }

    fn write_bifurcation(&mut self, b: &BifurcationRecord) -> Result<(), RecordError> {
        self.checks.bifurcation(b)?;
        let t = bifurcation_time_ns(b.after_point);
        self.publish(schema::TOPIC_BIFURCATIONS, t, &bifurcation_record_to_pb(b))?;
        let text = format!(
            "{} bifurcation #{} at ω = {:.4} rad/s (between points {} and {})",
            b.kind.label(),
            u64::from(b.number) + 1,
            b.omega_rad_s,
            b.after_point,
            b.after_point.saturating_add(1)
        );
        self.publish(schema::TOPIC_LOG, t, &log_to_pb(t, Level::Warning, &text))?;
        self.flush()
    }

    fn write_branch(&mut self, b: &BranchRecord) -> Result<(), RecordError> {
        self.checks.branch(b)?;
        let t = bifurcation_time_ns(self.checks.last_index().unwrap_or(0));
        self.publish(
            schema::TOPIC_BRANCHES,
            t,
            &super::convert::branch_record_to_pb(b),
        )?;
        let text = format!(
            "branch {}: {} from bifurcation #{} of branch {} at ω = {:.4} rad/s",
            b.branch,
            b.kind,
            u64::from(b.origin_bifurcation) + 1,
            b.parent,
            b.origin_omega_rad_s
        );
        self.publish(schema::TOPIC_LOG, t, &log_to_pb(t, Level::Info, &text))?;
        self.flush()
    }

    fn finish(&mut self, status: RunStatus) -> Result<(), RecordError> {
        self.checks.finish()?;
        self.close(&status)
    }

    fn write_note(&mut self, after_point: u64, text: &str) -> Result<(), RecordError> {
        let t = bifurcation_time_ns(after_point);
        let log = named_log_to_pb(t, Level::Warning, text, AUDIT_LOG_NAME);
        self.publish(schema::TOPIC_LOG, t, &log)?;
        self.warnings += 1;
        self.flush()
    }

    fn write_truncation_check(&mut self, c: &TruncationCheck) -> Result<(), RecordError> {
        self.checks.truncation_check()?;
        let t = bifurcation_time_ns(c.after_point);
        self.publish(
            schema::TOPIC_TRUNCATION,
            t,
            &super::convert::truncation_check_to_pb(c),
        )?;
        let text = format!(
            "{} at ω = {:.4} rad/s (between points {} and {}), at higher truncation orders: {}",
            c.what(),
            c.omega_rad_s,
            c.after_point,
            c.after_point.saturating_add(1),
            c.verdict_text()
        );
        let level = if c.verdict().vanished() {
            Level::Warning
        } else {
            Level::Info
        };
        self.publish(schema::TOPIC_LOG, t, &log_to_pb(t, level, &text))?;
        self.flush()
    }
}

impl TransientSink for McapSink {
    fn begin_transient(&mut self, run: &RunInfo, info: &TransientInfo) -> Result<(), RecordError> {
        self.start(run, "simulated time")?;
        self.publish(schema::TOPIC_RUN_INFO, 0, &run_info_to_pb(run))?;
        self.publish(schema::TOPIC_TRANSIENT_INFO, 0, info)?;
        let text = format!(
            "transient started: {} {}, model {}; {}; start: {}",
            run.tool_name, run.tool_version, run.model_name, info.profile, info.start
        );
        self.publish(schema::TOPIC_LOG, 0, &log_to_pb(0, Level::Info, &text))?;
        self.flush()
    }

    fn write_samples(&mut self, samples: &Samples) -> Result<(), RecordError> {
        if self.run.is_none() {
            return Err(RecordError::NotStarted("write_samples"));
        }
        self.publish(schema::TOPIC_SAMPLES, time_ns(samples.time_s), samples)
    }

    /// Each revolution closes the chunk and flushes the file: a killed run keeps every
    /// revolution written.
    fn write_revolution(&mut self, revolution: &Revolution) -> Result<(), RecordError> {
        if self.run.is_none() {
            return Err(RecordError::NotStarted("write_revolution"));
        }
        let t = time_ns(revolution.time_s);
        self.publish(schema::TOPIC_REVOLUTIONS, t, revolution)?;
        self.revolutions += 1;
        self.flush()
    }

    fn finish_transient(&mut self, status: RunStatus) -> Result<(), RecordError> {
        self.checks.finish()?;
        self.close(&status)
    }
}

impl Drop for McapSink {
    fn drop(&mut self) {
        if self.writer.is_some() && !self.checks.is_finished() {
            let status = if std::thread::panicking() {
                RunStatus::Failed("the writing thread panicked".into())
            } else {
                RunStatus::Failed("the recording was dropped without finish".into())
            };
            let _ = self.checks.finish();
            let _ = self.close(&status);
        }
    }
}
