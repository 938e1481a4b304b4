"""Front-to-back scan of a tmrotor MCAP recording (internal).

Mirrors the Rust reader (``src/record/reader.rs``): the file is read from its first byte
with the official ``mcap`` stream reader, not through the summary section, so a file cut
short (a killed process, a file still being written) yields every record that was written
completely. Chunk CRCs are checked; a damaged file is an error, a cut one is not.
Messages are decoded with ``mcap_protobuf``'s decoder from the schemas embedded in the file.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mcap.exceptions import EndOfFile, InvalidMagic, McapError
from mcap.records import (
    Attachment,
    Channel,
    DataEnd,
    Footer,
    Message,
    Metadata,
    Schema,
)
from mcap.stream_reader import StreamReader
from mcap_protobuf.decoder import DecoderFactory

MAGIC = b"\x89MCAP0\r\n"

TOPIC_RUN_INFO = "/run_info"
TOPIC_SUMMARY = "/summary"
TOPIC_BIFURCATIONS = "/bifurcations"
TOPIC_BRANCHES = "/branches"
TOPIC_TRUNCATION = "/truncation"
TOPIC_LOG = "/log"
TOPIC_TRANSIENT_INFO = "/transient/info"
TOPIC_REVOLUTIONS = "/transient/revolution"
TOPIC_SAMPLES = "/transient/samples"
TOPIC_SCENE = "/scene"
#: Per-point topics (every message carries ``index``), as in ``schemas/README.md``.
POINT_TOPICS = (
    "/summary",
    "/harmonics",
    "/orbits",
    "/temperatures",
    "/clearance",
    "/bearing_loads",
    "/thermal_forces",
    "/floquet",
)
#: ``name`` of the ``/log`` entries that carry the sweep's warnings about the branch.
AUDIT_LOG_NAME = "tmrotor.audit"
#: MCAP metadata record holding the end status.
METADATA_STATUS = "tmrotor.status"


class RecordingError(ValueError):
    """A file that cannot be read as a tmrotor recording.

    ``kind`` is one of ``"io"``, ``"not_mcap"``, ``"corrupt"`` (bad CRC, undecodable
    chunk or message) or ``"foreign"`` (MCAP, but no ``/run_info``). A file that is merely
    cut short is *not* an error: it is read up to the cut.
    """

    def __init__(self, file: str, kind: str, reason: str):
        self.file = file
        self.kind = kind
        self.reason = reason
        what = {
            "io": "cannot read {f}: {r}",
            "not_mcap": "{f} is not an MCAP file: {r}",
            "corrupt": "{f} is damaged: {r}",
            "foreign": "{f} is not a tmrotor recording: {r}",
        }[kind]
        super().__init__(what.format(f=file, r=reason))


class _StrictBytes:
    """A read-only stream over bytes whose ``read(n)`` raises ``EndOfFile`` when fewer than
    ``n`` bytes are left, so a record cut in the middle is reported as the end of the file
    instead of being parsed from a short buffer."""

    def __init__(self, data: bytes):
        self._data = memoryview(data)
        self._pos = 0

    def read(self, n: int = -1) -> bytes:
        if n is None or n < 0:
            n = len(self._data) - self._pos
        end = self._pos + n
        if end > len(self._data):
            self._pos = len(self._data)
            raise EndOfFile()
        out = self._data[self._pos : end].tobytes()
        self._pos = end
        return out

    @property
    def position(self) -> int:
        return self._pos


@dataclass
class LogEntry:
    """One ``/log`` message: MCAP log time (ns, the branch clock), level name, logger name
    and text."""

    time_ns: int
    level: str
    name: str
    message: str


@dataclass
class Scan:
    run_info: Any = None
    #: point index -> topic -> decoded message
    points: dict[int, dict[str, Any]] = field(default_factory=dict)
    bifurcations: list[Any] = field(default_factory=list)
    #: /truncation messages: the run's events re-solved at higher truncation orders
    truncation: list[Any] = field(default_factory=list)
    #: /branches messages: the branches beside the run's own, in order
    branches: list[Any] = field(default_factory=list)
    log: list[LogEntry] = field(default_factory=list)
    #: a transient run's /transient/info, /transient/revolution and /transient/samples
    transient_info: Any = None
    revolutions: list[Any] = field(default_factory=list)
    samples: list[Any] = field(default_factory=list)
    #: topic -> {"schema": name, "messages": count}, in order of first appearance
    topics: dict[str, dict[str, Any]] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    cut_short: bool = False
    saw_data_end: bool = False
    saw_footer: bool = False
    end_magic: bool = False


_LOG_LEVELS = {0: "UNKNOWN", 1: "DEBUG", 2: "INFO", 3: "WARNING", 4: "ERROR", 5: "FATAL"}


def scan(data: bytes, file: str) -> Scan:
    """Scans the bytes of a recording. Raises :class:`RecordingError` for files that are
    not MCAP, are damaged, or hold no ``/run_info``."""
    if len(data) < len(MAGIC) or not data.startswith(MAGIC):
        raise RecordingError(
            file,
            "not_mcap",
            f"it does not start with the MCAP magic bytes ({len(data)} bytes long)",
        )
    out = Scan()
    out.end_magic = len(data) >= 2 * len(MAGIC) and data.endswith(MAGIC)
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    decoders: dict[int, Callable[[bytes], Any] | None] = {}
    factory = DecoderFactory()

    stream = _StrictBytes(data)
    reader = StreamReader(stream, validate_crcs=True)  # type: ignore[arg-type]
    records = reader.records
    # where the last record read ends: a file that ends exactly there was stopped between
    # two records (no record is cut), one that ends later has a partial record at its end
    end_of_last_record = len(MAGIC)
    while True:
        try:
            record = next(records)
            end_of_last_record = stream.position
        except StopIteration:
            break
        except EndOfFile:
            # after the footer only the end magic is left: its absence is noted below
            if not out.saw_footer and end_of_last_record < len(data):
                out.cut_short = True
            break
        except InvalidMagic as e:
            if out.saw_footer:
                break  # bad end magic: noted below, the records are all there
            raise RecordingError(file, "not_mcap", str(e)) from e
        except (McapError, ValueError) as e:  # CRCValidationError is a ValueError
            raise RecordingError(file, "corrupt", f"{e} (a chunk was altered?)") from e
        except Exception as e:  # undecodable chunk (zstd/lz4 errors), bad record layout
            raise RecordingError(file, "corrupt", f"{type(e).__name__}: {e}") from e

        if isinstance(record, Schema):
            if not out.saw_data_end:
                schemas[record.id] = record
        elif isinstance(record, Channel):
            if not out.saw_data_end and record.id not in channels:
                channels[record.id] = record
                schema = schemas.get(record.schema_id)
                out.topics.setdefault(
                    record.topic,
                    {"schema": schema.name if schema else "", "messages": 0},
                )
        elif isinstance(record, Message):
            ch = channels.get(record.channel_id)
            if ch is None:
                raise RecordingError(
                    file,
                    "corrupt",
                    f"message {record.sequence} refers to unknown channel {record.channel_id}",
                )
            out.topics[ch.topic]["messages"] += 1
            if ch.topic == TOPIC_SCENE or ch.message_encoding != "protobuf":
                continue  # /scene is not needed to rebuild the run
            if ch.id not in decoders:
                try:
                    decoders[ch.id] = factory.decoder_for(
                        ch.message_encoding, schemas.get(ch.schema_id)
                    )
                except McapError as e:
                    raise RecordingError(file, "corrupt", f"{ch.topic}: {e}") from e
            decode = decoders[ch.id]
            if decode is None:
                continue
            try:
                msg = decode(record.data)
            except Exception as e:
                raise RecordingError(
                    file, "corrupt", f"{ch.topic}: protobuf decoding failed: {e}"
                ) from e
            _file_message(out, ch.topic, msg, record.log_time, file)
        elif isinstance(record, Attachment):
            out.attachments[record.name] = bytes(record.data)
        elif isinstance(record, Metadata):
            out.metadata[record.name] = dict(record.metadata)
        elif isinstance(record, DataEnd):
            out.saw_data_end = True
        elif isinstance(record, Footer):
            out.saw_footer = True

    if out.run_info is None:
        topics = ", ".join(out.topics)
        raise RecordingError(
            file,
            "foreign",
            "it holds no channels (no /run_info message)"
            if not topics
            else f"no /run_info message of schema tmrotor.v1.RunInfo (topics found: {topics})",
        )
    return out


def _file_message(out: Scan, topic: str, msg: Any, log_time: int, file: str) -> None:
    if topic == TOPIC_RUN_INFO:
        if out.run_info is not None:
            raise RecordingError(file, "corrupt", "/run_info: more than one run in one file")
        out.run_info = msg
    elif topic in POINT_TOPICS:
        out.points.setdefault(int(msg.index), {})[topic] = msg
    elif topic == TOPIC_BIFURCATIONS:
        out.bifurcations.append(msg)
    elif topic == TOPIC_TRUNCATION:
        out.truncation.append(msg)
    elif topic == TOPIC_TRANSIENT_INFO:
        out.transient_info = msg
    elif topic == TOPIC_REVOLUTIONS:
        out.revolutions.append(msg)
    elif topic == TOPIC_SAMPLES:
        out.samples.append(msg)
    elif topic == TOPIC_BRANCHES:
        out.branches.append(msg)
    elif topic == TOPIC_LOG:
        out.log.append(
            LogEntry(
                time_ns=int(log_time),
                level=_LOG_LEVELS.get(int(msg.level), str(msg.level)),
                name=msg.name,
                message=msg.message,
            )
        )
