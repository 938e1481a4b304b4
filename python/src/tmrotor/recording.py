"""A tmrotor recording read into pandas DataFrames: :func:`read` and :class:`Recording`.

Tables follow the one table convention of the project (the same tables ``replay export``
writes as CSV files):

* column names are lower-case ``[a-z0-9_]`` with the unit as the last part: ``_m``,
  ``_rad_s``, ``_s``, ``_c`` (degrees Celsius), ``_n``, ``_w``, ``_per_s``; dimensionless
  quantities have no unit part. Temperatures are in °C, everything else SI;
* entities in column names: dynamic node 8 -> ``node8``, thermal node 58 -> ``tnode58``,
  bearing ``"1#"`` -> ``bearing1`` (:func:`bearing_keys`);
* every per-point table starts with ``index`` (point index along the branch) and
  ``omega_rad_s`` and has one row per complete point (a point is complete when its
  ``/summary`` message was read), in index order;
* a value the recording does not hold is missing (NaN / ``<NA>``), as an empty CSV cell;
  booleans are the nullable ``boolean`` dtype, counts the nullable ``Int64`` dtype;
* bifurcation types are ``saddle_node``, ``period_doubling``, ``neimark_sacker``.
"""

from __future__ import annotations

import hashlib
import math
import os
import tomllib
from fractions import Fraction
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ._scan import (
    AUDIT_LOG_NAME,
    METADATA_STATUS,
    LogEntry,
    RecordingError,
    Scan,
    scan,
)

#: Names of the convention tables, in the order ``replay export`` writes them.
TABLES = (
    "branch",
    "temperatures",
    "clearances",
    "bearing_loads",
    "thermal_forces",
    "multipliers",
    "slow_exponents",
    "bifurcations",
    "nodes",
)

_BIFURCATION_KEYS = {1: "saddle_node", 2: "period_doubling", 3: "neimark_sacker"}
_STABILITY = {1: True, 2: False}  # 0 = not assessed
_TRUNCATION_OUTCOMES = {1: "converged", 2: "moved", 3: "vanished", 4: "failed"}
_TRUNCATION_VERDICTS = {1: "holds", 2: "moved", 3: "vanished", 4: "unchecked", 5: "unsettled"}


def node_key(node_id: int) -> str:
    """Column prefix of dynamic node ``node_id``: ``node8``."""
    return f"node{node_id}"


def thermal_node_key(node_id: int) -> str:
    """Column prefix of thermal node ``node_id``: ``tnode58``."""
    return f"tnode{node_id}"


def bearing_keys(names: list[str]) -> list[str]:
    """Column prefixes of bearings named ``names`` (in RunInfo order): ``bearing`` followed
    by the name's ASCII letters and digits, lower-cased (``"1#"`` -> ``bearing1``); where
    that leaves nothing or repeats an earlier key, ``bearing_<index from 0>``."""
    keys: list[str] = []
    for i, name in enumerate(names):
        clean = "".join(c for c in name if c.isascii() and c.isalnum()).lower()
        key = f"bearing{clean}"
        keys.append(f"bearing_{i}" if not clean or key in keys else key)
    return keys


def read(path: str | os.PathLike[str]) -> Recording:
    """Reads the tmrotor recording (MCAP file) at ``path``.

    A file cut short (a killed run, or a ``.partial`` file still being written) is read up
    to the cut: every complete point is kept, ``info["complete"]`` is False and
    ``info["notes"]`` says what was missing. When ``path`` does not exist but
    ``path + ".partial"`` does (a run still going, or killed), that file is read, with a
    note.

    Raises :class:`RecordingError` when the file is not MCAP, is damaged (bad chunk CRC,
    undecodable message) or holds no tmrotor run; ``OSError`` subclasses come through for
    files that cannot be opened.
    """
    p = Path(path)
    notes: list[str] = []
    if not p.exists():
        partial = p.with_name(p.name + ".partial")
        if partial.is_file():
            notes.append(
                f"{p.name} does not exist; read {partial.name}, the file of a run still "
                "going or killed"
            )
            p = partial
    if p.exists() and not p.is_file():
        raise RecordingError(
            str(p), "not_mcap", "it is not a regular file; a recording is a regular .mcap file"
        )
    data = p.read_bytes()
    return Recording(p, scan(data, str(p)), notes)


def _is_ns(b: Any) -> bool:
    """Whether a ``/bifurcations`` message carries a Neimark–Sacker point's modulation."""
    return float(getattr(b, "angle_rad", 0.0)) > 0.0


def _ns_value(b: Any, v: float) -> float:
    """A Neimark–Sacker field's value, NaN for the other kinds (and old recordings)."""
    return float(v) if _is_ns(b) else np.nan


