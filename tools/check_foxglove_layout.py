#!/usr/bin/env python3
"""Checks a Foxglove layout (the JSON of "Export layout") against a tmrotor recording.

usage: check_foxglove_layout.py [options] LAYOUT RECORDING

What is checked, in this order (the first problem stops the check, exit status 1):

1. LAYOUT is valid JSON of the exported-layout shape: an object with `configById`
   (panel id -> panel config object) and `layout` (the mosaic tree: a panel id, or
   `{"direction": "row"|"column", "first": NODE, "second": NODE, "splitPercentage": 0..100}`);
   `globalVariables`, `userNodes`, `playbackConfig` are objects when present. Panel ids
   are `Type!suffix` (e.g. `Plot!amplitude`); every panel of the tree, including the
   trees inside Tab panels (`{"activeTabIdx": i, "tabs": [{"title", "layout"}]}`), has a
   config and appears once. Configs no tree uses are reported as warnings.
2. Every topic the layout names exists in RECORDING and has messages: the topics of all
   message paths, the 3D panel's `topics`, the Log panel's `topicToRender` (which must
   carry a log message, e.g. foxglove.Log).
3. Every message path resolves on the decoded messages of its topic (decoded with the
   official `mcap` + `mcap_protobuf` readers, the same protobuf schemas Foxglove reads
   from the file). Paths are taken from: Plot `paths[].value` (a plain number is a
   reference line and is skipped), `paths[].xValuePath`, `xAxisPath.value` (required
   when `xAxisVal` is `custom` or `currentCustom`); State Transitions `paths[].value`;
   Raw Messages and Table `topicPath`; Indicator and Gauge `path`. Resolving means:
   each field name exists in the protobuf message at that point (with a suggestion when
   it is misspelt), repeated fields are indexed or sliced before going deeper, an index
   is within the array of at least one sampled message, each filter names an existing
   scalar field with a value of a type Foxglove can compare with it (enum fields are
   compared as numbers and the number must be a value of the enum), and a Plot path ends
   at a number (State Transitions: at a scalar). Filter values are checked, not applied:
   a filter that matches no sampled message (e.g. `{stability==2}` on a run without
   unstable points) still resolves; the number of matches is printed.
4. The 3D panel's `followTf` is a frame id used by the messages of its topics.
5. tmrotor specific: a series whose path indexes a per-node or per-bearing array
   (`amplitude_rms_m[k]` of /summary, `nodes[k]` of /temperatures and /orbits,
   `bearings[k]` of /clearance, /bearing_loads, /thermal_forces) and has a `label` must
   name the entry it plots: `RunInfo.nodes[k].name`, `RunInfo.thermal_nodes[k].name` or
   `RunInfo.bearings[k].name` (from /run_info), so a label cannot drift from its index
   (`--no-label-check` turns this off).

6. Pairing by position: Foxglove Studio 1.48 and Lichtblick ignore a series' own
   `xValuePath` and pair every series of a Plot whose `xAxisVal` is `custom` with the
   panel's `xAxisPath` by position ("Mismatch in the number of elements in x-axis and
   y-axis messages" otherwise). So every enabled series of such a panel must read the
   x path's topic with no message filter (`{...}` right after the topic), and neither
   may the x path.
7. Readable axes: a Plot series whose sampled values are all below 0.001 in magnitude
   (and not all zero) is drawn as a flat line, since the y-axis ticks are rounded to
   three decimals: plot a field in smaller units (e.g. `_um` instead of `_m`).
8. The 3D panel's `followTf` frame is published by a `foxglove.FrameTransform` in the
   recording (1.48 reports `Frame ... not found` for a frame only used by entities).

`--ignore-topic TOPIC` leaves out what the layout shows from TOPIC (e.g. `/scene` for a
recording written without it).

Message-path grammar supported (Foxglove's message path syntax):

    path      := topic element* modifier?
    topic     := ("/" id?)+  |  id ("/" id?)*  |  '"' quoted topic '"'
    element   := "." id slice? filter*  |  filter
    slice     := "[" index "]"  |  "[" index? ":" index? "]"      (end inclusive)
    index     := integer  |  "$" id                                (negative: from the end)
    filter    := "{" id ("." id)* "==" value "}"
    value     := integer  |  'string'  |  "string"  |  true  |  false  |  "$" id
    modifier  := ".@" id        (Plot math modifiers: .@abs, .@derivative, .@sqrt, ...)
    id        := [A-Za-z0-9_]+

Examples: `/summary.omega_rad_s`, `/summary{stability==1}.amplitude_rms_m[7]`,
`/clearance.bearings[1].delta_v_m`, `/floquet.multipliers[:].re`,
`/clearance.bearings[:]{bearing=="3#"}.delta_v_m`, `/summary.spectral_radius.@log10`.
No whitespace is allowed; `$name` must be a key of the layout's `globalVariables`. A
filter placed right after the topic selects whole messages; after a slice it selects
array elements. Protobuf enums are decoded as their numbers by Foxglove, so
`{stability==1}` (STABILITY_STABLE) works and `{stability=='STABILITY_STABLE'}` never
matches; the checker rejects the latter. google.protobuf.Timestamp/Duration fields are
addressed as `sec`/`nsec`, as Foxglove renames them.

Exit status: 0 when everything resolves, 1 on the first layout problem (the reason on
stderr), 2 on bad usage or an unreadable file.
"""

from __future__ import annotations

import argparse
import difflib
import json
import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from google.protobuf.descriptor import FieldDescriptor
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

PLOT_MODIFIERS = {
    "abs", "acos", "asin", "atan", "ceil", "cos", "derivative", "log", "log1p", "log2",
    "log10", "negative", "round", "sign", "sin", "sqrt", "tan", "trunc",
}
TIMESTAMP_METHODS = {"receiveTime", "publishTime", "headerStamp", "customField"}
X_AXIS_VALS = {"timestamp", "index", "custom", "currentCustom"}
LINE_STYLES = {"solid", "dashed", "dotted"}
LOG_SCHEMAS = {"foxglove.Log", "rosgraph_msgs/Log", "rcl_interfaces/msg/Log", "rcl_interfaces/Log"}
TIME_TYPES = {"google.protobuf.Timestamp", "google.protobuf.Duration"}
TIME_RENAMES = {"sec": "seconds", "nsec": "nanos"}
KNOWN_TOP_LEVEL = {"configById", "layout", "globalVariables", "userNodes", "playbackConfig",
                   "linkedGlobalVariables", "version"}
