"""Export a tmrotor recording to a native Rerun recording (``.rrd``) with a blueprint.

Command line (console script of the package, or ``python -m tmrotor.rerun``)::

    tmrotor-rerun REC.mcap -o OUT.rrd [--scale S] [--samples 128]
    rerun OUT.rrd

Rerun's own MCAP import shows our protobuf topics as opaque structs and does not draw
``/scene`` (``foxglove.SceneUpdate``); this exporter writes what the recording means
instead. Needs the optional dependency ``rerun-sdk`` (``pip install 'tmrotor[rerun]'``).

Timelines
    ``omega_mrad_s`` (sequence): omega in mrad/s, rounded — the timeline the blueprint
    opens on, so the plots are amplitude–frequency curves over the whole omega range.
    The branch's values are drawn as points, not lines: where it folds back (a
    saddle-node pair) several points share an omega range, and lines joined in omega
    order would zig-zag between its segments.
    ``point`` (sequence): the point index along the branch, the order of continuation.

Entities (all scalars logged on both timelines)
    ``info``                                  run description (markdown), static
    ``branch/omega_rad_s``                    omega, rad/s
    ``branch/amplitude_um/<rotor>/node<id>``  RMS radial amplitude (Eq. 35), µm, points per
                                              dynamic node, a distinct colour per node
    ``branch/unstable_um/<rotor>/node<id>``   the same values at unstable points only, red
                                              crosses over the points
    ``branch/stability/spectral_radius``      largest multiplier modulus
    ``branch/stability/unstable_count``       multipliers outside the unit circle
    ``temperatures/<group>/tnode<id>``        mean temperature over the period, °C; groups:
                                              ``bearing<k>`` (thermal nodes whose name
                                              holds the bearing's name as a word), the
                                              rotor names (names starting with one), ``other``
    ``clearance/delta_v_um/bearing<k>``       radial clearance variation delta_v, µm
    ``bearing_loads/mean_n/bearing<k>``       mean radial bearing load, N
    ``thermal_forces/generation_w/bearing<k>`` friction heat generated, W
    ``rotor/shaft/<rotor>``                   the undeformed shaft axis, static
    ``rotor/orbits/<rotor>/node<id>``         the whirl orbit of each dynamic node at each
                                              point, a closed 3D line strip re-derived from
                                              ``/harmonics`` (works without ``/orbits``)
    ``log``                                   the recording's ``/log`` entries (run start,
                                              bifurcations, warnings, end status), at the
                                              point they follow

3D layout (as ``/scene``): x = axial position along the shaft (m), y = scale · (y − ȳ),
z = scale · (x − x̄), z up: each orbit about its node's mean position over the period
(the static sag is left out, so scaled orbits stay on the shaft axis). The scale is
:func:`automatic_scale` of the run unless given, the rule the recording's ``/scene``
follows (10 000 for the built-in rotor); the 3D view's title states it. LP blue, HP
orange.

A recording of ``tmrotor transient`` is exported on a ``time`` timeline (simulated
time) instead: ``transient/omega_rad_s``, ``transient/amplitude_um/<rotor>/node<id>``
(per revolution), ``transient/temperatures/<group>/tnode<id>``,
``transient/clearance_um/<bearing>``, ``transient/load_max_n/<bearing>`` and the
decimated displacements ``transient/samples_um/<rotor>/node<id>/{x,y}``, with a
blueprint of their own.

Colours: within a plot every series has its own colour from an 18-colour qualitative
palette without its reds (red marks unstable points); a bearing has the same colour in the
clearance, load and heat plots. Legends
are shown at a corner for plots of up to six series and hidden above that (hover a
series for its name), so they do not cover the data.
"""

from __future__ import annotations

import argparse
import colorsys
import math
import re
import sys
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .recording import Recording, read

try:  # optional dependency
    import rerun as rr
    import rerun.blueprint as rrb

    _IMPORT_ERROR: ImportError | None = None
except ImportError as _e:  # pragma: no cover - exercised when rerun-sdk is missing
    rr = None  # type: ignore[assignment]
    rrb = None  # type: ignore[assignment]
    _IMPORT_ERROR = _e

