"""Export a tmrotor recording to a native Rerun recording (``.rrd``) with a blueprint.

Command line (console script of the package, or ``python -m tmrotor.rerun``)::

    tmrotor-rerun REC.mcap -o OUT.rrd [--scale 1000] [--samples 128]
    rerun OUT.rrd

Rerun's own MCAP import shows our protobuf topics as opaque structs and does not draw
``/scene`` (``foxglove.SceneUpdate``); this exporter writes what the recording means
instead. Needs the optional dependency ``rerun-sdk`` (``pip install 'tmrotor[rerun]'``).

Timelines
    ``point`` (sequence): the point index along the branch — the default timeline.
    ``omega_mrad_s`` (sequence): omega in mrad/s, rounded. Select it in the time panel to
    see the amplitude–frequency curves against omega; where the branch folds back (a
    saddle-node pair) several points share an omega range and the lines there zig-zag
    between the branch's segments, so the ``point`` timeline is the faithful one.

Entities (all scalars logged on both timelines)
    ``info``                                  run description (markdown), static
    ``branch/omega_rad_s``                    omega, rad/s
    ``branch/amplitude_um/<rotor>/node<id>``  RMS radial amplitude (Eq. 35), µm, a line per
                                              dynamic node, shades of the rotor's colour
    ``branch/unstable_um/<rotor>/node<id>``   the same values at unstable points only, red
                                              crosses over the lines
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

3D layout (as ``/scene``): x = axial position along the shaft (m), y = scale · horizontal
displacement y, z = scale · vertical displacement x, z up; scale 1000 by default, so 1 µm
of whirl is drawn as 1 mm. LP blue, HP orange.
"""

from __future__ import annotations

import argparse
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

#: Displacement scale of the 3D orbits (as the recording's /scene).
DEFAULT_SCALE = 1000.0
#: Samples per period of the 3D orbits.
DEFAULT_SAMPLES = 128

_ROTOR_COLOURS = {"lp": (31, 119, 180), "hp": (255, 127, 14)}
_GREY = (128, 128, 128)
_RED = (214, 39, 40)


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


def _shade(base: tuple[int, int, int], j: int, n: int) -> tuple[int, int, int]:
    """The ``j``-th of ``n`` shades of ``base``, from darker to lighter."""
    f = 0.0 if n <= 1 else j / (n - 1)
    dark = np.array(base) * 0.55
    light = np.array(base) + 0.6 * (255 - np.array(base))
    c = dark + f * (light - dark)
    return (int(c[0]), int(c[1]), int(c[2]))


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
    scale: float = DEFAULT_SCALE,
    samples: int = DEFAULT_SAMPLES,
    application_id: str = "tmrotor",
) -> Path:
    """Writes ``recording`` (a :class:`~tmrotor.Recording` or the path of an MCAP file)
    as a Rerun recording with a default blueprint to ``out`` (``.rrd``); returns ``out``.

    ``scale`` multiplies the displacements of the 3D whirl orbits; ``samples`` is the
    number of samples per period of each orbit. See the module docstring for the entities
    and timelines."""
    _require_rerun()
    rec = recording if isinstance(recording, Recording) else read(recording)
    out = Path(out)
    run = rec.run_info
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
        "branch/omega_rad_s", rr.SeriesLines(names="ω (rad/s)", colors=[80, 80, 80]), static=True
    )
    series("branch/omega_rad_s", omega)
    unstable = np.asarray(b["stable"].eq(False).fillna(False), dtype=bool)
    for rotor in rotors:
        members = [i for i, r in enumerate(rotor_of) if r == rotor]
        for j, i in enumerate(members):
            n = run.nodes[i]
            key = f"node{n.id}"
            colour = _shade(_rotor_colour(n.rotor), j, len(members))
            amp_um = np.asarray(b[f"amp_rms_{key}_m"], dtype=float) * 1e6
            label = f"node {n.id}" + (f" ({n.name})" if n.name and n.name != f"node {n.id}" else "")
            stream.log(
                f"branch/amplitude_um/{rotor}/{key}",
                rr.SeriesLines(names=label, colors=colour),
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
                        marker_sizes=4.0,
                    ),
                    static=True,
                )
                series(f"branch/unstable_um/{rotor}/{key}", amp_um, mask=unstable)
    stream.log(
        "branch/stability/spectral_radius",
        rr.SeriesLines(names="spectral radius", colors=[44, 160, 44]),
        static=True,
    )
    series("branch/stability/spectral_radius", b["spectral_radius"].to_numpy(dtype=float))
    stream.log(
        "branch/stability/unstable_count",
        rr.SeriesLines(names="multipliers outside the unit circle", colors=_RED),
        static=True,
    )
    series(
        "branch/stability/unstable_count",
        b["unstable_count"].astype("Float64").to_numpy(dtype=float, na_value=np.nan),
    )

    # temperatures, bearings
    temps = rec.temperatures
    for group, members in groups.items():
        for pos in members:
            tn = run.thermal_nodes[pos]
            path = f"temperatures/{group}/tnode{tn.id}"
            stream.log(path, rr.SeriesLines(names=tn.name or f"tnode{tn.id}"), static=True)
            series(path, temps[f"tnode{tn.id}_mean_c"])
    for key, bearing in zip(bearing_keys, run.bearings):
        for path, values, label in (
            (f"clearance/delta_v_um/{key}", rec.clearances[f"{key}_delta_v_m"] * 1e6, "δv"),
            (f"bearing_loads/mean_n/{key}", rec.bearing_loads[f"{key}_mean_n"], "mean load"),
            (
                f"thermal_forces/generation_w/{key}",
                rec.thermal_forces[f"{key}_generation_w"],
                "friction heat",
            ),
        ):
            stream.log(path, rr.SeriesLines(names=f"{label} {bearing.name}"), static=True)
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