NUMERIC_TYPES = {
    FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT, FieldDescriptor.TYPE_INT64,
    FieldDescriptor.TYPE_UINT64, FieldDescriptor.TYPE_INT32, FieldDescriptor.TYPE_FIXED64,
    FieldDescriptor.TYPE_FIXED32, FieldDescriptor.TYPE_UINT32, FieldDescriptor.TYPE_SFIXED32,
    FieldDescriptor.TYPE_SFIXED64, FieldDescriptor.TYPE_SINT32, FieldDescriptor.TYPE_SINT64,
}
TYPE_NAMES = {
    getattr(FieldDescriptor, n): n[len("TYPE_"):].lower()
    for n in dir(FieldDescriptor) if n.startswith("TYPE_")
}

# tmrotor: which RunInfo list names the entries of a per-node / per-bearing array.
RUNINFO_LISTS = {
    ("/summary", "amplitude_rms_m"): "nodes",
    ("/summary", "amplitude_rms_um"): "nodes",
    ("/summary", "amplitude_rms_stable_um"): "nodes",
    ("/summary", "amplitude_rms_unstable_um"): "nodes",
    ("/bifurcations", "amplitude_rms_m"): "nodes",
    ("/orbits", "nodes"): "nodes",
    ("/temperatures", "nodes"): "thermal_nodes",
    ("/clearance", "bearings"): "bearings",
    ("/bearing_loads", "bearings"): "bearings",
    ("/thermal_forces", "bearings"): "bearings",
}


class LayoutProblem(Exception):
    """A problem with the layout (exit status 1)."""


class UsageProblem(Exception):
    """Bad usage or unreadable recording (exit status 2)."""


# ------------------------------------------------------------------------------------
# Message-path parsing


@dataclass
class Var:
    name: str

    def __str__(self) -> str:
        return f"${self.name}"


@dataclass
class Name:
    name: str


@dataclass
class Slice:
    start: int | Var | None  # None: open
    end: int | Var | None
    single: bool

    def __str__(self) -> str:
        if self.single:
            return f"[{self.start}]"
        s = "" if self.start is None else str(self.start)
        e = "" if self.end is None else str(self.end)
        return f"[{s}:{e}]"


@dataclass
class Filter:
    path: list[str]
    value: Any  # int, str, bool or Var
    repr: str


@dataclass
class MessagePath:
    text: str
    topic: str
    parts: list = field(default_factory=list)
    modifier: str | None = None


_ID = re.compile(r"[A-Za-z0-9_]+")
_TOPIC = re.compile(r"(?:/[A-Za-z0-9_]*)+|[A-Za-z0-9_]+(?:/[A-Za-z0-9_]*)*")
_INT = re.compile(r"-?[0-9]+")


def _syntax(text: str, pos: int, what: str) -> LayoutProblem:
    return LayoutProblem(f"message path {text!r}: {what} at column {pos + 1}\n    {text}\n    {' ' * pos}^")


def parse_path(text: str) -> MessagePath:
    """Parses a Foxglove message path (grammar in the module docstring)."""
    if not isinstance(text, str) or not text:
        raise LayoutProblem(f"message path {text!r}: empty or not a string")
    pos = 0
    if text.startswith('"'):
        out = []
        pos = 1
        while True:
            if pos >= len(text):
                raise _syntax(text, pos, "unterminated quoted topic name")
            c = text[pos]
            if c == "\\" and pos + 1 < len(text) and text[pos + 1] in '\\"':
                out.append(text[pos + 1])
                pos += 2
            elif c == '"':
                pos += 1
                break
            else:
                out.append(c)
                pos += 1
        topic = "".join(out)
    else:
        m = _TOPIC.match(text)
        if not m:
            raise _syntax(text, 0, "expected a topic name such as /summary")
        topic = m.group(0)
        pos = m.end()
    path = MessagePath(text=text, topic=topic)

    def parse_id(p: int, what: str) -> tuple[str, int]:
        m = _ID.match(text, p)
        if not m:
            raise _syntax(text, p, f"expected {what} ([A-Za-z0-9_]+)")
        return m.group(0), m.end()

    def parse_index(p: int) -> tuple[int | Var | None, int]:
        if text.startswith("$", p):
            name, p = parse_id(p + 1, "a variable name after '$'")
            return Var(name), p
        m = _INT.match(text, p)
        if m:
            return int(m.group(0)), m.end()
        return None, p

    def parse_value(p: int) -> tuple[Any, str, int]:
        if p < len(text) and text[p] in "'\"":
            q = text[p]
            end = text.find(q, p + 1)
            if end < 0:
                raise _syntax(text, p, "unterminated string in filter")
            return text[p + 1:end], text[p:end + 1], end + 1
        if text.startswith("$", p):
            name, e = parse_id(p + 1, "a variable name after '$'")
            return Var(name), text[p:e], e
        for word, val in (("true", True), ("false", False)):
            if text.startswith(word, p) and not _ID.match(text, p + len(word)):
                return val, word, p + len(word)
        m = _INT.match(text, p)
        if m and (m.end() >= len(text) or text[m.end()] not in "._" and not text[m.end()].isalnum()):
            return int(m.group(0)), m.group(0), m.end()
        m = re.compile(r"[^}]*").match(text, p)
        raise _syntax(text, p, f"filter value {m.group(0)!r} is not an integer, a quoted string, "
                      "true, false or a $variable (Foxglove compares filters with these only; "
                      "protobuf enums are compared as their numbers)")

    def parse_filter(p: int) -> tuple[Filter, int]:
        start = p
        p += 1  # "{"
        names = []
        name, p = parse_id(p, "a field name in the filter")
        names.append(name)
        while text.startswith(".", p):
            name, p = parse_id(p + 1, "a field name after '.' in the filter")
            names.append(name)
        if not text.startswith("==", p):
            raise _syntax(text, p, "expected '==' in the filter (only equality is supported)")
        value, vrepr, p = parse_value(p + 2)
        if not text.startswith("}", p):
            raise _syntax(text, p, "expected '}' closing the filter")
        return Filter(names, value, f"{'.'.join(names)}=={vrepr}"), p + 1

    while pos < len(text):
        if text.startswith(".@", pos):
            name, pos = parse_id(pos + 2, "a modifier name after '.@'")
            if pos != len(text):
                raise _syntax(text, pos, "a modifier (.@name) must end the path")
            path.modifier = name
            break
        if text.startswith(".", pos):
            name, pos = parse_id(pos + 1, "a field name after '.'")
            path.parts.append(Name(name))
            if text.startswith("[", pos):
                p0 = pos
                start, pos = parse_index(pos + 1)
                if text.startswith("]", pos):
                    if start is None:
                        raise _syntax(text, p0, "empty index '[]'")
                    path.parts.append(Slice(start, start, True))
                    pos += 1
                elif text.startswith(":", pos):
                    end, pos = parse_index(pos + 1)
                    if not text.startswith("]", pos):
                        raise _syntax(text, pos, "expected ']' closing the slice")
                    path.parts.append(Slice(start, end, False))
                    pos += 1
                else:
                    raise _syntax(text, pos, "expected an integer index, ':' or ']'")
            continue
        if text.startswith("{", pos):
            flt, pos = parse_filter(pos)
            path.parts.append(flt)
            continue
        if text.startswith("[", pos):
            raise _syntax(text, pos, "an index must follow a field name (no index on a topic or a filter)")
        raise _syntax(text, pos, f"unexpected {text[pos]!r} (expected '.field', '{{filter}}' or '.@modifier')")
    return path