#: Displacement scale of the 3D orbits without bearings to size it from.
DEFAULT_SCALE = 1000.0
#: Samples per period of the 3D orbits.
DEFAULT_SAMPLES = 128
#: Plots with more series than this hide their legend.
MAX_LEGEND_SERIES = 6

_ROTOR_COLOURS = {"lp": (31, 119, 180), "hp": (255, 127, 14)}
_GREY = (128, 128, 128)
_RED = (214, 39, 40)
#: A qualitative palette: matplotlib's tab20, dark shades first, then the light ones,
#: without its reds, which mark unstable points (``_RED``).
_PALETTE = [
    (31, 119, 180), (255, 127, 14), (44, 160, 44), (148, 103, 189),
    (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207),
    (174, 199, 232), (255, 187, 120), (152, 223, 138), (197, 176, 213),
    (196, 156, 148), (247, 182, 210), (199, 199, 199), (219, 219, 141), (158, 218, 229),
]


def palette_colour(j: int) -> tuple[int, int, int]:
    """The ``j``-th colour: the palette's first, then hues spaced by the golden angle
    (a thermal group of a shaft can hold more than 18 nodes)."""
    if j < len(_PALETTE):
        return _PALETTE[j]
    k = j - len(_PALETTE)
    hue = (0.11 + 0.6180339887 * k) % 1.0
    value = 0.95 if k % 2 == 0 else 0.7
    r, g, b = colorsys.hsv_to_rgb(hue, 0.7, value)
    return (round(255 * r), round(255 * g), round(255 * b))


