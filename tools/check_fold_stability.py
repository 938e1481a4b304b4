#!/usr/bin/env python3
"""Checks a tmrotor recording's stability against its folds, with the official MCAP
readers only (independent of tmrotor's own reader):

* at every located saddle-node (alone in its step) the number of real multipliers above
  +1 changes by exactly one between the points on either side, or the recording's
  warnings say why not (a collision of real multipliers outside the circle in that step);
* between the two folds of an S-shaped pair every point is unstable;
* every change of the stable flag between neighbouring points has a located bifurcation
  in that step or a warning in /log (logger name "tmrotor.audit") about it.

    .venv/bin/python tools/check_fold_stability.py FILE.mcap [FILE.mcap ...]

Prints one line per file and exits with status 1 when a check fails.
"""
import sys

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

UNSTABLE = 2  # tmrotor.v1.Stability: UNKNOWN = 0, STABLE = 1, UNSTABLE = 2
SADDLE_NODE = 1  # tmrotor.v1.BifurcationType: NONE = 0, SADDLE_NODE = 1, ...


def read(path):
    floquet, summary, bifs, notes = {}, {}, [], []
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages():
            if channel.topic == "/floquet":
                floquet[msg.index] = msg
            elif channel.topic == "/summary":
                summary[msg.index] = msg
            elif channel.topic == "/bifurcations":
                bifs.append(msg)
            elif channel.topic == "/log" and msg.name == "tmrotor.audit":
                notes.append(msg.message)
    return floquet, summary, bifs, notes


def real_above_one(msg):
    """The recorded count, or (recordings without it) the count from the multipliers."""
    if hasattr(msg, "real_above_one"):
        return msg.real_above_one
    return sum(
        1
        for m in msg.multipliers
        if abs(complex(m.re, m.im)) > 1 + 1e-6 and m.re > 0 and abs(m.im) <= 0.05 * abs(complex(m.re, m.im))
    )


def check(path):
    floquet, summary, bifs, notes = read(path)
    problems = []
    folds = [b for b in bifs if b.type == SADDLE_NODE]
    per_step = {}
    for b in bifs:
        per_step.setdefault(b.after_point, []).append(b)
    for b in folds:
        k = b.after_point
        if len(per_step[k]) > 1 or k not in floquet or k + 1 not in floquet:
            continue
        before, after = real_above_one(floquet[k]), real_above_one(floquet[k + 1])
        reported = any(f"between points {k} and {k + 1} " in n and "not by one" in n for n in notes)
        if abs(after - before) != 1 and not reported:
            problems.append(
                f"saddle-node at {b.omega_rad_s:.4f} rad/s: real multipliers above +1 "
                f"{before} -> {after}"
            )
    indices = sorted(summary)
    direction = 1.0
    if len(indices) > 1:
        direction = 1.0 if summary[indices[-1]].omega_rad_s >= summary[indices[0]].omega_rad_s else -1.0
    for a, b in zip(folds, folds[1:]):
        inside = [i for i in range(a.after_point + 1, b.after_point + 1) if i in summary]
        if a.after_point == b.after_point or len(inside) < 2:
            continue
        # the segment between two folds that runs against the sweep's direction is the
        # middle of an S-shaped pair
        backward = all(
            (summary[j].omega_rad_s - summary[i].omega_rad_s) * direction < 0
            for i, j in zip(inside, inside[1:])
        )
        stable = [i for i in inside if summary[i].stability != UNSTABLE]
        if backward and stable:
            problems.append(
                f"fold pair {a.omega_rad_s:.4f}/{b.omega_rad_s:.4f} rad/s: points "
                f"{stable[:5]} of the middle segment are not flagged unstable"
            )
    for i, j in zip(indices, indices[1:]):
        sa, sb = summary[i].stability, summary[j].stability
        if sa == 0 or sb == 0 or sa == sb:
            continue
        located = i in per_step
        warned = any(f"between points {i} and {j} " in n for n in notes)
        if not located and not warned:
            problems.append(f"stable flag changes between points {i} and {j} silently")
    return len(folds), problems


def main():
    failed = False
    for path in sys.argv[1:]:
        n_folds, problems = check(path)
        status = "ok" if not problems else f"{len(problems)} problems"
        print(f"{path}: {n_folds} saddle-nodes, {status}")
        for p in problems:
            print(f"  {p}")
        failed |= bool(problems)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