# ------------------------------------------------------------------------------------
# The recording


@dataclass
class Recording:
    path: str
    schemas: dict[str, str]  # topic -> schema name
    counts: dict[str, int]  # topic -> message count (summary statistics, or counted while reading)
    samples: dict[str, list]  # topic -> decoded messages (the first max_samples)


def read_recording(path: str, topics: set[str], max_samples: int) -> Recording:
    try:
        f = open(path, "rb")
    except OSError as e:
        raise UsageProblem(f"cannot open recording {path}: {e}") from e
    with f:
        try:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
        except Exception as e:  # noqa: BLE001 - any reader failure means an unreadable file
            raise UsageProblem(f"{path} is not a readable MCAP file: {e}") from e
        schemas: dict[str, str] = {}
        counts: dict[str, int] = {}
        if summary is not None:
            for cid, ch in summary.channels.items():
                sch = summary.schemas.get(ch.schema_id)
                schemas[ch.topic] = sch.name if sch else ""
                if summary.statistics is not None:
                    counts[ch.topic] = counts.get(ch.topic, 0) + summary.statistics.channel_message_counts.get(cid, 0)
        factory = DecoderFactory()
        decoders: dict[int, Any] = {}
        samples: dict[str, list] = {t: [] for t in topics}
        scan_counts: dict[str, int] = {}
        wanted = set(topics)
        # with message counts in the summary, stop reading once every topic has its samples
        target = ({t: min(max_samples, counts.get(t, 0)) for t in wanted}
                  if summary is not None and summary.statistics is not None else None)
        try:
            for schema, channel, message in reader.iter_messages():
                t = channel.topic
                if schema is not None:
                    schemas.setdefault(t, schema.name)
                scan_counts[t] = scan_counts.get(t, 0) + 1
                if t not in wanted:
                    continue
                bucket = samples[t]
                if len(bucket) < max_samples:
                    dec = decoders.get(channel.id)
                    if dec is None:
                        dec = factory.decoder_for(channel.message_encoding, schema)
                        if dec is None:
                            raise UsageProblem(f"{path}: no decoder for topic {t} "
                                               f"(encoding {channel.message_encoding})")
                        decoders[channel.id] = dec
                    bucket.append(dec(message.data))
                if target is not None and all(len(samples[w]) >= target[w] for w in wanted):
                    break
        except UsageProblem:
            raise
        except Exception as e:  # noqa: BLE001
            if not any(samples.values()):
                raise UsageProblem(f"{path}: reading messages failed: {e}") from e
            print(f"warning: reading {path} stopped early: {e}", file=sys.stderr)
        if summary is None:
            counts = scan_counts
    return Recording(path=path, schemas=schemas, counts=counts, samples=samples)


# ------------------------------------------------------------------------------------
# Resolving a path on the protobuf messages


def _describe_field(fd: FieldDescriptor) -> str:
    if fd.type == FieldDescriptor.TYPE_MESSAGE:
        base = fd.message_type.full_name
    elif fd.type == FieldDescriptor.TYPE_ENUM:
        base = f"enum {fd.enum_type.full_name}"
    else:
        base = TYPE_NAMES.get(fd.type, "?")
    return f"repeated {base}" if _is_repeated(fd) else base


def _is_repeated(fd: FieldDescriptor) -> bool:
    rep = getattr(fd, "is_repeated", None)
    if rep is not None:
        return bool(rep)
    return fd.label == FieldDescriptor.LABEL_REPEATED


def _field_names(desc) -> list[str]:
    names = [f.name for f in desc.fields]
    if desc.full_name in TIME_TYPES:
        names = ["sec", "nsec"]
    return names


