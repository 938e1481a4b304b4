"""The Rerun exporter: the .rrd it writes is read back with Rerun's own tools.

Skipped when rerun-sdk is not installed, except under CI=true, where that fails.
"""

from __future__ import annotations

import collections
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import IN_CI, REPO, run

import tmrotor

if IN_CI:
    import rerun  # noqa: F401  (CI=true: rerun-sdk is required, a missing one fails)
else:
    pytest.importorskip(
        "rerun", reason="rerun-sdk is not installed (pip install './python[rerun]')"
    )

from rerun.chunk import RrdReader

import tmrotor.rerun as trr


def contents(rrd: Path) -> tuple[dict, dict, dict]:
    """Per entity path of the recording store: rows on the `point` timeline, static rows,
    and the timelines seen."""
    rows: dict[str, int] = collections.Counter()
    static: dict[str, int] = collections.Counter()
    timelines: dict[str, set] = collections.defaultdict(set)
    for chunk in RrdReader(rrd).stream():
        if chunk.is_static:
            static[chunk.entity_path] += chunk.num_rows
        else:
            assert "point" in chunk.timeline_names, chunk.entity_path
            rows[chunk.entity_path] += chunk.num_rows
            timelines[chunk.entity_path].update(chunk.timeline_names)
    return rows, static, timelines


def blueprint_views(rrd: Path) -> list[tuple[str, str]]:
    """(view class, display name) of every view of the blueprint store."""
    reader = RrdReader(rrd)
    (bp,) = reader.blueprints()
    views = []
    for chunk in reader.stream(store=bp):
        if not chunk.entity_path.startswith("/view/") or chunk.entity_path.endswith("ViewContents"):
            continue
        batch = chunk.to_record_batch().to_pydict()
        cls = next(v for k, v in batch.items() if k.endswith("class_identifier"))
        name = next((v for k, v in batch.items() if k.endswith("display_name")), [[None]])
        views.append((cls[0][0], name[0][0] if name[0] else None))
    return views


