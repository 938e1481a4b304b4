#!/usr/bin/env python3
"""Decodes every message of a tmrotor recording with the official MCAP Python reader
(`mcap` + `mcap-protobuf-support` from PyPI) and checks the message count per topic.

usage: check_recording.py FILE TOPIC=COUNT [TOPIC=COUNT ...]

Exit status 0 when every message decodes, the counts match and the decoded values are
plausible; 1 otherwise (the reason on stderr).
"""

import sys
from collections import Counter

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory


def main() -> int:
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    path = sys.argv[1]
    expected = {}
    for arg in sys.argv[2:]:
        topic, count = arg.rsplit("=", 1)
        expected[topic] = int(count)

    counts = Counter()
    problems = []
    omegas = []
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        if summary is None:
            problems.append("no summary section")
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            counts[channel.topic] += 1
            if schema.encoding != "protobuf" or channel.message_encoding != "protobuf":
                problems.append(f"{channel.topic}: encodings {schema.encoding}/{channel.message_encoding}")
            if decoded.DESCRIPTOR.full_name != schema.name:
                problems.append(f"{channel.topic}: decoded {decoded.DESCRIPTOR.full_name}, schema {schema.name}")
            if channel.topic == "/summary":
                omegas.append(decoded.omega_rad_s)
                if len(decoded.amplitude_rms_m) == 0:
                    problems.append(f"/summary index {decoded.index}: no amplitudes")
            if channel.topic == "/scene" and len(decoded.entities) == 0:
                problems.append("/scene: no entities")
        attachments = [a.name for a in reader.iter_attachments()]
        metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}

    for topic, n in expected.items():
        if counts[topic] != n:
            problems.append(f"{topic}: {counts[topic]} messages decoded, expected {n}")
    if not omegas or not all(w > 0 for w in omegas):
        problems.append("no positive omega in /summary")
    if "tmrotor.status" not in metadata:
        problems.append(f"no tmrotor.status metadata (found {sorted(metadata)})")
    if not attachments:
        problems.append("no attachments (model file missing)")

    total = sum(counts.values())
    print(f"{path}: decoded {total} messages on {len(counts)} topics: {dict(sorted(counts.items()))}")
    print(f"attachments: {attachments}; metadata: {sorted(metadata)}")
    for p in problems:
        print(f"problem: {p}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