def _lookup_field(desc, name: str, text: str, where: str):
    if desc.full_name in TIME_TYPES:
        if name in TIME_RENAMES:
            return desc.fields_by_name[TIME_RENAMES[name]]
        hint = " (Foxglove renames google.protobuf time fields: use sec and nsec)" if name in TIME_RENAMES.values() else ""
        raise LayoutProblem(f"message path {text!r}: no field {name!r} in {desc.full_name}{where}{hint}")
    fd = desc.fields_by_name.get(name)
    if fd is None:
        names = _field_names(desc)
        close = difflib.get_close_matches(name, names, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise LayoutProblem(f"message path {text!r}: no field {name!r} in {desc.full_name}{where}{hint} "
                            f"(its fields: {', '.join(names)})")
    return fd


@dataclass
class State:
    """Where the schema walk stands: a message, a scalar, or a repeated field not yet indexed."""

    desc: Any = None  # message descriptor when at a message (or a repeated message)
    fd: FieldDescriptor | None = None  # the field last stepped into
    repeated: bool = False

    def describe(self) -> str:
        if self.fd is None:
            return self.desc.full_name
        if self.repeated:
            return _describe_field(self.fd)
        if self.fd.type == FieldDescriptor.TYPE_MESSAGE:
            return self.fd.message_type.full_name
        if self.fd.type == FieldDescriptor.TYPE_ENUM:
            return f"enum {self.fd.enum_type.full_name}"
        return TYPE_NAMES.get(self.fd.type, "?")

    @property
    def is_message(self) -> bool:
        return not self.repeated and self.desc is not None

    @property
    def is_scalar(self) -> bool:
        return not self.repeated and self.desc is None


def _enum_listing(fd: FieldDescriptor) -> str:
    return ", ".join(f"{v.number}={v.name}" for v in fd.enum_type.values)


def _variable(var: Var, variables: dict, text: str) -> Any:
    if var.name not in variables:
        raise LayoutProblem(f"message path {text!r}: variable ${var.name} is not defined in the "
                            f"layout's globalVariables ({', '.join(sorted(variables)) or 'none defined'})")
    return variables[var.name]


def _check_filter_value(flt: Filter, fd: FieldDescriptor, value: Any, text: str) -> str:
    """Checks that Foxglove can compare `value` with the field; returns a note for the report."""
    t = fd.type
    desc = f"{'.'.join(flt.path)} ({_describe_field(fd)})"
    if isinstance(value, bool):
        if t != FieldDescriptor.TYPE_BOOL:
            raise LayoutProblem(f"message path {text!r}: filter {{{flt.repr}}} compares {desc} with a boolean")
        return ""
    if t == FieldDescriptor.TYPE_ENUM:
        if isinstance(value, str):
            raise LayoutProblem(
                f"message path {text!r}: filter {{{flt.repr}}} compares the enum field {desc} with a "
                f"string; Foxglove decodes protobuf enums as their numbers, so this never matches; "
                f"use a number: {_enum_listing(fd)}")
        if not isinstance(value, int):
            raise LayoutProblem(f"message path {text!r}: filter {{{flt.repr}}}: {value!r} is not a number")
        ev = fd.enum_type.values_by_number.get(value)
        if ev is None:
            raise LayoutProblem(f"message path {text!r}: filter {{{flt.repr}}}: {value} is not a value of "
                                f"{fd.enum_type.full_name} ({_enum_listing(fd)})")
        return f"{'.'.join(flt.path)}=={value} ({ev.name})"
    if t in NUMERIC_TYPES:
        if isinstance(value, str):
            try:
                float(value)
            except ValueError:
                raise LayoutProblem(f"message path {text!r}: filter {{{flt.repr}}} compares the number "
                                    f"{desc} with the string {value!r}") from None
        return ""
    if t == FieldDescriptor.TYPE_BOOL:
        if value not in (0, 1):
            raise LayoutProblem(f"message path {text!r}: filter {{{flt.repr}}} compares the boolean {desc} "
                                f"with {value!r}; use true or false")
        return ""
    if t == FieldDescriptor.TYPE_STRING:
        return ""
    raise LayoutProblem(f"message path {text!r}: filter {{{flt.repr}}}: {desc} cannot be compared in a filter")


def schema_walk(mp: MessagePath, root_desc, variables: dict) -> tuple[State, list[str]]:
    """Walks the path over the protobuf descriptors; returns the final state and notes."""
    text = mp.text
    state = State(desc=root_desc)
    notes: list[str] = []
    trail = mp.topic
    for part in mp.parts:
        if isinstance(part, Name):
            if state.repeated:
                raise LayoutProblem(
                    f"message path {text!r}: {trail} is a {state.describe()}: index it ({trail}[0]) or "
                    f"slice it ({trail}[:]) before '.{part.name}'")
            if state.is_scalar:
                raise LayoutProblem(f"message path {text!r}: {trail} is a {state.describe()}; it has no "
                                    f"field '.{part.name}'")
            fd = _lookup_field(state.desc, part.name, text, f" (at {trail})")
            rep = _is_repeated(fd)
            msg = fd.message_type if fd.type == FieldDescriptor.TYPE_MESSAGE else None
            state = State(desc=msg, fd=fd, repeated=rep)
            trail = f"{trail}.{part.name}"
        elif isinstance(part, Slice):
            if not state.repeated:
                raise LayoutProblem(f"message path {text!r}: {trail} is a {state.describe()}, not an array; "
                                    f"it cannot be indexed with {part}")
            for v in (part.start, part.end):
                if isinstance(v, Var):
                    val = _variable(v, variables, text)
                    if not isinstance(val, int) or isinstance(val, bool):
                        raise LayoutProblem(f"message path {text!r}: variable ${v.name} = {val!r} is used "
                                            f"as an index but is not an integer")
            state = State(desc=state.desc, fd=state.fd, repeated=False)
            trail = f"{trail}{part}"
        elif isinstance(part, Filter):
            if state.repeated:
                raise LayoutProblem(f"message path {text!r}: filter {{{part.repr}}} on the array {trail}; "
                                    f"slice it first ({trail}[:]{{{part.repr}}})")
            if not state.is_message:
                raise LayoutProblem(f"message path {text!r}: filter {{{part.repr}}} on {trail}, a "
                                    f"{state.describe()}; filters select messages by one of their fields")
            desc = state.desc
            fd = None
            for i, name in enumerate(part.path):
                fd = _lookup_field(desc, name, text, f" (filter {{{part.repr}}} at {trail})")
                last = i == len(part.path) - 1
                if _is_repeated(fd):
                    raise LayoutProblem(f"message path {text!r}: filter {{{part.repr}}}: {name} is a "
                                        f"{_describe_field(fd)}; a filter compares a single value")
                if not last:
                    if fd.type != FieldDescriptor.TYPE_MESSAGE:
                        raise LayoutProblem(f"message path {text!r}: filter {{{part.repr}}}: {name} is a "
                                            f"{_describe_field(fd)}; it has no field '.{part.path[i + 1]}'")
                    desc = fd.message_type
                elif fd.type == FieldDescriptor.TYPE_MESSAGE:
                    raise LayoutProblem(f"message path {text!r}: filter {{{part.repr}}}: {name} is a message "
                                        f"({fd.message_type.full_name}); compare one of its fields")
            value = part.value
            if isinstance(value, Var):
                value = _variable(value, variables, text)
            note = _check_filter_value(part, fd, value, text)
            notes.append(note or part.repr)
            trail = f"{trail}{{{part.repr}}}"
    return state, notes


def _loose_eq(a: Any, b: Any) -> bool:
    """JavaScript `==` for the values a filter meets (numbers, booleans, strings)."""
    if isinstance(a, str) and isinstance(b, str):
        return a == b
    def num(x):
        if isinstance(x, str):
            try:
                return float(x)
            except ValueError:
                return math.nan
        return float(x)
    try:
        return num(a) == num(b)
    except (TypeError, ValueError):
        return False


@dataclass
class WalkStats:
    out_of_range: list = field(default_factory=list)  # (trail, index, length)


def data_walk(mp: MessagePath, msg, variables: dict, honor_filters: bool, stats: WalkStats) -> list:
    """Evaluates the path on one decoded message like Foxglove does; filters are applied
    only when honor_filters (otherwise they just pass through)."""
    results: list = []
    parts = mp.parts

    def get(value, name):
        if value.DESCRIPTOR.full_name in TIME_TYPES:
            name = TIME_RENAMES.get(name, name)
        fd = value.DESCRIPTOR.fields_by_name[name]
        if fd.type == FieldDescriptor.TYPE_MESSAGE and not _is_repeated(fd) and not value.HasField(name):
            return None  # Foxglove (protobufjs, defaults) gives null for an unset message field
        return getattr(value, name)

    def index_value(v):
        return _variable(v, variables, mp.text) if isinstance(v, Var) else v

    def walk(value, i, trail):
        if i == len(parts):
            results.append(value)
            return
        if value is None:
            return
        part = parts[i]
        if isinstance(part, Name):
            walk(get(value, part.name), i + 1, f"{trail}.{part.name}")
        elif isinstance(part, Slice):
            n = len(value)
            if part.single:
                k = index_value(part.start)
                kk = k + n if k < 0 else k
                if 0 <= kk < n:
                    walk(value[kk], i + 1, f"{trail}[{k}]")
                else:
                    stats.out_of_range.append((trail, k, n))
                return
            a = index_value(part.start)
            b = index_value(part.end)
            a = 0 if a is None else (a + n if a < 0 else a)
            b = n - 1 if b is None else (b + n if b < 0 else b)
            for k in range(max(a, 0), min(b, n - 1) + 1):
                walk(value[k], i + 1, f"{trail}[{k}]")
        elif isinstance(part, Filter):
            if honor_filters:
                cur = value
                for name in part.path:
                    cur = get(cur, name)
                    if cur is None:
                        return
                want = part.value
                if isinstance(want, Var):
                    want = _variable(want, variables, mp.text)
                if not _loose_eq(cur, want):
                    return
            walk(value, i + 1, trail)

    walk(msg, 0, mp.topic)
    return results


@dataclass
class Resolved:
    type_desc: str
    example: Any
    notes: list[str]
    state: State


def _fmt_value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (int, bool, str)):
        s = repr(v)
        return s if len(s) <= 40 else s[:37] + "..."
    if hasattr(v, "DESCRIPTOR"):
        return f"<{v.DESCRIPTOR.full_name}>"
    try:
        return f"<{len(v)} elements>"
    except TypeError:
        return f"<{type(v).__name__}>"