@pytest.fixture(scope="module")
def sweep_rrd(sweep_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rrd") / "sweep.rrd"
    assert trr.main([str(sweep_rec), "-o", str(out)]) == 0
    return out


def test_rrd_is_read_by_rerun_tools(sweep_rrd: Path, rerun_cli: str | None) -> None:
    assert sweep_rrd.stat().st_size > 0
    need_cli = rerun_cli is not None
    if not need_cli:
        pytest.skip("the rerun command line is not on PATH")
    p = subprocess.run(
        [rerun_cli, "rrd", "verify", str(sweep_rrd)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    stats = subprocess.run(
        [rerun_cli, "rrd", "stats", str(sweep_rrd)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert stats.returncode == 0, stats.stdout + stats.stderr


def test_entities_and_rows_on_the_point_timeline(sweep_rec: Path, sweep_rrd: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    n = len(rec.points)
    rows, static, timelines = contents(sweep_rrd)
    run_info = rec.run_info
    # the branch: one row per point for omega and each node's amplitude
    assert rows["/branch/omega_rad_s"] == n
    for node in run_info.nodes:
        assert rows[f"/branch/amplitude_um/{node.rotor}/node{node.id}"] == n
        # whirl orbit of every dynamic node at every point
        assert rows[f"/rotor/orbits/{node.rotor}/node{node.id}"] == n
    unstable = int(rec.branch["stable"].eq(False).sum())
    assert sum(
        v for k, v in rows.items() if k.startswith("/branch/unstable_um/")
    ) == unstable * len(run_info.nodes)
    # every thermal node in a group, every bearing's clearance
    temps = [k for k in rows if k.startswith("/temperatures/")]
    assert len(temps) == len(run_info.thermal_nodes)
    assert all(rows[k] == n for k in temps)
    assert {"/temperatures/bearing1/tnode50", "/temperatures/LP/tnode1"} <= set(temps)
    for k in rec.bearing_columns:
        assert rows[f"/clearance/delta_v_um/{k}"] == n
    # timelines: point and omega; no wall clock
    assert timelines["/branch/omega_rad_s"] == {"point", "omega_mrad_s"}
    assert timelines["/rotor/orbits/LP/node8"] == {"point", "omega_mrad_s"}
    assert {"/info", "/rotor", "/rotor/shaft/LP", "/rotor/shaft/HP"} <= set(static)
    assert rows["/log"] == sum(1 for _ in rec.log_entries)


def test_blueprint_has_a_view_per_group(sweep_rec: Path, sweep_rrd: Path) -> None:
    views = blueprint_views(sweep_rrd)
    classes = collections.Counter(c for c, _ in views)
    assert classes["3D"] == 1
    groups = trr.thermal_groups(tmrotor.read(sweep_rec))
    # amplitude LP and HP, omega, stability, temperature groups, three bearing views
    assert classes["TimeSeries"] == 2 + 2 + len(groups) + 3
    names = {n for _, n in views}
    assert "RMS amplitude LP (µm); red: unstable" in names


def test_synthetic_unstable_points_and_orbit_scale(synthetic_rec: Path, tmp_path: Path) -> None:
    rec = tmrotor.read(synthetic_rec)
    out = trr.export(rec, tmp_path / "s.rrd", scale=500.0, samples=32)
    rows, _static, _tl = contents(out)
    unstable = int(rec.branch["stable"].eq(False).sum())
    assert unstable > 0
    node = rec.run_info.nodes[0]
    assert rows[f"/branch/unstable_um/{node.rotor}/node{node.id}"] == unstable
    # the orbit strip: closed, at the axial position, displacements times the scale
    reader = RrdReader(out)
    chunk = next(
        c for c in reader.stream() if c.entity_path == f"/rotor/orbits/{node.rotor}/node{node.id}"
    )
    batch = chunk.to_record_batch().to_pydict()
    strips = next(v for k, v in batch.items() if k.endswith("LineStrips3D:strips"))
    points = chunk.to_record_batch().to_pydict()["point"]
    first = strips[0][0]
    assert len(first) == 33 and first[0] == first[-1]
    orbit = rec.orbit(points[0], samples=32)
    assert first[0][0] == pytest.approx(node.axial_position_m)
    assert first[1][1] == pytest.approx(500.0 * orbit[f"node{node.id}_y_m"][1], rel=1e-6)
    assert first[1][2] == pytest.approx(500.0 * orbit[f"node{node.id}_x_m"][1], rel=1e-6)


def test_mechanical_and_truncated_recordings_export(
    mechanical_rec: Path, truncated_rec: Path, tmp_path: Path
) -> None:
    for path in (mechanical_rec, truncated_rec):
        rec = tmrotor.read(path)
        out = trr.export(rec, tmp_path / f"{path.stem}.rrd")
        rows, _s, _t = contents(out)
        assert rows["/branch/omega_rad_s"] == len(rec.points)


def test_command_line(synthetic_rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "cli.rrd"
    env = dict(os.environ, PYTHONPATH=str(REPO / "python" / "src"))
    p = subprocess.run(
        [sys.executable, "-m", "tmrotor.rerun", str(synthetic_rec), "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    assert out.exists() and "wrote" in p.stdout
    # not a recording: exit status 1 and a message
    bad = tmp_path / "bad.mcap"
    bad.write_text("no")
    p = subprocess.run(
        [sys.executable, "-m", "tmrotor.rerun", str(bad)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    assert p.returncode == 1 and "not an MCAP file" in p.stderr
    # the console script, when the package is installed
    script = Path(sys.executable).parent / "tmrotor-rerun"
    if script.exists():
        out2 = tmp_path / "script.rrd"
        run(script, synthetic_rec, "-o", out2)
        assert out2.exists()