def _blueprint(rec: Recording, rotors: list[str], groups: dict[str, list[int]], scale: float):
    series = []
    for rotor in rotors:
        series.append(
            rrb.TimeSeriesView(
                name=f"RMS amplitude {rotor} (µm); red: unstable",
                origin="/branch",
                contents=[f"/branch/amplitude_um/{rotor}/**", f"/branch/unstable_um/{rotor}/**"],
            )
        )
    branch = rrb.Vertical(
        *series,
        rrb.Horizontal(
            rrb.TimeSeriesView(name="ω (rad/s)", origin="/branch/omega_rad_s"),
            rrb.TimeSeriesView(name="stability", origin="/branch/stability"),
        ),
        name="branch",
    )
    right: list[Any] = [
        rrb.Spatial3DView(name=f"whirl orbits (displacements ×{scale:g})", origin="/rotor")
    ]
    if groups:
        right.append(
            rrb.Tabs(
                *[
                    rrb.TimeSeriesView(name=f"T {g} (°C)", origin=f"/temperatures/{g}")
                    for g in groups
                ],
                name="temperatures",
            )
        )
    bottom: list[Any] = []
    if rec.bearing_columns:
        bottom.append(
            rrb.Tabs(
                rrb.TimeSeriesView(name="δv (µm)", origin="/clearance/delta_v_um"),
                rrb.TimeSeriesView(name="mean bearing load (N)", origin="/bearing_loads/mean_n"),
                rrb.TimeSeriesView(name="friction heat (W)", origin="/thermal_forces/generation_w"),
                name="bearings",
            )
        )
    bottom.append(
        rrb.Tabs(
            rrb.TextDocumentView(name="run", origin="/info"),
            rrb.TextLogView(name="log", origin="/log"),
            name="run",
        )
    )
    right.append(rrb.Horizontal(*bottom))
    return rrb.Blueprint(
        rrb.Horizontal(branch, rrb.Vertical(*right, name="rotor")),
        rrb.TimePanel(timeline="point"),
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
        default=DEFAULT_SCALE,
        help=f"displacement scale of the 3D orbits (default {DEFAULT_SCALE:g})",
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
    try:
        _require_rerun()
        rec = read(args.recording)
    except (ImportError, OSError, ValueError) as e:
        print(f"tmrotor-rerun: error: {e}", file=sys.stderr)
        return 1
    out = args.output or _default_output(args.recording)
    export(rec, out, scale=args.scale, samples=args.samples)
    state = "complete" if rec.info["complete"] else "INCOMPLETE: " + "; ".join(rec.info["notes"])
    print(f"wrote {out} ({len(rec.points)} points; recording {state})")
    print(f"open it with: rerun {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
