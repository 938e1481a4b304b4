"""Column names and units of every table follow the one table convention
(/tmp/spec/csv_convention.md), and the DataFrames equal the CSV files of `replay export`."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import run

import tmrotor

NAME = re.compile(r"^[a-z0-9_]+$")
UNITS = ("_m", "_rad_s", "_s", "_c", "_n", "_w", "_per_s")
#: columns without unit (dimensionless quantities, counts, labels)
DIMENSIONLESS = {
    "index",
    "branch",
    "arc_length",
    "stable",
    "bifurcation",
    "spectral_radius",
    "unstable_count",
    "real_above_one",
    "residual_mech",
    "residual_therm",
    "newton_iterations",
    "half_order_share",
    "k",
    "re",
    "im",
    "modulus",
    "number",
    "type",
    "after_point",
    "unconfirmed",
    "angle_rad",
    "modulation_period_s",
    "thermal_share",
    "thermo_mechanical",
    "kind",
    "id",
    "column",
    "name",
    "rotor",
}
ENTITY = r"(node\d+|tnode\d+|bearing[a-z0-9]+)"
#: the exact pattern of every column, per table
PATTERNS = {
    "branch": [
        r"index",
        r"omega_rad_s",
        r"branch",
        r"arc_length",
        r"stable",
        r"bifurcation",
        r"spectral_radius",
        r"unstable_count",
        r"real_above_one",
        r"residual_mech",
        r"residual_therm",
        r"newton_iterations",
        r"half_order_share",
        r"(amp_rms_node\d+_m)*",
    ],
    "temperatures": [r"index", r"omega_rad_s", r"(tnode\d+_(mean|min|max)_c)*"],
    "clearances": [
        r"index",
        r"omega_rad_s",
        r"(bearing[a-z0-9]+_(delta_v|ub|ui|uo|effective)_m)*",
    ],
    "bearing_loads": [
        r"index",
        r"omega_rad_s",
        r"period_s",
        r"(bearing[a-z0-9]+_(mean|min|max)_n)*",
    ],
    "thermal_forces": [
        r"index",
        r"omega_rad_s",
        r"(bearing[a-z0-9]+_(bearing|lubricant|generation|dissipation)_w)*",
    ],
    "multipliers": ["index", "omega_rad_s", "k", "re", "im", "modulus"],
    "slow_exponents": ["index", "omega_rad_s", "k", "re_per_s", "im_per_s"],
    "bifurcations": [
        "number",
        "type",
        "omega_rad_s",
        "arc_length",
        "after_point",
        "unconfirmed",
        "angle_rad",
        "modulation_period_s",
        "thermal_share",
        "thermo_mechanical",
        r"(amp_rms_node\d+_m)*",
    ],
    "nodes": ["kind", "id", "column", "name", "rotor", "axial_position_m", "initial_clearance_m"],
}


def header_regex(parts: list[str]) -> re.Pattern[str]:
    """The pattern of a whole header joined with ',' (repeated groups may be empty)."""
    out = ""
    for p in parts:
        if p.endswith(")*"):
            out += rf"(,{p[1:-2]})*"
        else:
            out += ("," if out else "") + p
    return re.compile(rf"^{out}$")


RECORDINGS = ["sweep_rec", "synthetic_rec", "mechanical_rec", "truncated_rec"]


@pytest.mark.parametrize("which", RECORDINGS)
def test_column_names_follow_the_convention(which: str, request) -> None:
    rec = tmrotor.read(request.getfixturevalue(which))
    tables = rec.tables()
    assert list(tables) == list(tmrotor.TABLES)
    for name, df in tables.items():
        cols = list(df.columns)
        assert len(set(cols)) == len(cols), f"{name}: duplicate columns"
        for c in cols:
            assert NAME.match(c), f"{name}.{c}: not [a-z0-9_]"
        assert header_regex(PATTERNS[name]).match(",".join(cols)), f"{name}: {cols}"
        if name not in ("bifurcations", "nodes"):
            assert cols[:2] == ["index", "omega_rad_s"], name


@pytest.mark.parametrize("which", RECORDINGS)
def test_unit_suffixes(which: str, request) -> None:
    rec = tmrotor.read(request.getfixturevalue(which))
    for name, df in rec.tables().items():
        for c in df.columns:
            assert c in DIMENSIONLESS or c.endswith(UNITS), f"{name}.{c}: no unit suffix"
    # the entity columns use the RunInfo ids and the bearing keys of the convention
    run_info = rec.run_info
    assert [c for c in rec.branch.columns if c.startswith("amp_rms_")] == [
        f"amp_rms_node{n.id}_m" for n in run_info.nodes
    ]
    assert [c for c in rec.temperatures.columns if c.endswith("_mean_c")] == [
        f"tnode{n.id}_mean_c" for n in run_info.thermal_nodes
    ]
    # temperatures are °C (a few tens of degrees), displacements metres (micrometres here)
    if len(run_info.thermal_nodes) and len(rec.points):
        t = rec.temperatures.filter(regex=r"_mean_c$").to_numpy()
        assert 0 < np.nanmin(t) and np.nanmax(t) < 300
    amps = rec.branch.filter(regex=r"^amp_rms_").to_numpy()
    assert np.nanmax(amps) < 1e-2  # metres, not micrometres


def test_bearing_keys() -> None:
    # the name's ASCII letters and digits, lower-cased; bearing_<index from 0> where that
    # leaves nothing ("##", index 2) or repeats an earlier key ("1", index 4); the
    # fallback cannot collide with a name's key ("2#" and "##" differ)
    assert tmrotor.bearing_keys(["1#", "2#", "3#", "4#"]) == [
        "bearing1",
        "bearing2",
        "bearing3",
        "bearing4",
    ]
    assert tmrotor.bearing_keys(["A-b", "x", "##", "1", "1"]) == [
        "bearingab",
        "bearingx",
        "bearing_2",
        "bearing1",
        "bearing_4",
    ]
    assert tmrotor.bearing_keys(["1#", "2#", "##"]) == ["bearing1", "bearing2", "bearing_2"]


# ------------------------------------------------------------------ replay export


def replay_has_export(replay_bin: Path) -> bool:
    out = run(replay_bin, "--help").stdout
    return re.search(r"^\s+export\s", out, re.MULTILINE) is not None


def read_csv_like(path: Path, like: pd.DataFrame) -> pd.DataFrame:
    """A CSV of `replay export` with the dtypes of the DataFrame `like`: empty cells
    missing, `true`/`false` booleans."""
    raw = pd.read_csv(path, dtype=str, keep_default_na=False)
    out = {}
    for c in raw.columns:
        cells = raw[c]
        kind = like[c].dtype if c in like.columns else np.dtype(object)
        missing = cells == ""
        if str(kind) == "boolean":
            assert cells.isin(["true", "false", ""]).all(), f"{path.name}.{c}: {set(cells)}"
            out[c] = pd.array(
                [None if m else v == "true" for v, m in zip(cells, missing)], dtype="boolean"
            )
        elif str(kind) in ("int64", "Int64"):
            out[c] = pd.array(
                [None if m else int(v) for v, m in zip(cells, missing)], dtype="Int64"
            )
        elif pd.api.types.is_float_dtype(kind):
            out[c] = np.array([np.nan if m else float(v) for v, m in zip(cells, missing)])
        else:
            out[c] = [None if m else v for v, m in zip(cells, missing)]
    return pd.DataFrame(out, columns=raw.columns)


def text(v: object) -> object:
    """A text cell with every kind of missing value as None."""
    return None if v is None or v is pd.NA or (isinstance(v, float) and np.isnan(v)) else v


def compare(name: str, mine: pd.DataFrame, csv: Path) -> None:
    ref = read_csv_like(csv, mine)
    assert list(ref.columns) == list(mine.columns), f"{name}: columns differ"
    assert len(ref) == len(mine), f"{name}: {len(ref)} CSV rows, {len(mine)} DataFrame rows"
    for c in mine.columns:
        a, b = mine[c], ref[c]
        what = f"{name}.{c}"
        if str(a.dtype) == "boolean":
            assert list(a.astype(object).where(a.notna(), None)) == list(
                b.astype(object).where(b.notna(), None)
            ), what
        elif str(a.dtype) in ("int64", "Int64"):
            assert list(a.astype("Int64")) == list(b.astype("Int64")), what
        elif pd.api.types.is_float_dtype(a.dtype):
            # numbers are written in their shortest round-trip form: recorded values come
            # back exactly; quantities derived on each side (hypot, ratios) to rounding
            np.testing.assert_allclose(
                a.to_numpy(), b.to_numpy(), rtol=1e-13, atol=0, equal_nan=True, err_msg=what
            )
        else:
            assert [text(v) for v in a] == [text(v) for v in b], what


@pytest.mark.parametrize(
    "which",
    [
        "sweep_rec",
        "synthetic_rec",
        "mechanical_rec",
        "truncated_rec",
        "unfinished_rec",
        "lean_rec",
        "native_lean_rec",
    ],
)
def test_replay_export_matches(which: str, request, replay_bin: Path, tmp_path: Path) -> None:
    if not replay_has_export(replay_bin):
        pytest.skip(f"{replay_bin} has no `export` subcommand yet (`replay --help`)")
    path = request.getfixturevalue(which)
    out = tmp_path / "export"
    run(replay_bin, "export", path, "--out", out)
    rec = tmrotor.read(path)
    for name, df in rec.tables().items():
        csv = out / f"{name}.csv"
        assert csv.exists(), f"replay export wrote no {csv.name}"
        compare(name, df, csv)
    if (out / "model.toml").exists():
        assert (out / "model.toml").read_text() == rec.model_text
    if (out / "settings.toml").exists():
        assert (out / "settings.toml").read_text() == rec.run_info.settings_toml
