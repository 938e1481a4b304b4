"""Fixtures: recordings made once per session with the built binaries.

Binaries: ``TMROTOR_BIN`` and ``REPLAY_BIN`` (default ``target/release/tmrotor`` and
``target/release/replay`` of the checkout). Without them the tests are skipped, except
under ``CI=true``, where that is a failure.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
# test the package source of this checkout even when an older copy is installed
sys.path.insert(0, str(HERE.parent / "src"))

TMROTOR_BIN = Path(os.environ.get("TMROTOR_BIN", REPO / "target" / "release" / "tmrotor"))
REPLAY_BIN = Path(os.environ.get("REPLAY_BIN", REPO / "target" / "release" / "replay"))
IN_CI = os.environ.get("CI", "").lower() == "true"


def need(condition: bool, reason: str) -> None:
    """Skips the test when ``condition`` is false, or fails it under ``CI=true``."""
    if not condition:
        if IN_CI:
            pytest.fail(f"{reason} (CI=true: required)")
        pytest.skip(reason)


def run(*args: object, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """Runs a command; fails the test with its output when it does not succeed."""
    cmd = [str(a) for a in args]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    if p.returncode != 0:
        pytest.fail(f"{' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


@pytest.fixture(scope="session")
def tmrotor_bin() -> Path:
    need(os.access(TMROTOR_BIN, os.X_OK), f"tmrotor binary not found at {TMROTOR_BIN}")
    return TMROTOR_BIN


@pytest.fixture(scope="session")
def replay_bin() -> Path:
    need(os.access(REPLAY_BIN, os.X_OK), f"replay binary not found at {REPLAY_BIN}")
    return REPLAY_BIN


@pytest.fixture(scope="session")
def recdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("recordings")


@pytest.fixture(scope="session")
def sweep_rec(tmrotor_bin: Path, recdir: Path) -> Path:
    """The dual rotor, ω 400..460 rad/s, order 2 (~1 s): thermal, stability, 18 nodes."""
    out = recdir / "sweep.mcap"
    run(tmrotor_bin, "sweep", "--omega", "400:460", "--order", "2", "-q", "-o", out)
    return out


@pytest.fixture(scope="session")
def transient_rec(tmrotor_bin: Path, recdir: Path) -> Path:
    """The dual rotor at 400 rad/s from a cold start, 0.3 s (19 revolutions)."""
    out = recdir / "transient.mcap"
    run(tmrotor_bin, "transient", "--speed", "400", "--duration", "0.3", "-q", "-o", out)
    return out


@pytest.fixture(scope="session")
def synthetic_rec(replay_bin: Path, recdir: Path) -> Path:
    """Closed-form 2-DoF rotor: two saddle-nodes, unstable points between them."""
    out = recdir / "synthetic.mcap"
    run(replay_bin, "synthetic", out, "--points", "6")
    return out


@pytest.fixture(scope="session")
def mechanical_rec(replay_bin: Path, recdir: Path) -> Path:
    """Synthetic recording without thermal node and bearing."""
    out = recdir / "mechanical.mcap"
    run(replay_bin, "synthetic", out, "--points", "6", "--mechanical")
    return out


@pytest.fixture(scope="session")
def unfinished_rec(replay_bin: Path, recdir: Path) -> Path:
    """Synthetic recording stopped without finishing, as a killed process leaves it."""
    out = recdir / "unfinished.mcap"
    run(replay_bin, "synthetic", out, "--points", "6", "--unfinished")
    return out


@pytest.fixture(scope="session")
def truncated_rec(sweep_rec: Path, recdir: Path) -> Path:
    """The first 60 % of the bytes of the sweep recording."""
    data = sweep_rec.read_bytes()
    out = recdir / "truncated.mcap"
    out.write_bytes(data[: int(0.6 * len(data))])
    return out


def rewrite_mcap(src: Path, out: Path, keep) -> Path:
    """Copies the recording ``src`` to ``out`` with the official mcap writer, keeping the
    messages for which ``keep(topic, message_bytes_decoded_index_or_None)`` is true;
    schemas, channels of kept topics, attachments and metadata are copied as they are."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer
    from mcap_protobuf.decoder import DecoderFactory

    decoders = DecoderFactory()
    with open(src, "rb") as f, open(out, "wb") as g:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        assert summary is not None
        w = Writer(g, compression=CompressionType.ZSTD)
        w.start(profile=header.profile, library="tmrotor tests (rewritten copy)")
        schema_ids = {
            sid: w.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()
        }
        channel_ids = {}
        for att in reader.iter_attachments():
            w.add_attachment(att.create_time, att.log_time, att.name, att.media_type, att.data)
        for md in reader.iter_metadata():
            w.add_metadata(md.name, md.metadata)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            decode = decoders.decoder_for(channel.message_encoding, schema)
            decoded = decode(message.data) if decode else None
            if not keep(channel.topic, decoded):
                continue
            if channel.id not in channel_ids:
                channel_ids[channel.id] = w.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schema_ids[channel.schema_id],
                    channel.metadata,
                )
            w.add_message(
                channel_ids[channel.id],
                message.log_time,
                message.data,
                message.publish_time,
                message.sequence,
            )
        w.finish()
    return out


@pytest.fixture(scope="session")
def lean_rec(sweep_rec: Path, recdir: Path) -> Path:
    """The sweep recording rewritten without /orbits and /scene (the planned "lean"
    option)."""
    return rewrite_mcap(
        sweep_rec, recdir / "lean.mcap", lambda topic, _m: topic not in ("/orbits", "/scene")
    )


@pytest.fixture(scope="session")
def native_lean_rec(tmrotor_bin: Path, recdir: Path) -> Path:
    """The sweep of `sweep_rec` recorded with `--lean` (no /orbits, /scene), when the
    binary has that option."""
    if "--lean" not in run(tmrotor_bin, "sweep", "--help").stdout:
        pytest.skip(f"{tmrotor_bin} sweep has no --lean option yet")
    out = recdir / "native_lean.mcap"
    run(tmrotor_bin, "sweep", "--omega", "400:460", "--order", "2", "--lean", "-q", "-o", out)
    return out


@pytest.fixture(scope="session")
def rerun_cli() -> str | None:
    """The `rerun` command line of the installed rerun-sdk, if any."""
    cand = Path(sys.executable).parent / "rerun"
    if cand.exists():
        return str(cand)
    return shutil.which("rerun")