def automatic_scale(run_info) -> float:
    """The 3D orbits' displacement scale when none is given: the largest of 1, 2 or
    5 × 10^k that draws the largest bearing clearance at no more than 5 % of the dynamic
    nodes' axial span; :data:`DEFAULT_SCALE` without bearings or span. The rule of the
    recording's ``/scene`` (its entities carry the factor in their metadata)."""
    zs = [n.axial_position_m for n in run_info.nodes]
    clearances = [
        b.initial_clearance_m
        for b in run_info.bearings
        if math.isfinite(b.initial_clearance_m) and b.initial_clearance_m > 0
    ]
    if len(zs) < 2 or not clearances or not max(zs) > min(zs):
        return DEFAULT_SCALE
    target = 0.05 * (max(zs) - min(zs)) / max(clearances)
    decade = 10.0 ** math.floor(math.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * decade <= target:
            return max(m * decade, 1.0)
    return max(decade, 1.0)


def _require_rerun() -> None:
    if rr is None:
        raise ImportError(
            "tmrotor.rerun needs the rerun-sdk package: pip install 'tmrotor[rerun]' "
            f"(import failed: {_IMPORT_ERROR})"
        )


def _path_part(text: str, fallback: str) -> str:
    """An entity-path part: letters, digits and underscores only."""
    clean = re.sub(r"[^A-Za-z0-9_]+", "_", text).strip("_")
    return clean or fallback


def _rotor_colour(rotor: str) -> tuple[int, int, int]:
    return _ROTOR_COLOURS.get(rotor.lower(), _GREY)


def thermal_groups(rec: Recording) -> dict[str, list[int]]:
    """Positions (in RunInfo.thermal_nodes order) of the thermal nodes per group:
    ``bearing<k>`` for nodes whose name holds a bearing's name as a word (``"1# inner
    ring"``), a rotor name for nodes whose name starts with it (``"LP shaft ..."``), else
    ``other``. Groups in that order, empty ones left out."""
    run = rec.run_info
    keys = rec.bearing_columns
    rotors = []
    for n in run.nodes:
        if n.rotor and n.rotor not in rotors:
            rotors.append(n.rotor)
    groups: dict[str, list[int]] = {k: [] for k in keys}
    groups.update({_path_part(r, "rotor"): [] for r in rotors})
    groups["other"] = []
    for pos, tn in enumerate(run.thermal_nodes):
        words = tn.name.split()
        group = next((k for k, b in zip(keys, run.bearings) if b.name in words), None)
        if group is None:
            group = next(
                (_path_part(r, "rotor") for r in rotors if words and words[0] == r), "other"
            )
        groups[group].append(pos)
    return {g: v for g, v in groups.items() if v}


def _info_markdown(rec: Recording) -> str:
    info = rec.info
    b = rec.branch
    lines = [
        f"# {rec.path.name}",
        "",
        f"- written by: {info['tool_name']} {info['tool_version']}",
        f"- model: {info['model_name']} (sha256 {info['model_sha256'][:12]}…)",
        (
            f"- status: {info['status'] or 'none (the run did not finish writing)'}; "
            f"{'complete' if info['complete'] else 'INCOMPLETE'}"
        ),
        f"- points: {info['points']}",
    ]
    if len(b):
        stable = int(b["stable"].eq(True).sum())
        unstable = int(b["stable"].eq(False).sum())
        lines += [
            f"- omega: {b['omega_rad_s'].min():.4f} … {b['omega_rad_s'].max():.4f} rad/s",
            (
                f"- stability: {stable} stable, {unstable} unstable, "
                f"{len(b) - stable - unstable} not assessed"
            ),
        ]
    basis = ", ".join(f"{r}ω" for r in rec.basis)
    lines += [
        f"- basis: {basis} (period 2π·{rec.period_denominator}/ω)",
        f"- bifurcations: {len(rec.bifurcations)}",
        "- orbits in 3D: x = axial position (m), y = scale·y, z = scale·x (vertical up)",
    ]
    for title, items in (("Notes", info["notes"]), ("Warnings", info["warnings"])):
        if items:
            lines += ["", f"## {title}", ""] + [f"- {t}" for t in items]
    if rec.run_info.settings_toml:
        lines += ["", "## Settings", "", "```toml", rec.run_info.settings_toml.rstrip(), "```"]
    return "\n".join(lines) + "\n"


def _log_point(time_ns: int, first: int, last: int) -> int:
    """The point a /log entry follows, from the branch clock (point i at (i+1) ms)."""
    return min(max(math.floor(time_ns / 1e6) - 1, first), last)


def export(
    recording: Recording | str | Path,
    out: str | Path,
    *,
    scale: float | None = None,
    samples: int = DEFAULT_SAMPLES,
    application_id: str = "tmrotor",
) -> Path:
    """Writes ``recording`` (a :class:`~tmrotor.Recording` or the path of an MCAP file)
    as a Rerun recording with a default blueprint to ``out`` (``.rrd``); returns ``out``.

    ``scale`` multiplies the displacements of the 3D whirl orbits (default
    :func:`automatic_scale`); ``samples`` is the number of samples per period of each
    orbit. See the module docstring for the entities and timelines."""
    _require_rerun()
    rec = recording if isinstance(recording, Recording) else read(recording)
    out = Path(out)
    run = rec.run_info
    if scale is None:
        scale = automatic_scale(run)
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale {scale}: must be positive and finite")
    if rec.transient_info is not None:
        return _export_transient(rec, out, application_id)
    b = rec.branch
    points = np.asarray(b["index"], dtype=np.int64)
    omega = np.asarray(b["omega_rad_s"], dtype=float)
    omega_seq = np.round(omega * 1000.0).astype(np.int64)

    rotor_of = [_path_part(n.rotor, "shaft") for n in run.nodes]
    rotors = list(dict.fromkeys(rotor_of))
    groups = thermal_groups(rec)
    bearing_keys = rec.bearing_columns

    stream = rr.RecordingStream(application_id, recording_id=uuid.uuid4())
    stream.save(out, default_blueprint=_blueprint(rec, rotors, groups, scale))
    stream.set_log_time_enabled(False)  # wall-clock time means nothing here
    if hasattr(stream, "send_recording_name"):
        stream.send_recording_name(rec.path.name)

    def series(path: str, values: Any, mask: Any = None) -> None:
        v = np.asarray(values, dtype=float)
        keep = np.isfinite(v) if mask is None else (np.asarray(mask, dtype=bool) & np.isfinite(v))
        if not keep.any():
            return
        stream.send_columns(
            path,
            indexes=[
                rr.TimeColumn("point", sequence=points[keep]),
                rr.TimeColumn("omega_mrad_s", sequence=omega_seq[keep]),
            ],
            columns=rr.Scalars.columns(scalars=v[keep]),
        )

    stream.log(
        "info", rr.TextDocument(_info_markdown(rec), media_type=rr.MediaType.MARKDOWN), static=True
    )

    # the branch
    stream.log(
        "branch/omega_rad_s",
        rr.SeriesPoints(names="ω (rad/s)", colors=[80, 80, 80], marker_sizes=1.5),
        static=True,
    )
    series("branch/omega_rad_s", omega)
    unstable = np.asarray(b["stable"].eq(False).fillna(False), dtype=bool)
    for rotor in rotors:
        members = [i for i, r in enumerate(rotor_of) if r == rotor]
        for j, i in enumerate(members):
            n = run.nodes[i]
            key = f"node{n.id}"
            colour = palette_colour(j)
            amp_um = np.asarray(b[f"amp_rms_{key}_m"], dtype=float) * 1e6
            label = f"node {n.id}" + (f" ({n.name})" if n.name and n.name != f"node {n.id}" else "")
            stream.log(
                f"branch/amplitude_um/{rotor}/{key}",
                rr.SeriesPoints(
                    names=label,
                    colors=colour,
                    markers=rr.components.MarkerShape.Circle,
                    marker_sizes=1.5,
                ),
                static=True,
            )
            series(f"branch/amplitude_um/{rotor}/{key}", amp_um)
            if unstable.any():
                stream.log(
                    f"branch/unstable_um/{rotor}/{key}",
                    rr.SeriesPoints(
                        names=f"{label} unstable",
                        colors=_RED,
                        markers=rr.components.MarkerShape.Cross,
                        marker_sizes=3.0,
                    ),
                    static=True,
                )
                series(f"branch/unstable_um/{rotor}/{key}", amp_um, mask=unstable)
    stream.log(
        "branch/stability/spectral_radius",
        rr.SeriesPoints(names="spectral radius", colors=[44, 160, 44], marker_sizes=1.5),
        static=True,
    )
    series("branch/stability/spectral_radius", b["spectral_radius"].to_numpy(dtype=float))
    stream.log(
        "branch/stability/unstable_count",
        rr.SeriesPoints(names="multipliers outside the unit circle", colors=_RED, marker_sizes=1.5),
        static=True,
    )
    series(
        "branch/stability/unstable_count",
        b["unstable_count"].astype("Float64").to_numpy(dtype=float, na_value=np.nan),
    )

    # temperatures, bearings
    temps = rec.temperatures
    for group, members in groups.items():
        for j, pos in enumerate(members):
            tn = run.thermal_nodes[pos]
            path = f"temperatures/{group}/tnode{tn.id}"
            stream.log(
                path,
                rr.SeriesPoints(
                    names=tn.name or f"tnode{tn.id}", colors=palette_colour(j), marker_sizes=1.5
                ),
                static=True,
            )
            series(path, temps[f"tnode{tn.id}_mean_c"])
    for k, (key, bearing) in enumerate(zip(bearing_keys, run.bearings)):
        for path, values, label in (
            (f"clearance/delta_v_um/{key}", rec.clearances[f"{key}_delta_v_m"] * 1e6, "δv"),
            (f"bearing_loads/mean_n/{key}", rec.bearing_loads[f"{key}_mean_n"], "mean load"),
            (
                f"thermal_forces/generation_w/{key}",
                rec.thermal_forces[f"{key}_generation_w"],
                "friction heat",
            ),
        ):
            stream.log(
                path,
                rr.SeriesPoints(
                    names=f"{label} {bearing.name}", colors=palette_colour(k), marker_sizes=1.5
                ),
                static=True,
            )
            series(path, values)

    # the rotor in 3D
    stream.log("rotor", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for rotor in rotors:
        z = [run.nodes[i].axial_position_m for i, r in enumerate(rotor_of) if r == rotor]
        colour = _rotor_colour(run.nodes[rotor_of.index(rotor)].rotor)
        if len(z) > 1 and max(z) > min(z):
            stream.log(
                f"rotor/shaft/{rotor}",
                rr.LineStrips3D(
                    [[[min(z), 0.0, 0.0], [max(z), 0.0, 0.0]]],
                    colors=colour,
                    radii=rr.Radius.ui_points(1.0),
                ),
                static=True,
            )
    for row, point in enumerate(points):
        stream.set_time("point", sequence=int(point))
        stream.set_time("omega_mrad_s", sequence=int(omega_seq[row]))
        try:
            orbit = rec.orbit(int(point), samples=samples)
        except ValueError:
            continue  # no /harmonics for this point
        for i, n in enumerate(run.nodes):
            x = orbit[f"node{n.id}_x_m"].to_numpy()
            y = orbit[f"node{n.id}_y_m"].to_numpy()
            x, y = x - x.mean(), y - y.mean()  # about the mean position
            strip = np.column_stack([np.full(len(x), n.axial_position_m), scale * y, scale * x])
            strip = np.vstack([strip, strip[:1]])  # closed
            stream.log(
                f"rotor/orbits/{rotor_of[i]}/node{n.id}",
                rr.LineStrips3D(
                    [strip],
                    colors=_rotor_colour(n.rotor),
                    radii=rr.Radius.ui_points(1.5),
                    labels=f"node {n.id}",
                    show_labels=False,
                ),
            )

    # events
    if len(points):
        first, last = int(points.min()), int(points.max())
        by_point = dict(zip(points.tolist(), omega_seq.tolist()))
        for e in rec.log_entries:
            p = _log_point(e.time_ns, first, last)
            stream.set_time("point", sequence=p)
            stream.set_time("omega_mrad_s", sequence=int(by_point.get(p, omega_seq[0])))
            level = {"WARNING": "WARN", "FATAL": "CRITICAL"}.get(e.level, e.level)
            stream.log("log", rr.TextLog(e.message, level=level))

    stream.flush()
    stream.disconnect()
    return out


def _export_transient(rec: Recording, out: Path, application_id: str) -> Path:
    """A recording of ``tmrotor transient``: everything on a ``time`` timeline (the
    simulated time, s), per revolution the RMS amplitude of every node, the speed, the
    temperatures, clearances and largest bearing loads, and the decimated displacement
    samples of every node; the blueprint opens on them with the whole run in view."""
    run = rec.run_info
    revs = rec.revolutions
    samples = rec.samples
    rotor_of = [_path_part(n.rotor, "shaft") for n in run.nodes]
    rotors = list(dict.fromkeys(rotor_of))
    groups = thermal_groups(rec)
    keys = rec.bearing_columns

    stream = rr.RecordingStream(application_id, recording_id=uuid.uuid4())
    stream.save(out, default_blueprint=_transient_blueprint(rec, rotors, groups))
    stream.set_log_time_enabled(False)
    if hasattr(stream, "send_recording_name"):
        stream.send_recording_name(rec.path.name)

    def series(path: str, times: Any, values: Any, style: Any) -> None:
        v = np.asarray(values, dtype=float)
        t = np.asarray(times, dtype=float)
        keep = np.isfinite(v) & np.isfinite(t)
        stream.log(path, style, static=True)
        if keep.any():
            stream.send_columns(
                path,
                indexes=[rr.TimeColumn("time", duration=t[keep])],
                columns=rr.Scalars.columns(scalars=v[keep]),
            )

    def lines(name: str, j: int) -> Any:
        return rr.SeriesLines(names=name, colors=palette_colour(j))

    info = rec.transient_info or {}
    text = _info_markdown(rec) + "\n## Transient run\n\n" + "".join(
        f"- {k}: {v}\n" for k, v in info.items()
    )
    stream.log("info", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)
    t_rev = revs["time_s"]
    series("transient/omega_rad_s", t_rev, revs["omega_rad_s"], lines("ω (rad/s)", 7))
    for rotor in rotors:
        members = [i for i, r in enumerate(rotor_of) if r == rotor]
        for j, i in enumerate(members):
            n = run.nodes[i]
            col = f"amp_rms_node{n.id}_m"
            if col in revs:
                series(
                    f"transient/amplitude_um/{rotor}/node{n.id}",
                    t_rev,
                    revs[col] * 1e6,
                    lines(f"node {n.id}", j),
                )
    for g, members in groups.items():
        for j, pos in enumerate(members):
            tn = run.thermal_nodes[pos]
            col = f"tnode{tn.id}_c"
            if col in revs:
                series(
                    f"transient/temperatures/{g}/tnode{tn.id}",
                    t_rev,
                    revs[col],
                    lines(tn.name or f"tnode{tn.id}", j),
                )
    for k, (key, bearing) in enumerate(zip(keys, run.bearings)):
        for path, col, scale_by, label in (
            ("clearance_um", f"{key}_clearance_m", 1e6, "effective clearance"),
            ("load_max_n", f"{key}_load_max_n", 1.0, "largest load"),
        ):
            if col in revs:
                series(
                    f"transient/{path}/{key}",
                    t_rev,
                    revs[col] * scale_by,
                    lines(f"{label} {bearing.name}", k),
                )
    if len(samples):
        t_s = samples["time_s"]
        for i, n in enumerate(run.nodes):
            for axis, j in (("x", 0), ("y", 1)):
                col = f"node{n.id}_{axis}_m"
                if col in samples:
                    series(
                        f"transient/samples_um/{rotor_of[i]}/node{n.id}/{axis}",
                        t_s,
                        samples[col] * 1e6,
                        lines(f"node {n.id} {axis}", j),
                    )
    for e in rec.log_entries:
        stream.set_time("time", duration=e.time_ns * 1e-9)
        level = {"WARNING": "WARN", "FATAL": "CRITICAL"}.get(e.level, e.level)
        stream.log("log", rr.TextLog(e.message, level=level))
    stream.flush()
    stream.disconnect()
    return out


def _transient_blueprint(rec: Recording, rotors: list[str], groups: dict[str, list[int]]):
    run = rec.run_info
    rotor_of = [_path_part(n.rotor, "shaft") for n in run.nodes]

    def plot(name: str, origin: str, n_series: int):
        return _plot(name, origin, n_series, timelines=("time",))

    amplitude = [
        plot(
            f"RMS amplitude {r} (µm)",
            f"/transient/amplitude_um/{r}",
            sum(1 for x in rotor_of if x == r),
        )
        for r in rotors
    ]
    nb = len(rec.bearing_columns)
    right: list[Any] = [plot("ω (rad/s)", "/transient/omega_rad_s", 1)]
    if groups:
        right.append(
            rrb.Tabs(
                *[
                    plot(f"T {g} (°C)", f"/transient/temperatures/{g}", len(v))
                    for g, v in groups.items()
                ],
                name="temperatures",
            )
        )
    if nb:
        right.append(
            rrb.Tabs(
                plot("effective clearance (µm)", "/transient/clearance_um", nb),
                plot("largest bearing load (N)", "/transient/load_max_n", nb),
                name="bearings",
            )
        )
    right.append(_run_tabs())
    samples = rrb.Tabs(
        *[
            plot(f"displacement samples {r} (µm)", f"/transient/samples_um/{r}", 99)
            for r in rotors
        ],
        name="samples",
    )
    return rrb.Blueprint(
        rrb.Horizontal(rrb.Vertical(*amplitude, samples), rrb.Vertical(*right)),
        rrb.TimePanel(timeline="time"),
        collapse_panels=False,
    )


def _run_tabs():
    """The run's description and its log, as tabs."""
    return rrb.Tabs(
        rrb.TextDocumentView(name="run", origin="/info"),
        rrb.TextLogView(name="log", origin="/log"),
        name="run",
    )


def _plot(
    name: str,
    origin: str,
    n_series: int,
    contents: Any = None,
    timelines: Sequence[str] = ("omega_mrad_s", "point"),
):
    """A time series view over the whole of each of ``timelines``, its legend at a corner
    or, for more than :data:`MAX_LEGEND_SERIES` series, hidden."""
    everything = [
        rrb.VisibleTimeRange(
            timeline,
            start=rrb.TimeRangeBoundary.infinite(),
            end=rrb.TimeRangeBoundary.infinite(),
        )
        for timeline in timelines
    ]
    legend = rrb.PlotLegend(
        corner=rrb.Corner2D.RightBottom, visible=n_series <= MAX_LEGEND_SERIES
    )
    kwargs: dict[str, Any] = {"contents": contents} if contents is not None else {}
    # the data of the whole timeline (time_ranges) and an x axis that shows all of it
    # (without axis_x the viewer shows about 1000 steps of the timeline around its cursor:
    # 1 rad/s on omega_mrad_s, seen in Rerun 0.41's own screenshot)
    whole = rrb.TimeRange(
        start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.infinite()
    )
    return rrb.TimeSeriesView(
        name=name if n_series <= MAX_LEGEND_SERIES else f"{name} (hover for names)",
        origin=origin,
        time_ranges=everything,
        axis_x=rrb.TimeAxis(view_range=whole),
        plot_legend=legend,
        **kwargs,
    )


def _blueprint(rec: Recording, rotors: list[str], groups: dict[str, list[int]], scale: float):
    run = rec.run_info
    rotor_of = [_path_part(n.rotor, "shaft") for n in run.nodes]
    series = []
    for rotor in rotors:
        n_nodes = sum(1 for r in rotor_of if r == rotor)
        series.append(
            _plot(
                f"RMS amplitude {rotor} (µm); red: unstable",
                "/branch",
                n_nodes,
                contents=[f"/branch/amplitude_um/{rotor}/**", f"/branch/unstable_um/{rotor}/**"],
            )
        )
    branch = rrb.Vertical(
        *series,
        rrb.Horizontal(
            _plot("ω (rad/s)", "/branch/omega_rad_s", 1),
            _plot("stability", "/branch/stability", 2),
        ),
        name="branch",
    )
    right: list[Any] = [
        rrb.Spatial3DView(
            name=f"whirl orbits about their mean, displacements ×{scale:g}", origin="/rotor"
        )
    ]
    if groups:
        right.append(
            rrb.Tabs(
                *[_plot(f"T {g} (°C)", f"/temperatures/{g}", len(v)) for g, v in groups.items()],
                name="temperatures",
            )
        )
    bottom: list[Any] = []
    if rec.bearing_columns:
        nb = len(rec.bearing_columns)
        bottom.append(
            rrb.Tabs(
                _plot("δv (µm)", "/clearance/delta_v_um", nb),
                _plot("mean bearing load (N)", "/bearing_loads/mean_n", nb),
                _plot("friction heat (W)", "/thermal_forces/generation_w", nb),
                name="bearings",
            )
        )
    bottom.append(_run_tabs())
    right.append(rrb.Horizontal(*bottom))
    return rrb.Blueprint(
        rrb.Horizontal(branch, rrb.Vertical(*right, name="rotor")),
        rrb.TimePanel(timeline="omega_mrad_s"),
        collapse_panels=False,
    )


def _default_output(path: Path) -> Path:
    name = path.name.removesuffix(".partial")
    return path.with_name(Path(name).with_suffix(".rrd").name)


def main(argv: Sequence[str] | None = None) -> int:
    """``tmrotor-rerun REC.mcap -o OUT.rrd``: exit status 0 on success, 1 when the
    recording cannot be read or rerun-sdk is missing, 2 for usage errors."""
    parser = argparse.ArgumentParser(
        prog="tmrotor-rerun",
        description="Export a tmrotor recording (MCAP) to a Rerun recording (.rrd) with a "
        "blueprint: the branch, node temperatures, clearances and the whirl orbits in 3D.",
    )
    parser.add_argument("recording", type=Path, help="tmrotor recording (.mcap or .mcap.partial)")
    parser.add_argument(
        "-o", "--output", type=Path, help="output .rrd (default: the recording's name with .rrd)"
    )
    parser.add_argument(
        "--scale",
        type=float,
        default=None,
        help="displacement scale of the 3D orbits (default: the recording's own, the "
        "largest 1, 2 or 5 x 10^k that draws the largest bearing clearance at 5 %% of the "
        f"rotor's length; {DEFAULT_SCALE:g} without bearings)",
    )
    parser.add_argument(
        "--samples",
        type=int,
        default=DEFAULT_SAMPLES,
        help=f"samples per period of each orbit (default {DEFAULT_SAMPLES})",
    )
    args = parser.parse_args(argv)
    if args.samples < 2:
        parser.error("--samples must be at least 2")
    if args.scale is not None and not (math.isfinite(args.scale) and args.scale > 0):
        parser.error(f"--scale {args.scale}: must be positive and finite")
    try:
        _require_rerun()
        rec = read(args.recording)
    except (ImportError, OSError, ValueError) as e:
        print(f"tmrotor-rerun: error: {e}", file=sys.stderr)
        return 1
    out = args.output or _default_output(args.recording)
    export(rec, out, scale=args.scale, samples=args.samples)
    state = "complete" if rec.info["complete"] else "INCOMPLETE: " + "; ".join(rec.info["notes"])
    what = (
        f"{len(rec.revolutions)} revolutions"
        if rec.transient_info is not None
        else f"{len(rec.points)} points"
    )
    print(f"wrote {out} ({what}; recording {state})")
    print(f"open it with: rerun {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