def resolve(text: str, role: str, rec: Recording, variables: dict) -> tuple[MessagePath, Resolved]:
    """role: 'number' (Plot), 'scalar' (State Transitions, Indicator), 'any' (Raw Messages, Table)."""
    mp = parse_path(text)
    if mp.topic not in rec.schemas:
        close = difflib.get_close_matches(mp.topic, list(rec.schemas), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise LayoutProblem(f"message path {text!r}: topic {mp.topic} is not in the recording{hint} "
                            f"(topics: {', '.join(sorted(rec.schemas))})")
    samples = rec.samples.get(mp.topic) or []
    if not samples:
        raise LayoutProblem(f"message path {text!r}: topic {mp.topic} has no messages in the recording, so "
                            f"the path cannot be resolved on a decoded message")
    root = samples[0].DESCRIPTOR
    state, notes = schema_walk(mp, root, variables)
    if mp.modifier is not None:
        if role != "number":
            raise LayoutProblem(f"message path {text!r}: modifiers (.@{mp.modifier}) are a Plot feature")
        if mp.modifier not in PLOT_MODIFIERS:
            raise LayoutProblem(f"message path {text!r}: unknown modifier .@{mp.modifier} "
                                f"(known: {', '.join(sorted(PLOT_MODIFIERS))})")
    if role in ("number", "scalar"):
        if state.repeated:
            raise LayoutProblem(f"message path {text!r}: ends at the array {state.describe()}; pick an element "
                                f"([k]) or all of them ([:])")
        if state.is_message:
            raise LayoutProblem(f"message path {text!r}: ends at the message {state.describe()}; "
                                f"{'a plot needs a number' if role == 'number' else 'a scalar is needed'}: "
                                f"name one of its fields ({', '.join(_field_names(state.desc))})")
        if role == "number" and state.fd is not None and state.fd.type in (
                FieldDescriptor.TYPE_STRING, FieldDescriptor.TYPE_BYTES):
            raise LayoutProblem(f"message path {text!r}: ends at a {state.describe()}; a plot needs a number")
    stats = WalkStats()
    example = None
    resolved_on = 0
    matched = 0
    has_filter = any(isinstance(p, Filter) for p in mp.parts)
    example_matches = False
    for msg in samples:
        vals = data_walk(mp, msg, variables, honor_filters=False, stats=stats)
        if vals:
            resolved_on += 1
            if example is None:
                example = vals[0]
        if has_filter:
            hits = data_walk(mp, msg, variables, honor_filters=True, stats=WalkStats())
            if hits:
                matched += 1
                if not example_matches:
                    example, example_matches = hits[0], True
    if resolved_on == 0:
        if stats.out_of_range:
            trail, k, _ = stats.out_of_range[0]
            lengths = sorted({n for (_, _, n) in stats.out_of_range})
            raise LayoutProblem(f"message path {text!r}: index [{k}] is out of range: {trail} has "
                                f"{'/'.join(map(str, lengths))} elements in the {len(samples)} sampled "
                                f"{mp.topic} messages")
        raise LayoutProblem(f"message path {text!r}: resolves to no value on any of the {len(samples)} sampled "
                            f"{mp.topic} messages (empty arrays or unset message fields)")
    out_notes = []
    if has_filter:
        out_notes.append(f"filter {', '.join(notes)} matches {matched}/{len(samples)} sampled messages")
    if resolved_on < len(samples):
        out_notes.append(f"resolves on {resolved_on}/{len(samples)} messages")
    return mp, Resolved(type_desc=state.describe(), example=example, notes=out_notes, state=state)


# ------------------------------------------------------------------------------------
# Layout shape


PANEL_ID = re.compile(r"^([^!]+)!(.+)$")


def panel_type(panel_id: str) -> str:
    return panel_id.split("!", 1)[0]


def mosaic_leaves(node: Any, where: str, out: list[str]) -> None:
    if isinstance(node, str):
        if not PANEL_ID.match(node):
            raise LayoutProblem(f"{where}: panel id {node!r} is not of the form Type!suffix (e.g. Plot!a1b2)")
        out.append(node)
        return
    if not isinstance(node, dict):
        raise LayoutProblem(f"{where}: a mosaic node must be a panel id or an object with direction, first, "
                            f"second; found {type(node).__name__}")
    for key in ("first", "second", "direction"):
        if key not in node:
            raise LayoutProblem(f"{where}: mosaic split without {key!r} (keys: {', '.join(node)})")
    if node["direction"] not in ("row", "column"):
        raise LayoutProblem(f"{where}: direction {node['direction']!r} is neither 'row' nor 'column'")
    if "splitPercentage" in node:
        sp = node["splitPercentage"]
        if not isinstance(sp, (int, float)) or isinstance(sp, bool) or not 0 <= sp <= 100:
            raise LayoutProblem(f"{where}: splitPercentage {sp!r} is not a number in 0..100")
    extra = set(node) - {"first", "second", "direction", "splitPercentage"}
    if extra:
        print(f"warning: {where}: unknown mosaic keys {sorted(extra)} (ignored by Foxglove)", file=sys.stderr)
    mosaic_leaves(node["first"], f"{where}.first", out)
    mosaic_leaves(node["second"], f"{where}.second", out)


def all_panels(doc: dict) -> list[tuple[str, str]]:
    """Every panel id of the layout with where it sits; Tab panels' trees included."""
    configs = doc["configById"]
    found: list[tuple[str, str]] = []

    def visit(node: Any, where: str) -> None:
        leaves: list[str] = []
        mosaic_leaves(node, where, leaves)
        for pid in leaves:
            found.append((pid, where))
            if pid not in configs:
                raise LayoutProblem(f"{where}: panel {pid!r} has no entry in configById")
            if panel_type(pid) == "Tab":
                cfg = configs[pid]
                tabs = cfg.get("tabs")
                idx = cfg.get("activeTabIdx")
                if not isinstance(tabs, list) or not tabs:
                    raise LayoutProblem(f"configById[{pid!r}]: a Tab panel needs a non-empty 'tabs' list")
                if not isinstance(idx, int) or not 0 <= idx < len(tabs):
                    raise LayoutProblem(f"configById[{pid!r}]: activeTabIdx {idx!r} does not name one of its "
                                        f"{len(tabs)} tabs")
                for i, tab in enumerate(tabs):
                    if not isinstance(tab, dict) or not isinstance(tab.get("title", ""), str):
                        raise LayoutProblem(f"configById[{pid!r}].tabs[{i}]: a tab is {{title, layout}}")
                    if tab.get("layout") is not None:
                        visit(tab["layout"], f"configById[{pid!r}].tabs[{i}].layout")

    visit(doc["layout"], "layout")
    seen: set[str] = set()
    for pid, where in found:
        if pid in seen:
            raise LayoutProblem(f"{where}: panel {pid!r} appears more than once in the layout")
        seen.add(pid)
    return found


def load_layout(path: str) -> dict:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as e:
        raise UsageProblem(f"cannot read layout {path}: {e}") from e
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise LayoutProblem(f"{path} is not valid JSON: {e.msg} at line {e.lineno} column {e.colno}") from None
    if not isinstance(doc, dict):
        raise LayoutProblem(f"{path}: a layout is a JSON object, found {type(doc).__name__}")
    for key in ("configById", "layout"):
        if key not in doc:
            raise LayoutProblem(f"{path}: no {key!r} (a Foxglove layout has configById, layout, "
                                f"globalVariables, userNodes, playbackConfig)")
    if not isinstance(doc["configById"], dict):
        raise LayoutProblem(f"{path}: configById must be an object (panel id -> config)")
    if doc["layout"] is None:
        raise LayoutProblem(f"{path}: layout is empty (null): no panel would be shown")
    for key in ("globalVariables", "userNodes", "playbackConfig"):
        if key in doc and not isinstance(doc[key], dict):
            raise LayoutProblem(f"{path}: {key} must be an object")
    speed = doc.get("playbackConfig", {}).get("speed")
    if speed is not None and (not isinstance(speed, (int, float)) or isinstance(speed, bool) or speed <= 0):
        raise LayoutProblem(f"{path}: playbackConfig.speed {speed!r} is not a positive number")
    for key in set(doc) - KNOWN_TOP_LEVEL:
        print(f"warning: unknown top-level key {key!r} (ignored by Foxglove)", file=sys.stderr)
    for pid, cfg in doc["configById"].items():
        if not PANEL_ID.match(pid):
            raise LayoutProblem(f"configById: panel id {pid!r} is not of the form Type!suffix")
        if not isinstance(cfg, dict):
            raise LayoutProblem(f"configById[{pid!r}]: a panel config must be an object")
    return doc


# ------------------------------------------------------------------------------------
# Panels


@dataclass
class PathUse:
    panel: str
    what: str  # e.g. "series 2 y"
    text: str
    role: str
    label: str | None = None
    # a Plot series paired by position with this x path (rule 6)
    paired_with: str | None = None


def _is_number_literal(s: Any) -> bool:
    if not isinstance(s, str):
        return False
    try:
        float(s)
        return True
    except ValueError:
        return False


def _expect(cond: bool, msg: str) -> None:
    if not cond:
        raise LayoutProblem(msg)


def _check_pairing(pid: str, series: str, y: str, x: str) -> None:
    """Rule 6: a series paired by position with the panel's x path."""
    ym, xm = parse_path(y), parse_path(x)
    for what, mp, text in (("x axis", xm, x), (series, ym, y)):
        if mp.parts and isinstance(mp.parts[0], Filter):
            raise LayoutProblem(
                f"[{pid}] {what} {text!r} filters whole messages: Foxglove Studio 1.48 and Lichtblick "
                f"pair each series with the x axis {x!r} by position, and a filtered series has fewer "
                f"elements (error badge 'Mismatch in the number of elements'); plot an unfiltered "
                f"field instead (e.g. amplitude_rms_stable_um, NaN where unstable)")
    if ym.topic != xm.topic:
        raise LayoutProblem(
            f"[{pid}] {series} {y!r} reads {ym.topic}, the x axis {x!r} reads {xm.topic}: older "
            f"Foxglove pairs them by position, which only holds for one topic")


def panel_uses(pid: str, cfg: dict) -> tuple[list[PathUse], list[str], list[str]]:
    """Returns the message paths of a panel, the plain topics it names, and notes."""
    ptype = panel_type(pid)
    uses: list[PathUse] = []
    topics: list[str] = []
    notes: list[str] = []
    where = f"configById[{pid!r}]"
    if ptype == "Plot":
        paths = cfg.get("paths", [])
        _expect(isinstance(paths, list), f"{where}.paths must be a list")
        xval = cfg.get("xAxisVal", "timestamp")
        _expect(xval in X_AXIS_VALS, f"{where}.xAxisVal {xval!r} is not one of {sorted(X_AXIS_VALS)}")
        axis_ids = set()
        for ax in cfg.get("secondaryAxes") or []:
            _expect(isinstance(ax, dict) and isinstance(ax.get("id"), str),
                    f"{where}.secondaryAxes: each axis needs a string id")
            axis_ids.add(ax["id"])
        if xval in ("custom", "currentCustom"):
            xp = cfg.get("xAxisPath")
            has_default = isinstance(xp, dict) and isinstance(xp.get("value"), str) and xp["value"]
            every_series = paths and all(isinstance(p, dict) and p.get("xValuePath") for p in paths
                                         if not _is_number_literal(p.get("value")))
            _expect(has_default or every_series,
                    f"{where}: xAxisVal is {xval!r} (message path) but there is no xAxisPath.value "
                    f"(nor an xValuePath on every series)")
            if has_default:
                uses.append(PathUse(pid, "x axis (default)", xp["value"], "number"))
        for i, s in enumerate(paths, 1):
            sw = f"{where}.paths[{i - 1}]"
            _expect(isinstance(s, dict), f"{sw} must be an object")
            v = s.get("value")
            _expect(isinstance(v, str) and v != "", f"{sw}.value must be a non-empty message path")
            if "enabled" in s:
                _expect(isinstance(s["enabled"], bool), f"{sw}.enabled must be true or false")
            if "timestampMethod" in s:
                _expect(s["timestampMethod"] in TIMESTAMP_METHODS,
                        f"{sw}.timestampMethod {s['timestampMethod']!r} is not one of {sorted(TIMESTAMP_METHODS)}")
            if "color" in s:
                _expect(isinstance(s["color"], str) and re.fullmatch(r"#([0-9a-fA-F]{3}|[0-9a-fA-F]{6}|[0-9a-fA-F]{8})", s["color"]),
                        f"{sw}.color {s.get('color')!r} is not a #rrggbb colour")
            if "lineStyle" in s:
                _expect(s["lineStyle"] in LINE_STYLES, f"{sw}.lineStyle {s['lineStyle']!r} is not one of {sorted(LINE_STYLES)}")
            if "yAxisId" in s:
                _expect(s["yAxisId"] in axis_ids, f"{sw}.yAxisId {s['yAxisId']!r} names no entry of secondaryAxes")
            label = s.get("label")
            state = "" if s.get("enabled", True) else " (disabled)"
            if _is_number_literal(v):
                notes.append(f"series {i}{state}: reference line at {v}")
                continue
            x_default = (cfg.get("xAxisPath") or {}).get("value")
            paired = (x_default if xval == "custom" and s.get("enabled", True)
                      and isinstance(x_default, str) and x_default else None)
            uses.append(PathUse(pid, f"series {i}{state} y", v, "number", label, paired))
            if s.get("xValuePath"):
                _expect(xval in ("custom", "currentCustom"),
                        f"{sw}.xValuePath is set but xAxisVal is {xval!r}, not a message path")
                uses.append(PathUse(pid, f"series {i}{state} x", s["xValuePath"], "number"))
    elif ptype == "StateTransitions":
        paths = cfg.get("paths", [])
        _expect(isinstance(paths, list), f"{where}.paths must be a list")
        for i, s in enumerate(paths, 1):
            _expect(isinstance(s, dict) and isinstance(s.get("value"), str) and s["value"],
                    f"{where}.paths[{i - 1}].value must be a non-empty message path")
            uses.append(PathUse(pid, f"series {i}", s["value"], "scalar", s.get("label")))
    elif ptype in ("RawMessages", "Table"):
        tp = cfg.get("topicPath")
        _expect(isinstance(tp, str) and tp, f"{where}.topicPath must be a non-empty message path")
        uses.append(PathUse(pid, "topicPath", tp, "any"))
        if ptype == "RawMessages" and cfg.get("diffEnabled") and cfg.get("diffTopicPath"):
            uses.append(PathUse(pid, "diffTopicPath", cfg["diffTopicPath"], "any"))
    elif ptype in ("Indicator", "Gauge"):
        p = cfg.get("path")
        _expect(isinstance(p, str) and p, f"{where}.path must be a non-empty message path")
        uses.append(PathUse(pid, "path", p, "scalar" if ptype == "Indicator" else "number"))
    elif ptype == "RosOut":
        t = cfg.get("topicToRender")
        _expect(isinstance(t, str) and t, f"{where}.topicToRender must name the log topic")
        topics.append(t)
        lvl = cfg.get("minLogLevel")
        if lvl is not None:
            _expect(isinstance(lvl, int) and 1 <= lvl <= 5, f"{where}.minLogLevel {lvl!r} is not 1..5")
    elif ptype == "3D":
        tps = cfg.get("topics", {})
        _expect(isinstance(tps, dict), f"{where}.topics must be an object (topic -> settings)")
        for t, settings in tps.items():
            _expect(isinstance(settings, dict), f"{where}.topics[{t!r}] must be an object")
            topics.append(t)
    elif ptype == "Tab":
        pass
    else:
        notes.append(f"panel type {ptype!r} is not checked")
    return uses, topics, notes


def frame_ids(messages: list, limit: int = 5) -> set[str]:
    """Frame ids used in decoded messages (fields frame_id, parent_frame_id, child_frame_id)."""
    out: set[str] = set()

    def visit(m):
        for fd, value in m.ListFields():
            if fd.type == FieldDescriptor.TYPE_MESSAGE:
                if _is_repeated(fd):
                    for item in value:
                        visit(item)
                else:
                    visit(value)
            elif fd.name in ("frame_id", "parent_frame_id", "child_frame_id") and isinstance(value, str):
                out.add(value)

    for m in messages[:limit]:
        visit(m)
    return out


def label_check(use: PathUse, mp: MessagePath, run_info) -> str | None:
    """tmrotor: the label of a series indexing a per-node/per-bearing array names that entry."""
    if run_info is None:
        return None
    names = [p for p in mp.parts if not isinstance(p, Filter)]
    if len(names) < 2 or not isinstance(names[0], Name) or not isinstance(names[1], Slice):
        return None
    lst = RUNINFO_LISTS.get((mp.topic, names[0].name))
    sl = names[1]
    if lst is None or not sl.single or not isinstance(sl.start, int):
        return None
    entries = getattr(run_info, lst)
    k = sl.start
    if not -len(entries) <= k < len(entries):
        raise LayoutProblem(f"[{use.panel}] {use.what} {use.text!r}: index [{k}] is beyond RunInfo.{lst} "
                            f"({len(entries)} entries)")
    name = entries[k].name
    if use.label is None:
        return f"plots RunInfo.{lst}[{k}] {name!r}"
    if not re.search(r"(?<![\w#])" + re.escape(name) + r"(?![\w#])", use.label):
        raise LayoutProblem(f"[{use.panel}] {use.what} {use.text!r}: label {use.label!r} does not name the entry "
                            f"it plots: RunInfo.{lst}[{k}] is {name!r} (index = position in RunInfo.{lst})")
    return f"label names RunInfo.{lst}[{k}] {name!r}"


# ------------------------------------------------------------------------------------


def _check_readable(use: PathUse, mp: MessagePath, rec: Recording, variables: dict) -> None:
    """Rule 7: the sampled values of a Plot series do not all round to zero on the axis."""
    values = []
    for msg in rec.samples.get(mp.topic) or []:
        for v in data_walk(mp, msg, variables, honor_filters=True, stats=WalkStats()):
            if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
                values.append(float(v))
    if values and any(v != 0.0 for v in values) and max(abs(v) for v in values) < 1e-3:
        raise LayoutProblem(
            f"[{use.panel}] {use.what} {use.text!r}: every sampled value is below 0.001 in magnitude "
            f"(largest {max(abs(v) for v in values):.3g}); Foxglove rounds the y-axis ticks to three "
            f"decimals and draws a flat line: plot the field in smaller units (e.g. _um)")


def check(layout_path: str, recording_path: str, max_samples: int, labels: bool, quiet: bool,
          ignored: frozenset[str] = frozenset()) -> int:
    say = (lambda *a: None) if quiet else print
    doc = load_layout(layout_path)
    panels = all_panels(doc)
    used = {pid for pid, _ in panels}
    for pid in doc["configById"]:
        if pid not in used:
            print(f"warning: configById[{pid!r}] is used by no panel of the layout", file=sys.stderr)
    variables = doc.get("globalVariables", {})

    per_panel = []
    needed: set[str] = set()
    for pid, where in panels:
        uses, topics, notes = panel_uses(pid, doc["configById"][pid])
        kept = []
        for u in uses:
            try:
                t = parse_path(u.text).topic
            except LayoutProblem as e:
                raise LayoutProblem(f"[{u.panel}] {u.what}: {e}") from None
            if t in ignored:
                notes.append(f"{u.what} {u.text} not checked (--ignore-topic {t})")
            else:
                kept.append(u)
                needed.add(t)
        for t in topics:
            if t in ignored:
                notes.append(f"topic {t} not checked (--ignore-topic)")
        topics = [t for t in topics if t not in ignored]
        needed.update(topics)
        per_panel.append((pid, where, kept, topics, notes))
    say(f"layout {layout_path}: valid layout JSON, {len(panels)} panels "
        f"({', '.join(sorted({panel_type(p) for p, _ in panels}))})")

    rec = read_recording(recording_path, needed | {"/run_info", "/tf"}, max_samples)
    missing = sorted(t for t in needed if t not in rec.schemas)
    if missing:
        t = missing[0]
        close = difflib.get_close_matches(t, list(rec.schemas), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        users = [pid for pid, _, uses, topics, _ in per_panel
                 if t in topics or any(parse_path(u.text).topic == t for u in uses)]
        raise LayoutProblem(f"topic {t} (used by {', '.join(users)}) is not in the recording{hint} "
                            f"(topics: {', '.join(sorted(rec.schemas))})")
    say(f"recording {recording_path}: {len(rec.schemas)} topics; the layout names "
        f"{len(needed)}: " + ", ".join(f"{t} ({rec.schemas[t]}, {len(rec.samples[t])} sampled)" for t in sorted(needed)))
    run_info = rec.samples["/run_info"][0] if labels and rec.samples.get("/run_info") else None

    n_paths = 0
    for pid, where, uses, topics, notes in per_panel:
        cfg = doc["configById"][pid]
        title = cfg.get("foxglovePanelTitle")
        say(f"[{pid}]" + (f" {title!r}" if title else "") + (f"  (in {where})" if where != "layout" else ""))
        for t in topics:
            if not rec.samples.get(t):
                raise LayoutProblem(f"[{pid}] topic {t} has no messages in the recording")
            schema = rec.schemas.get(t, "")
            if panel_type(pid) == "RosOut" and schema not in LOG_SCHEMAS:
                raise LayoutProblem(f"[{pid}] topicToRender {t} carries {schema}, not a log message "
                                    f"({', '.join(sorted(LOG_SCHEMAS))})")
            say(f"  ok  topic {t} ({schema}, {rec.counts.get(t, len(rec.samples[t]))} messages)")
        if panel_type(pid) == "3D":
            follow = cfg.get("followTf")
            frames: set[str] = set()
            for t in topics:
                frames |= frame_ids(rec.samples[t])
            if follow and not topics:
                say(f"  --  followTf {follow!r} not checked (no topic of the panel is checked)")
            elif follow:
                if follow not in frames:
                    raise LayoutProblem(f"[{pid}] followTf {follow!r} is not a frame of its topics' messages "
                                        f"(frames found: {', '.join(sorted(frames)) or 'none'})")
                say(f"  ok  followTf {follow!r} is the frame_id of the messages")
                published = set()
                for t, schema in rec.schemas.items():
                    if schema == "foxglove.FrameTransform":
                        for m in rec.samples.get(t) or []:
                            published |= {m.parent_frame_id, m.child_frame_id}
                if follow not in published:
                    raise LayoutProblem(f"[{pid}] followTf {follow!r} is not published by a "
                                        f"foxglove.FrameTransform in the recording (Foxglove Studio 1.48: "
                                        f"'Frame {follow!r} not found')")
                say(f"  ok  followTf {follow!r} is published by a foxglove.FrameTransform")
        for u in uses:
            try:
                mp, r = resolve(u.text, u.role, rec, variables)
            except LayoutProblem as e:
                raise LayoutProblem(f"[{u.panel}] {u.what}: {e}") from None
            extra = list(r.notes)
            if u.paired_with:
                _check_pairing(u.panel, u.what, u.text, u.paired_with)
            if u.role == "number" and mp.modifier is None:
                _check_readable(u, mp, rec, variables)
            if labels:
                lc = label_check(u, mp, run_info)
                if lc:
                    extra.append(lc)
            label = f" {u.label!r}" if u.label else ""
            example = _fmt_value(r.example)
            fd = r.state.fd
            if fd is not None and fd.type == FieldDescriptor.TYPE_ENUM and not r.state.repeated:
                ev = fd.enum_type.values_by_number.get(r.example)
                example += f" ({ev.name})" if ev else ""
            if mp.modifier:
                example += f" before .@{mp.modifier}"
            say(f"  ok  {u.what}{label}: {u.text} -> {r.type_desc}, e.g. {example}"
                + (f"; {'; '.join(extra)}" if extra else ""))
            n_paths += 1
        for n in notes:
            say(f"  --  {n}")
    print(f"OK: {layout_path}: {len(panels)} panels, {n_paths} message paths and "
          f"{len(needed)} topics resolve on {recording_path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description="Check a Foxglove layout's topics and message paths against a tmrotor recording "
                    "(see the module docstring for the message-path grammar).")
    ap.add_argument("layout", metavar="LAYOUT", help="layout JSON (Foxglove: Layouts menu -> Export)")
    ap.add_argument("recording", metavar="RECORDING", help="MCAP recording written by tmrotor")
    ap.add_argument("--max-samples", type=int, default=500,
                    help="decoded messages per topic to resolve paths on (default 500)")
    ap.add_argument("--no-label-check", action="store_true",
                    help="do not require series labels to name the RunInfo entry they plot")
    ap.add_argument("--ignore-topic", action="append", default=[], metavar="TOPIC",
                    help="do not check what the layout shows from TOPIC (repeatable), e.g. /scene "
                         "for a recording written without it")
    ap.add_argument("-q", "--quiet", action="store_true", help="print only the verdict")
    args = ap.parse_args(argv)
    if args.max_samples < 1:
        ap.error("--max-samples must be at least 1")
    try:
        return check(args.layout, args.recording, args.max_samples, not args.no_label_check, args.quiet,
                     frozenset(args.ignore_topic))
    except LayoutProblem as e:
        print(f"FAIL: {args.layout}: {e}", file=sys.stderr)
        return 1
    except UsageProblem as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
