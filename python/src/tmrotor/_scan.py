"""Front-to-back scan of a tmrotor MCAP recording (internal).

Mirrors the Rust reader (``src/record/reader.rs``): the file is read from its first byte
with the official ``mcap`` stream reader, not through the summary section, so a file cut
short (a killed process, a file still being written) yields every record that was written
completely. Like the Rust reader, it goes on past damage: the top-level records are walked
here with every length checked against the bytes there; a chunk whose lengths,
decompression or CRC fail is skipped (one point per chunk: a flipped byte costs one point,
not the file), a record whose length runs past the end is a cut or a damaged length (the
walk then resumes at the next chunk or data-end header it finds), and each skip is noted.
The records themselves are parsed by the official ``mcap`` stream reader, and messages are
decoded with ``mcap_protobuf``'s decoder from the schemas embedded in the file.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from mcap.exceptions import EndOfFile, McapError
from mcap.records import (
    Attachment,
    Channel,
    DataEnd,
    Footer,
    Message,
    Metadata,
    Schema,
    Statistics,
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
    #: what was skipped as damaged, in words (the file is then incomplete)
    damaged: list[str] = field(default_factory=list)
    saw_data_end: bool = False
    saw_footer: bool = False
    end_magic: bool = False


_LOG_LEVELS = {0: "UNKNOWN", 1: "DEBUG", 2: "INFO", 3: "WARNING", 4: "ERROR", 5: "FATAL"}


_OP_FOOTER = 0x02
_OP_CHUNK = 0x06
_OP_DATA_END = 0x0F
#: largest record (or decompressed chunk) accepted, as the Rust reader's MAX_RECORD_BYTES
_MAX_RECORD = 512 << 20


def _parse(raw: bytes) -> list[Any]:
    """The records in ``raw`` (whole records, no magic), parsed by the official reader."""
    reader = StreamReader(io.BytesIO(raw), skip_magic=True, record_size_limit=_MAX_RECORD)
    out: list[Any] = []
    it = reader.records
    while True:
        try:
            out.append(next(it))
        except (StopIteration, EndOfFile):
            # the reader reports the end of its buffer as EndOfFile: every whole record is in
            return out


def _chunk_records(body: bytes) -> list[Any]:
    """The records of a chunk's body, after its lengths, decompression and CRC are
    checked; ``ValueError`` naming what failed."""
    if len(body) < 8 + 8 + 8 + 4 + 4:
        raise ValueError("chunk header too short")
    _start, _end, size, crc, name_len = struct.unpack_from("<QQQII", body, 0)
    pos = 32
    if pos + name_len + 8 > len(body):
        raise ValueError("chunk compression name runs past the chunk")
    compression = body[pos : pos + name_len].decode("utf-8", errors="replace")
    pos += name_len
    (records_len,) = struct.unpack_from("<Q", body, pos)
    pos += 8
    if pos + records_len != len(body):
        raise ValueError("chunk records length disagrees with the chunk length")
    if size > _MAX_RECORD or size > 64 * records_len + (1 << 20):
        raise ValueError(f"chunk claims {size} uncompressed bytes")
    compressed = body[pos:]
    if compression == "":
        raw = compressed
    elif compression == "zstd":
        import zstandard

        raw = zstandard.ZstdDecompressor().decompress(compressed, max_output_size=size)
    elif compression == "lz4":
        import lz4.frame

        raw = lz4.frame.decompress(compressed)
    else:
        raise ValueError(f"unknown chunk compression {compression!r}")
    if len(raw) != size:
        raise ValueError(f"chunk decompressed to {len(raw)} bytes, not {size}")
    if crc != 0 and zlib.crc32(raw) != crc:
        raise ValueError("chunk CRC mismatch")
    return _parse(raw)


def _resync(data: bytes, start: int) -> int | None:
    """The offset of the next plausible chunk or data-end record after ``start``: an
    opcode whose length fits the file and, for a chunk, whose header agrees with it."""
    n = len(data)
    pos = start
    while True:
        candidates = [i for i in (data.find(b"\x06", pos), data.find(b"\x0f", pos)) if i >= 0]
        if not candidates:
            return None
        i = min(candidates)
        if i + 9 <= n:
            (length,) = struct.unpack_from("<Q", data, i + 1)
            end = i + 9 + length
            if data[i] == _OP_DATA_END and length == 4 and end <= n:
                return i
            if data[i] == _OP_CHUNK and 36 <= length and end <= n:
                body = data[i + 9 : end]
                name_len = struct.unpack_from("<I", body, 28)[0]
                if 32 + name_len + 8 <= len(body):
                    (rl,) = struct.unpack_from("<Q", body, 32 + name_len)
                    if 32 + name_len + 8 + rl == len(body):
                        return i
        pos = i + 1


def _records(data: bytes, out: Scan) -> Iterator[Any]:
    """Every intact record of the file after its magic, in order; damage and a cut are
    noted on ``out`` (``damaged``, ``cut_short``)."""
    n = len(data)
    pos = len(MAGIC)
    while pos < n:
        if n - pos < 9:
            if not (out.saw_footer and data[pos:] == MAGIC[: n - pos]):
                out.cut_short = not out.saw_footer
            return
        op = data[pos]
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        end = pos + 9 + length
        if length > _MAX_RECORD or end > n:
            nxt = _resync(data, pos + 1)
            if nxt is None:
                if not out.saw_footer:
                    out.cut_short = True
                return
            out.damaged.append(f"bytes {pos}..{nxt}: a record length runs past the end")
            pos = nxt
            continue
        body = data[pos + 9 : end]
        try:
            records = _chunk_records(body) if op == _OP_CHUNK else _parse(data[pos:end])
        except Exception as e:  # damaged chunk or record: skipped, noted
            what = "chunk" if op == _OP_CHUNK else f"record (opcode 0x{op:02x})"
            out.damaged.append(f"{what} at byte {pos} skipped: {e}")
            records = []
        yield from records
        pos = end
        if op == _OP_FOOTER:
            return



def scan(data: bytes, file: str) -> Scan:
    """Scans the bytes of a recording. Raises :class:`RecordingError` for files that are
    not MCAP or hold no ``/run_info`` (damage is skipped and listed in ``damaged``)."""
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

    records = list(_records(data, out))
    # schemas and channels first, from wherever they are intact: a channel is written in
    # the chunk of its first message, and repeated in the summary section, so a damaged
    # first chunk does not take the later messages of its topics with it
    for in_summary in (False, True):
        seen_end = False
        for record in records:
            if isinstance(record, DataEnd):
                seen_end = True
            elif seen_end != in_summary:
                continue
            elif isinstance(record, Schema):
                schemas.setdefault(record.id, record)
            elif isinstance(record, Channel) and record.id not in channels:
                channels[record.id] = record
    for ch in channels.values():
        schema = schemas.get(ch.schema_id)
        out.topics.setdefault(ch.topic, {"schema": schema.name if schema else "", "messages": 0})
    read_per_channel: dict[int, int] = {}
    for record in records:
        if isinstance(record, Message):
            read_per_channel[record.channel_id] = read_per_channel.get(record.channel_id, 0) + 1
        if isinstance(record, Statistics):
            # the summary's counts against what was read: a chunk lost without a trace (cut
            # out cleanly) shows here, as in the Rust reader
            for cid, count in sorted(record.channel_message_counts.items()):
                got = read_per_channel.get(cid, 0)
                ch = channels.get(cid)
                if got < count and ch is not None:
                    out.damaged.append(
                        f"the summary counts {count} {ch.topic} messages, {got} were read"
                    )
    for record in records:
        if isinstance(record, (Schema, Channel, Statistics)):
            continue
        elif isinstance(record, Message):
            ch = channels.get(record.channel_id)
            if ch is None:
                out.damaged.append(
                    f"message {record.sequence} refers to unknown channel {record.channel_id}"
                )
                continue
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
                out.damaged.append(f"{ch.topic}: protobuf decoding failed: {e}")
                continue
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