class Recording:
    """A recording read back. Build it with :func:`read`.

    Attributes
    ----------
    path : pathlib.Path
        The file read.
    info : dict
        ``tool_name``, ``tool_version``, ``model_name``, ``model_sha256``, ``parameter``,
        ``complete`` (bool: the file ends properly — data end, footer, end magic — and has
        its end status), ``notes`` (list of str: what was missing or skipped), ``points``
        (int: complete points), and also ``status`` (``"completed"``, ``"interrupted"``,
        ``"failed: <reason>"``, or None when the run did not finish writing) and
        ``warnings`` (list of str: the sweep's warnings about the branch).
    settings : dict
        The solver and study settings, parsed with :mod:`tomllib` from
        ``RunInfo.settings_toml``.
    model_text : str
        The model file text (the attachment named ``RunInfo.model_name``); empty, with a
        note, when the attachment is missing.
    run_info : tmrotor.v1.RunInfo
        The decoded ``/run_info`` message.
    basis : list[fractions.Fraction]
        The harmonics ``nu_h`` (h = 1..H) of the basis as multiples of omega.
    period_denominator : int
        ``q``, the least common multiple of the denominators of the basis: the response
        has the period ``2 pi q / omega``.
    metadata : dict[str, dict[str, str]]
        MCAP metadata records by name (``tmrotor.run``, ``tmrotor.settings``,
        ``tmrotor.status``).
    attachments : dict[str, bytes]
        MCAP attachments by name (the model file, ``settings.toml``).
    topics : dict[str, dict]
        Per topic: ``schema`` name and ``messages`` count (from the scan, including
        messages of incomplete points).
    log_entries : list[LogEntry]
        Every ``/log`` message (time on the branch clock, level, logger name, text).
    points : list[int]
        Indices of the complete points, ascending.
    node_columns, thermal_node_columns, bearing_columns : list[str]
        Column prefixes (``node8``, ``tnode58``, ``bearing1``) in RunInfo order.

    DataFrames (built on first access; see ``python/README.md`` for every column):
    :attr:`branch`, :attr:`temperatures`, :attr:`clearances`, :attr:`bearing_loads`,
    :attr:`thermal_forces`, :attr:`multipliers`, :attr:`slow_exponents`,
    :attr:`bifurcations`, :attr:`nodes`, :attr:`harmonics`. Time histories of one point:
    :meth:`orbit` (re-derived from ``/harmonics``), :meth:`recorded_orbit` (the stored
    ``/orbits`` samples).
    """

    def __init__(self, path: Path, s: Scan, notes: list[str] | None = None):
        self.path = Path(path)
        self._scan = s
        notes = list(notes or [])
        run = s.run_info
        self.run_info = run

        self.attachments: dict[str, bytes] = dict(s.attachments)
        self.metadata: dict[str, dict[str, str]] = dict(s.metadata)
        self.topics: dict[str, dict[str, Any]] = {k: dict(v) for k, v in s.topics.items()}
        self.log_entries: list[LogEntry] = list(s.log)

        # basis
        self.basis: list[Fraction] = [Fraction(r.num, r.den) for r in run.harmonics]
        if not self.basis or any(r.num == 0 or r.den == 0 for r in run.harmonics):
            raise RecordingError(str(path), "corrupt", "/run_info: invalid harmonic basis")
        self.period_denominator: int = math.lcm(*(int(r.den) for r in run.harmonics))
        self._nu = np.array([float(r.num) / float(r.den) for r in run.harmonics])
        self._n_coeffs = 1 + 2 * len(self.basis)
        #: branch number -> its basis as ``Ratio`` messages (branch 0: the run's); the
        #: branches beside the run's own come from ``/branches``
        self._branch_harmonics: dict[int, list[Any]] = {0: list(run.harmonics)}
        for b in s.branches:
            self._branch_harmonics[int(b.branch)] = list(b.harmonics)
        #: column prefixes of the dynamic nodes, thermal nodes and bearings, in RunInfo order
        self.node_columns: list[str] = [node_key(n.id) for n in run.nodes]
        self.thermal_node_columns: list[str] = [thermal_node_key(n.id) for n in run.thermal_nodes]
        self.bearing_columns: list[str] = bearing_keys([b.name for b in run.bearings])
        self._node_keys = self.node_columns
        self._tnode_keys = self.thermal_node_columns
        self._bearing_keys = self.bearing_columns

        # model text
        model = self.attachments.get(run.model_name)
        if model is None:
            notes.append(f"the model file attachment {run.model_name!r} is missing")
            self.model_text = ""
        else:
            self.model_text = model.decode("utf-8", errors="replace")
            if run.model_sha256 and hashlib.sha256(model).hexdigest() != run.model_sha256:
                notes.append(
                    f"the model file attachment {run.model_name!r} does not match "
                    "RunInfo.model_sha256"
                )

        # settings
        try:
            self.settings: dict[str, Any] = tomllib.loads(run.settings_toml)
        except tomllib.TOMLDecodeError as e:
            notes.append(f"RunInfo.settings_toml is not valid TOML: {e}")
            self.settings = {}

        # complete points: those whose /summary was read (it is written last)
        self._points: dict[int, dict[str, Any]] = {}
        for index in sorted(s.points):
            parts = s.points[index]
            if "/summary" not in parts:
                notes.append(
                    f"point {index} skipped: no /summary message (the point was not "
                    "written completely)"
                )
                continue
            self._check_point(index, parts)
            self._points[index] = parts
        self.points: list[int] = list(self._points)

        # completeness, as the Rust reader decides it
        status_md = self.metadata.get(METADATA_STATUS, {})
        status = status_md.get("status")
        if s.cut_short:
            notes.append("the file ends in the middle of a record (cut short)")
        for d in s.damaged:
            notes.append(f"damaged, skipped: {d}")
        # points lost before the last one read (their chunks damaged), as replay names them
        if self.points:
            lost = sorted(set(range(self.points[-1])) - set(self.points))
            if lost:
                notes.append(
                    f"points missing: {len(lost)} ({', '.join(str(i) for i in lost[:10])}"
                    f"{', …' if len(lost) > 10 else ''})"
                )
        self.missing_points: list[int] = (
            sorted(set(range(self.points[-1])) - set(self.points)) if self.points else []
        )
        if not s.end_magic:
            notes.append("the file does not end with the MCAP magic bytes")
        if not (s.saw_data_end and s.saw_footer):
            notes.append("the file has no summary/footer: it was not finished")
        if status is None:
            notes.append("no run status: the run did not finish writing")
        complete = (
            not s.cut_short
            and not s.damaged
            and not self.missing_points
            and s.end_magic
            and s.saw_data_end
            and s.saw_footer
            and status is not None
        )
        self.info: dict[str, Any] = {
            "tool_name": run.tool_name,
            "tool_version": run.tool_version,
            "model_name": run.model_name,
            "model_sha256": run.model_sha256,
            "parameter": run.parameter,
            "complete": bool(complete),
            "notes": notes,
            "points": len(self.points),
            "status": status,
            "warnings": [e.message for e in self.log_entries if e.name == AUDIT_LOG_NAME],
            "revolutions": len(s.revolutions),
        }
        # a transient run (tmrotor transient): its settings, and revolutions lost in
        # damaged chunks (numbered from 1)
        ti = s.transient_info
        self.transient_info: dict[str, Any] | None = (
            None
            if ti is None
            else {
                "profile": ti.profile,
                "start": ti.start,
                "duration_s": ti.duration_s,
                "thermal_stepping": ti.thermal_stepping,
                "rtol": ti.rtol,
                "window_revolutions": int(ti.window_revolutions),
                "samples_per_revolution": int(ti.samples_per_revolution),
            }
        )
        seen = sorted(int(r.index) for r in s.revolutions)
        if seen:
            missing = sorted(set(range(1, seen[-1])) - set(seen))
            if missing:
                notes.append(f"revolutions missing: {len(missing)} (first {missing[0]})")
                self.info["complete"] = False

    # ------------------------------------------------------------------ helpers

    def __repr__(self) -> str:
        state = "complete" if self.info["complete"] else "INCOMPLETE"
        return f"<tmrotor.Recording {self.path.name}: {len(self.points)} points, {state}>"

    def _harmonics_of(self, parts: dict[str, Any]) -> list[Any]:
        """The basis of a point: that of its branch (``branch`` of its ``/summary``)."""
        k = _branch_of(parts["/summary"])
        if k not in self._branch_harmonics:
            raise RecordingError(
                str(self.path), "corrupt", f"branch {k} is not described on /branches"
            )
        return self._branch_harmonics[k]

    def _check_point(self, index: int, parts: dict[str, Any]) -> None:
        run = self.run_info
        what = None
        s = parts["/summary"]
        if len(s.amplitude_rms_m) not in (0, len(run.nodes)):
            what = f"/summary has {len(s.amplitude_rms_m)} amplitudes for {len(run.nodes)} nodes"
        h = parts.get("/harmonics")
        if h is not None:
            nc = 1 + 2 * len(self._harmonics_of(parts))
            if len(h.mech) != run.n_mech * nc or len(h.therm) != run.n_therm * nc:
                what = (
                    f"/harmonics has {len(h.mech)} + {len(h.therm)} coefficients, expected "
                    f"{run.n_mech * nc} + {run.n_therm * nc}"
                )
        if what:
            raise RecordingError(str(self.path), "corrupt", f"point {index}: {what}")

    def _point(self, point: int) -> dict[str, Any]:
        try:
            return self._points[int(point)]
        except KeyError:
            last = self.points[-1] if self.points else "none"
            raise KeyError(
                f"{self.path.name} has no point {point} ({len(self.points)} points "
                f"readable, last index {last})"
            ) from None

    def _summaries(self):
        return [self._points[i]["/summary"] for i in self.points]

    def _start(self, branch: bool = False) -> dict[str, Any]:
        cols: dict[str, Any] = {
            "index": pd.Series(self.points, dtype="int64"),
            "omega_rad_s": pd.Series([s.omega_rad_s for s in self._summaries()], dtype="float64"),
        }
        if branch:
            cols["branch"] = pd.Series(
                [_branch_of(s) for s in self._summaries()], dtype="int64"
            )
        return cols

    def _entity_columns(
        self,
        topic: str,
        keys: list[str],
        fields: list[tuple[str, str]],
        list_attr: str,
    ) -> dict[str, np.ndarray]:
        """Columns ``<key>_<suffix>`` from the per-entity list ``list_attr`` of ``topic``
        (positional, in RunInfo order), NaN where the point lacks them."""
        n = len(self.points)
        cols = {f"{k}_{suffix}": np.full(n, np.nan) for k in keys for _, suffix in fields}
        for row, index in enumerate(self.points):
            msg = self._points[index].get(topic)
            if msg is None:
                continue
            for k, entity in zip(keys, getattr(msg, list_attr)):
                for attr, suffix in fields:
                    cols[f"{k}_{suffix}"][row] = getattr(entity, attr)
        return cols

    # ------------------------------------------------------------------ tables

    @cached_property
    def revolutions(self) -> pd.DataFrame:
        """A transient run's records, one row per revolution (empty for a sweep):
        ``revolution``, ``time_s``, ``omega_rad_s``, ``step_count``, ``last_step_s``, then
        ``amp_rms_node<id>_m`` and ``amp_max_node<id>_m`` per dynamic node (RMS amplitude
        of Eq. 35 over the last basis period, largest excursion), ``tnode<id>_c`` per
        thermal node, and per bearing ``<bearing>_delta_v_m``,
        ``<bearing>_clearance_m``, ``<bearing>_load_n``, ``<bearing>_load_max_n``
        (see ``schemas/README.md``, topic ``/transient/revolution``)."""
        revs = sorted(self._scan.revolutions, key=lambda r: int(r.index))
        cols: dict[str, Any] = {
            "revolution": pd.Series([int(r.index) for r in revs], dtype="int64"),
            "time_s": pd.Series([r.time_s for r in revs], dtype="float64"),
            "omega_rad_s": pd.Series([r.omega_rad_s for r in revs], dtype="float64"),
            "step_count": pd.Series([int(r.step_count) for r in revs], dtype="int64"),
            "last_step_s": pd.Series([r.last_step_s for r in revs], dtype="float64"),
        }

        def per(keys: list[str], suffix: str, attr: str) -> None:
            for k, key in enumerate(keys):
                cols[f"{key}{suffix}"] = pd.Series(
                    [
                        getattr(r, attr)[k] if k < len(getattr(r, attr)) else np.nan
                        for r in revs
                    ],
                    dtype="float64",
                )

        per([f"amp_rms_{k}" for k in self.node_columns], "_m", "amplitude_rms_m")
        per([f"amp_max_{k}" for k in self.node_columns], "_m", "amplitude_max_m")
        per(self.thermal_node_columns, "_c", "temperature_c")
        per(self.bearing_columns, "_delta_v_m", "delta_v_m")
        per(self.bearing_columns, "_clearance_m", "effective_clearance_m")
        per(self.bearing_columns, "_load_n", "bearing_load_n")
        per(self.bearing_columns, "_load_max_n", "bearing_load_max_n")
        return pd.DataFrame(cols)

    @cached_property
    def samples(self) -> pd.DataFrame:
        """A transient run's decimated displacements (empty for a sweep): ``time_s``,
        ``omega_rad_s``, then ``<node>_x_m`` and ``<node>_y_m`` per dynamic node."""
        ss = self._scan.samples
        cols: dict[str, Any] = {
            "time_s": pd.Series([m.time_s for m in ss], dtype="float64"),
            "omega_rad_s": pd.Series([m.omega_rad_s for m in ss], dtype="float64"),
        }
        for k, key in enumerate(self.node_columns):
            cols[f"{key}_x_m"] = pd.Series([m.x_m[k] for m in ss], dtype="float64")
            cols[f"{key}_y_m"] = pd.Series([m.y_m[k] for m in ss], dtype="float64")
        return pd.DataFrame(cols)

    @cached_property
    def branch(self) -> pd.DataFrame:
        """One row per complete point: ``index``, ``omega_rad_s``, ``branch`` (0 the run's
        branch, k > 0 the k-th of :attr:`branches`), ``arc_length``,
        ``stable`` (boolean; from ``/floquet``, missing without it), ``bifurcation``
        (type detected since the previous point, missing for none), ``spectral_radius``,
        ``unstable_count``, ``real_above_one`` (from ``/floquet``), ``residual_mech``,
        ``residual_therm``, ``newton_iterations``, ``half_order_share`` (largest omega/2
        amplitude over the mechanical DoFs divided by the largest amplitude of any
        harmonic; missing when the basis has no half-order harmonic), then
        ``amp_rms_node<id>_m`` per dynamic node (RMS radial amplitude, paper Eq. 35)."""
        summaries = self._summaries()
        floquet = [self._points[i].get("/floquet") for i in self.points]
        cols = self._start(branch=True)
        cols["arc_length"] = pd.Series([s.arc_length for s in summaries], dtype="float64")
        cols["stable"] = pd.array(
            [None if f is None else _STABILITY.get(int(f.stability)) for f in floquet],
            dtype="boolean",
        )
        cols["bifurcation"] = pd.array(
            [_BIFURCATION_KEYS.get(int(s.bifurcation)) for s in summaries], dtype="object"
        )
        cols["spectral_radius"] = pd.Series(
            [np.nan if f is None else f.spectral_radius for f in floquet], dtype="float64"
        )
        cols["unstable_count"] = pd.array(
            [None if f is None else int(f.unstable_count) for f in floquet], dtype="Int64"
        )
        cols["real_above_one"] = pd.array(
            [None if f is None else int(f.real_above_one) for f in floquet], dtype="Int64"
        )
        cols["residual_mech"] = pd.Series([s.residual_mech for s in summaries], dtype="float64")
        cols["residual_therm"] = pd.Series([s.residual_therm for s in summaries], dtype="float64")
        cols["newton_iterations"] = pd.Series(
            [int(s.newton_iterations) for s in summaries], dtype="int64"
        )
        cols["half_order_share"] = pd.Series(
            [
                self._half_order_share(
                    self._points[i].get("/harmonics"), self._harmonics_of(self._points[i])
                )
                for i in self.points
            ],
            dtype="float64",
        )
        amps = np.full((len(self.points), len(self._node_keys)), np.nan)
        for row, s in enumerate(summaries):
            a = list(s.amplitude_rms_m)[: len(self._node_keys)]
            amps[row, : len(a)] = a
        for j, k in enumerate(self._node_keys):
            cols[f"amp_rms_{k}_m"] = amps[:, j]
        return pd.DataFrame(cols)

    def _half_order_share(self, h: Any, harmonics: list[Any]) -> float:
        """As ``derive::half_order_share`` of the Rust crate."""
        half = [
            r.den > 0 and (2 * r.num) % r.den == 0 and ((2 * r.num) // r.den) % 2 == 1
            for r in harmonics
        ]
        if not any(half) or h is None:
            return math.nan
        n_h = len(half)
        c = np.asarray(h.mech, dtype=float).reshape(self.run_info.n_mech, 1 + 2 * n_h)
        amp = np.hypot(c[:, 1 : 1 + n_h], c[:, 1 + n_h :])
        largest = float(amp.max()) if amp.size else 0.0
        largest_half = float(amp[:, np.array(half)].max()) if amp.size else 0.0
        return largest_half / largest if largest > 0.0 else 0.0

    @cached_property
    def temperatures(self) -> pd.DataFrame:
        """Per complete point: ``index``, ``omega_rad_s``, then per thermal node
        ``tnode<id>_mean_c``, ``tnode<id>_min_c``, ``tnode<id>_max_c`` (mean and range
        over one period, °C; missing for points without ``/temperatures``)."""
        cols = self._start()
        cols.update(
            self._entity_columns(
                "/temperatures",
                self._tnode_keys,
                [("mean_c", "mean_c"), ("min_c", "min_c"), ("max_c", "max_c")],
                "nodes",
            )
        )
        return pd.DataFrame(cols)

    @cached_property
    def clearances(self) -> pd.DataFrame:
        """Per complete point: ``index``, ``omega_rad_s``, then per bearing
        ``bearing<k>_delta_v_m`` (clearance variation), ``_ub_m``, ``_ui_m``, ``_uo_m``
        (expansion of rolling elements, inner and outer ring), ``_effective_m``
        (delta_0 + delta_v); from ``/clearance``."""
        cols = self._start()
        cols.update(
            self._entity_columns(
                "/clearance",
                self._bearing_keys,
                [
                    ("delta_v_m", "delta_v_m"),
                    ("ub_m", "ub_m"),
                    ("ui_m", "ui_m"),
                    ("uo_m", "uo_m"),
                    ("effective_m", "effective_m"),
                ],
                "bearings",
            )
        )
        return pd.DataFrame(cols)

    @cached_property
    def bearing_loads(self) -> pd.DataFrame:
        """Per complete point: ``index``, ``omega_rad_s``, ``period_s`` (of ``/orbits``;
        ``2 pi q / omega`` in a lean recording), then per bearing ``bearing<k>_mean_n``,
        ``bearing<k>_min_n``, ``bearing<k>_max_n`` (radial load, paper Eq. 5: mean, and
        minimum and maximum over the period samples of ``/bearing_loads``)."""
        cols = self._start()
        n = len(self.points)
        period = np.empty(n)
        vals = {
            f"{k}_{f}": np.full(n, np.nan)
            for k in self._bearing_keys
            for f in ("mean_n", "min_n", "max_n")
        }
        for row, index in enumerate(self.points):
            parts = self._points[index]
            loads = parts.get("/bearing_loads")
            orbits = parts.get("/orbits")
            # as the Rust reader: the period of /orbits, else the basis's 2 pi q / omega
            if orbits is not None:
                period[row] = orbits.period_s
            else:
                period[row] = self._period(parts["/summary"].omega_rad_s)
            if loads is None:
                continue
            for k, b in zip(self._bearing_keys, loads.bearings):
                vals[f"{k}_mean_n"][row] = b.mean_n
                if len(b.radial_n):
                    r = np.asarray(b.radial_n, dtype=float)
                    vals[f"{k}_min_n"][row] = r.min()
                    vals[f"{k}_max_n"][row] = r.max()
        cols["period_s"] = period
        cols.update(vals)
        return pd.DataFrame(cols)

    @cached_property
    def thermal_forces(self) -> pd.DataFrame:
        """Per complete point: ``index``, ``omega_rad_s``, then per bearing
        ``bearing<k>_bearing_w`` (net heat into the bearing's solid nodes),
        ``_lubricant_w`` (into its lubricant), ``_generation_w`` (friction heat),
        ``_dissipation_w`` (carried away by the lubricant flow); from ``/thermal_forces``."""
        cols = self._start()
        cols.update(
            self._entity_columns(
                "/thermal_forces",
                self._bearing_keys,
                [
                    ("bearing_w", "bearing_w"),
                    ("lubricant_w", "lubricant_w"),
                    ("generation_w", "generation_w"),
                    ("dissipation_w", "dissipation_w"),
                ],
                "bearings",
            )
        )
        return pd.DataFrame(cols)

    def _long(self, attr: str, names: tuple[str, str], modulus: bool) -> pd.DataFrame:
        index, omega, k, re, im = [], [], [], [], []
        for i in self.points:
            f = self._points[i].get("/floquet")
            if f is None:
                continue
            w = self._points[i]["/summary"].omega_rad_s
            for j, c in enumerate(getattr(f, attr)):
                index.append(i)
                omega.append(w)
                k.append(j)
                re.append(c.re)
                im.append(c.im)
        cols: dict[str, Any] = {
            "index": np.asarray(index, dtype="int64"),
            "omega_rad_s": np.asarray(omega, dtype=float),
            "k": np.asarray(k, dtype="int64"),
            names[0]: np.asarray(re, dtype=float),
            names[1]: np.asarray(im, dtype=float),
        }
        if modulus:
            cols["modulus"] = np.hypot(cols[names[0]], cols[names[1]])
        return pd.DataFrame(cols)

    @cached_property
    def multipliers(self) -> pd.DataFrame:
        """Long form, one row per fast Floquet multiplier: ``index``, ``omega_rad_s``,
        ``k`` (0-based within the point), ``re``, ``im``, ``modulus``."""
        return self._long("multipliers", ("re", "im"), modulus=True)

    @cached_property
    def slow_exponents(self) -> pd.DataFrame:
        """Long form, one row per slow (thermal) Floquet exponent: ``index``,
        ``omega_rad_s``, ``k``, ``re_per_s``, ``im_per_s``."""
        return self._long("slow_exponents", ("re_per_s", "im_per_s"), modulus=False)

    @cached_property
    def truncation(self) -> pd.DataFrame:
        """The run's located bifurcations and unlocated changes of stability re-solved at
        higher truncation orders after the sweep (``/truncation``): one row per event and
        order checked, columns ``number`` (as in :attr:`bifurcations`), ``located``
        (False for a change of stability the sweep did not locate), ``type`` (None for
        those), ``omega_rad_s`` (where the sweep put it), ``after_point``,
        ``recorded_order``, ``order``, ``outcome`` (``converged``, ``moved``,
        ``vanished``, ``failed``), ``found_omega_rad_s`` (NaN unless found), ``reason``
        (why it failed) and ``verdict`` over all orders (``holds``, ``moved``,
        ``vanished``: found at no higher order, an artefact of the truncation, not a result;
        ``unsettled``: found at some orders, not at the highest; ``unchecked``). Empty
        when the sweep made no check."""
        rows: list[dict[str, Any]] = []
        for c in self._scan.truncation:
            for o in c.orders:
                rows.append(
                    {
                        "number": int(c.number),
                        "located": bool(c.located),
                        "type": _BIFURCATION_KEYS.get(int(c.type)),
                        "omega_rad_s": float(c.omega_rad_s),
                        "after_point": int(c.after_point),
                        "recorded_order": int(c.recorded_order),
                        "order": int(o.order),
                        "outcome": _TRUNCATION_OUTCOMES.get(int(o.outcome), "unknown"),
                        "found_omega_rad_s": float(o.omega_rad_s)
                        if int(o.outcome) in (1, 2)
                        else np.nan,
                        "reason": str(o.reason),
                        "verdict": _TRUNCATION_VERDICTS.get(int(c.verdict), "unknown"),
                    }
                )
        columns = [
            "number", "located", "type", "omega_rad_s", "after_point", "recorded_order",
            "order", "outcome", "found_omega_rad_s", "reason", "verdict",
        ]
        return pd.DataFrame(rows, columns=columns)

    @cached_property
    def bifurcations(self) -> pd.DataFrame:
        """One row per located bifurcation (``/bifurcations``, in file order): ``number``,
        ``type``, ``omega_rad_s``, ``arc_length``, ``after_point`` (it lies between this
        point and the next), ``unconfirmed`` (boolean), for Neimark–Sacker points
        ``angle_rad``, ``modulation_period_s``, ``thermal_share`` (NaN otherwise) and
        ``thermo_mechanical`` (boolean, NA otherwise), then ``amp_rms_node<id>_m``."""
        bifs = self._scan.bifurcations
        cols: dict[str, Any] = {
            "number": pd.Series([int(b.number) for b in bifs], dtype="int64"),
            "type": pd.array([_BIFURCATION_KEYS.get(int(b.type)) for b in bifs], dtype="object"),
            "omega_rad_s": pd.Series([b.omega_rad_s for b in bifs], dtype="float64"),
            "arc_length": pd.Series([b.arc_length for b in bifs], dtype="float64"),
            "after_point": pd.Series([int(b.after_point) for b in bifs], dtype="int64"),
            "unconfirmed": pd.array([bool(b.unconfirmed) for b in bifs], dtype="boolean"),
            "angle_rad": pd.Series(
                [_ns_value(b, b.angle_rad) for b in bifs], dtype="float64"
            ),
            "modulation_period_s": pd.Series(
                [_ns_value(b, b.modulation_period_s) for b in bifs], dtype="float64"
            ),
            "thermal_share": pd.Series(
                [
                    _ns_value(b, b.thermal_share) if getattr(b, "near_zero", False) else np.nan
                    for b in bifs
                ],
                dtype="float64",
            ),
            "thermo_mechanical": pd.array(
                [bool(b.thermo_mechanical) if _is_ns(b) else None for b in bifs],
                dtype="boolean",
            ),
        }
        amps = np.full((len(bifs), len(self._node_keys)), np.nan)
        for row, b in enumerate(bifs):
            a = list(b.amplitude_rms_m)[: len(self._node_keys)]
            amps[row, : len(a)] = a
        for j, k in enumerate(self._node_keys):
            cols[f"amp_rms_{k}_m"] = amps[:, j]
        return pd.DataFrame(cols)

    @cached_property
    def nodes(self) -> pd.DataFrame:
        """What the column prefixes stand for: one row per dynamic node, thermal node and
        bearing. ``kind`` (``dynamic``, ``thermal``, ``bearing``), ``id`` (node id; the
        bearing's index for bearings), ``column`` (the prefix, e.g. ``node8``), ``name``,
        ``rotor`` (dynamic nodes), ``axial_position_m`` (dynamic nodes),
        ``initial_clearance_m`` (bearings)."""
        run = self.run_info
        rows: list[dict[str, Any]] = []
        for n, key in zip(run.nodes, self._node_keys):
            rows.append(
                {
                    "kind": "dynamic",
                    "id": int(n.id),
                    "column": key,
                    "name": _text(n.name),
                    "rotor": _text(n.rotor),
                    "axial_position_m": n.axial_position_m,
                    "initial_clearance_m": np.nan,
                }
            )
        for n, key in zip(run.thermal_nodes, self._tnode_keys):
            rows.append(
                {
                    "kind": "thermal",
                    "id": int(n.id),
                    "column": key,
                    "name": _text(n.name),
                    "rotor": None,
                    "axial_position_m": np.nan,
                    "initial_clearance_m": np.nan,
                }
            )
        for i, (b, key) in enumerate(zip(run.bearings, self._bearing_keys)):
            rows.append(
                {
                    "kind": "bearing",
                    "id": i,
                    "column": key,
                    "name": _text(b.name),
                    "rotor": None,
                    "axial_position_m": np.nan,
                    "initial_clearance_m": b.initial_clearance_m,
                }
            )
        columns = [
            "kind",
            "id",
            "column",
            "name",
            "rotor",
            "axial_position_m",
            "initial_clearance_m",
        ]
        df = pd.DataFrame(rows, columns=columns)
        df["id"] = df["id"].astype("int64")
        df["axial_position_m"] = df["axial_position_m"].astype("float64")
        df["initial_clearance_m"] = df["initial_clearance_m"].astype("float64")
        return df

    @cached_property
    def branches(self) -> pd.DataFrame:
        """One row per branch beside the run's own (``/branches``): ``branch``, ``kind``
        (``period_doubled``: switched to at a period doubling), ``parent`` (the branch it
        leaves from), ``origin_bifurcation`` (its number on ``/bifurcations``),
        ``origin_omega_rad_s``, ``harmonics`` (its basis, ``"num/den"`` strings). Empty for
        a recording with one branch; :attr:`branch` has each point's ``branch``."""
        rows = [
            {
                "branch": int(b.branch),
                "kind": b.kind,
                "parent": int(b.parent),
                "origin_bifurcation": int(b.origin_bifurcation),
                "origin_omega_rad_s": float(b.origin_omega_rad_s),
                "harmonics": [f"{r.num}/{r.den}" for r in b.harmonics],
            }
            for b in self._scan.branches
        ]
        return pd.DataFrame(
            rows,
            columns=[
                "branch",
                "kind",
                "parent",
                "origin_bifurcation",
                "origin_omega_rad_s",
                "harmonics",
            ],
        )

    @cached_property
    def harmonics(self) -> pd.DataFrame:
        """Harmonic coefficients, one row per (complete point, DoF).

        Columns: ``index``, ``omega_rad_s``, ``kind`` (``mech`` or ``therm``), ``dof``
        (index in the mechanical or thermal DoF vector), ``column`` (what the DoF is:
        ``node<id>_x`` / ``node<id>_y`` for the displacements of a dynamic node,
        ``tnode<id>`` for a thermal node, missing for the other DoFs such as rotations),
        then ``a0``, ``a1`` .. ``aH``, ``b1`` .. ``bH``: the DoF's history is
        ``x(t) = a0 + sum_h a_h cos(nu_h omega t) + b_h sin(nu_h omega t)`` with
        ``nu_h = basis[h-1]`` (also in ``DataFrame.attrs["basis"]`` as ``"num/den"``
        strings). Units of the coefficients: m (translations) or rad (rotations) for
        ``mech``, °C for ``therm`` — mixed, hence no unit suffix. Points without
        ``/harmonics`` have no rows, nor have the points of a branch on a basis of its own
        (:attr:`branches`): :meth:`branch_harmonics` gives those, branch by branch.
        """
        return self.branch_harmonics(0)

    def branch_harmonics(self, branch: int) -> pd.DataFrame:
        """:attr:`harmonics` for the points of branch ``branch`` (0: the run's own; the
        others listed in :attr:`branches`), in that branch's basis (``attrs["basis"]``)."""
        if branch not in self._branch_harmonics:
            known = sorted(self._branch_harmonics)
            raise KeyError(f"{self.path}: no branch {branch} (branches: {known})")
        run = self.run_info
        basis = [Fraction(r.num, r.den) for r in self._branch_harmonics[branch]]
        h_count = len(basis)
        nc = 1 + 2 * h_count
        mech_names: list[Any] = [None] * run.n_mech
        for n, key in zip(run.nodes, self._node_keys):
            if n.dof_x < run.n_mech:
                mech_names[n.dof_x] = f"{key}_x"
            if n.dof_y < run.n_mech:
                mech_names[n.dof_y] = f"{key}_y"
        therm_names: list[Any] = [None] * run.n_therm
        for n, key in zip(run.thermal_nodes, self._tnode_keys):
            if n.dof < run.n_therm:
                therm_names[n.dof] = key
        blocks, index, omega, kind, dof, column = [], [], [], [], [], []
        for i in self.points:
            h = self._points[i].get("/harmonics")
            if h is None or _branch_of(self._points[i]["/summary"]) != branch:
                continue
            w = self._points[i]["/summary"].omega_rad_s
            c = np.concatenate(
                [
                    np.asarray(h.mech, dtype=float).reshape(run.n_mech, nc),
                    np.asarray(h.therm, dtype=float).reshape(run.n_therm, nc),
                ]
            )
            blocks.append(c)
            n_dofs = run.n_mech + run.n_therm
            index += [i] * n_dofs
            omega += [w] * n_dofs
            kind += ["mech"] * run.n_mech + ["therm"] * run.n_therm
            dof += list(range(run.n_mech)) + list(range(run.n_therm))
            column += mech_names + therm_names
        coeffs = np.concatenate(blocks) if blocks else np.empty((0, nc))
        cols: dict[str, Any] = {
            "index": np.asarray(index, dtype="int64"),
            "omega_rad_s": np.asarray(omega, dtype=float),
            "kind": pd.array(kind, dtype="object"),
            "dof": np.asarray(dof, dtype="int64"),
            "column": pd.array(column, dtype="object"),
            "a0": coeffs[:, 0],
        }
        for h in range(1, h_count + 1):
            cols[f"a{h}"] = coeffs[:, h]
        for h in range(1, h_count + 1):
            cols[f"b{h}"] = coeffs[:, h_count + h]
        df = pd.DataFrame(cols)
        df.attrs["basis"] = [f"{r.numerator}/{r.denominator}" for r in basis]
        return df

    def tables(self) -> dict[str, pd.DataFrame]:
        """Every convention table by name (:data:`TABLES`): the DataFrames ``replay
        export`` writes as ``<name>.csv``."""
        return {name: getattr(self, name) for name in TABLES}

    # ------------------------------------------------------------------ orbits

    def _period(self, omega: float) -> float:
        return 2.0 * math.pi * self.period_denominator / omega

    def orbit(self, point: int, samples: int = 256) -> pd.DataFrame:
        """Time histories of the dynamic nodes of point ``point`` (its ``index``) over one
        period, re-derived from its ``/harmonics`` coefficients.

        ``x(t) = a0 + sum_h a_h cos(nu_h omega t) + b_h sin(nu_h omega t)`` with
        ``nu_h = RunInfo.harmonics[h-1]``, at ``t_k = k T / samples``, ``k = 0..samples-1``,
        ``T = 2 pi q / omega`` (``q`` = :attr:`period_denominator`); x (vertical) and y
        (horizontal) are the DoFs ``RunInfo.nodes[].dof_x`` / ``dof_y``.

        Returns a DataFrame with ``t_s`` and ``node<id>_x_m``, ``node<id>_y_m`` per dynamic
        node (RunInfo order); ``attrs`` holds ``index``, ``omega_rad_s``, ``period_s``.
        Works on recordings without ``/orbits`` (only ``/harmonics`` is needed). Raises
        ``KeyError`` for a point the recording does not hold completely, ``ValueError``
        when the point has no ``/harmonics``.
        """
        if samples < 1:
            raise ValueError("samples must be at least 1")
        parts = self._point(point)
        h = parts.get("/harmonics")
        if h is None:
            raise ValueError(f"point {point} has no /harmonics message")
        run = self.run_info
        omega = parts["/summary"].omega_rad_s
        harmonics = self._harmonics_of(parts)
        den = math.lcm(*(int(r.den) for r in harmonics))
        period = 2.0 * math.pi * den / omega
        nu = np.array([float(r.num) / float(r.den) for r in harmonics])
        # the same operations, in the same order, as the Rust crate's derive::sample_times
        # and Basis::trig_table
        t = period * np.arange(samples, dtype=float) / float(samples)
        arg = np.outer(t, nu * omega)
        cos, sin = np.cos(arg), np.sin(arg)
        nh = len(harmonics)
        c = np.asarray(h.mech, dtype=float).reshape(run.n_mech, 1 + 2 * nh)
        cols: dict[str, np.ndarray] = {"t_s": t}
        for n, key in zip(run.nodes, self._node_keys):
            for axis, d in (("x", n.dof_x), ("y", n.dof_y)):
                row = c[d]
                cols[f"{key}_{axis}_m"] = row[0] + cos @ row[1 : 1 + nh] + sin @ row[1 + nh :]
        df = pd.DataFrame(cols)
        df.attrs.update(index=int(point), omega_rad_s=omega, period_s=period)
        return df

    def recorded_orbit(self, point: int) -> pd.DataFrame:
        """The ``/orbits`` samples of point ``point`` as stored, in the layout of
        :meth:`orbit` (``t_s`` at ``k period_s / S``, S the stored sample count). Raises
        ``ValueError`` for a recording without ``/orbits`` (a lean recording): use
        :meth:`orbit` there."""
        parts = self._point(point)
        o = parts.get("/orbits")
        if o is None:
            raise ValueError(
                f"point {point} has no /orbits message (a lean recording?); use orbit()"
            )
        samples = len(o.nodes[0].x_m) if o.nodes else 0
        cols: dict[str, np.ndarray] = {
            "t_s": o.period_s * np.arange(samples, dtype=float) / float(max(samples, 1))
        }
        for n, key in zip(o.nodes, (node_key(n.node_id) for n in o.nodes)):
            cols[f"{key}_x_m"] = np.asarray(n.x_m, dtype=float)
            cols[f"{key}_y_m"] = np.asarray(n.y_m, dtype=float)
        df = pd.DataFrame(cols)
        df.attrs.update(index=int(point), omega_rad_s=o.omega_rad_s, period_s=o.period_s)
        return df


def _branch_of(summary: Any) -> int:
    """The ``branch`` of a ``/summary`` message; 0 in recordings written before branches
    were recorded (their schema has no such field)."""
    return int(getattr(summary, "branch", 0))


def _text(s: str) -> str | None:
    return s if s else None
