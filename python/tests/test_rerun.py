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
        cls = next((v for k, v in batch.items() if k.endswith("class_identifier")), None)
        if cls is None:
            continue  # a view's property (legend, axis, time ranges), not a view
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
    # 11 LP nodes: more than a legend should cover, so hidden and the title says so
    assert "RMS amplitude LP (µm); red: unstable (hover for names)" in names
    assert any(n.startswith("whirl orbits about their mean, displacements ×") for n in names)


def static_batches(rrd: Path, prefix: str) -> dict[str, dict]:
    """The static rows (series styles) of the entities under ``prefix``."""
    return {
        c.entity_path: c.to_record_batch().to_pydict()
        for c in RrdReader(rrd).stream()
        if c.is_static and c.entity_path.startswith(prefix)
    }


def time_panel_timeline(rrd: Path) -> list:
    """The timeline(s) the blueprint's time panel opens on."""
    reader = RrdReader(rrd)
    (bp,) = reader.blueprints()
    return [
        c.to_record_batch().to_pydict()["TimePanelBlueprint:timeline"][0]
        for c in reader.stream(store=bp)
        if c.entity_path == "/time_panel"
    ]


def test_blueprint_opens_on_omega_with_distinct_colours(sweep_rec: Path, sweep_rrd: Path) -> None:
    reader = RrdReader(sweep_rrd)
    (bp,) = reader.blueprints()
    assert time_panel_timeline(sweep_rrd) == [["omega_mrad_s"]]
    # the plots show the whole range of both timelines, not a window about the cursor
    ranges = [
        c.entity_path
        for c in reader.stream(store=bp)
        if any(k.endswith("VisibleTimeRanges:ranges") for k in c.to_record_batch().to_pydict())
    ]
    assert len(ranges) >= 4, ranges
    # every view of a group of series tells its series apart by colour
    rec = tmrotor.read(sweep_rec)
    for prefix in ("/branch/amplitude_um/LP/", "/branch/amplitude_um/HP/", "/clearance/delta_v_um/"):
        colours = [
            tuple(b[k][0]) if isinstance(b[k][0], list) else b[k][0]
            for b in static_batches(sweep_rrd, prefix).values()
            for k in b
            if k.endswith(":colors")
        ]
        assert len(colours) >= 2 and len(set(colours)) == len(colours), (prefix, colours)
    groups = trr.thermal_groups(rec)
    for g, members in groups.items():
        colours = [
            b[k][0]
            for b in static_batches(sweep_rrd, f"/temperatures/{g}/").values()
            for k in b
            if k.endswith(":colors")
        ]
        assert len(colours) == len(members) and len(set(map(str, colours))) == len(colours), g


def test_orbit_scale_is_the_recordings_own(sweep_rec: Path, sweep_rrd: Path) -> None:
    """The exporter's automatic factor (Python) against the one the recording's /scene was
    drawn with (Rust, in each orbit entity's metadata): two implementations of one rule."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    with open(sweep_rec, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        scene = next(m for _s, _c, _r, m in reader.iter_decoded_messages(topics=["/scene"]))
    meta = {kv.key: kv.value for kv in scene.entities[0].metadata}
    assert float(meta["displacement_scale"]) == trr.automatic_scale(tmrotor.read(sweep_rec).run_info)
    views = {n for _, n in blueprint_views(sweep_rrd)}
    assert f"whirl orbits about their mean, displacements ×{float(meta['displacement_scale']):g}" in views


def test_synthetic_unstable_points_and_orbit_scale(synthetic_rec: Path, tmp_path: Path) -> None:
    rec = tmrotor.read(synthetic_rec)
    out = trr.export(rec, tmp_path / "s.rrd", scale=500.0, samples=32)
    rows, _static, _tl = contents(out)
    unstable = int(rec.branch["stable"].eq(False).sum())
    assert unstable > 0
    node = rec.run_info.nodes[0]
    assert rows[f"/branch/unstable_um/{node.rotor}/node{node.id}"] == unstable
    # the orbit strip: closed, at the axial position, displacements about their mean
    # times the scale
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
    y = orbit[f"node{node.id}_y_m"].to_numpy()
    x = orbit[f"node{node.id}_x_m"].to_numpy()
    assert first[0][0] == pytest.approx(node.axial_position_m)
    assert first[1][1] == pytest.approx(500.0 * (y[1] - y.mean()), rel=1e-6, abs=1e-12)
    assert first[1][2] == pytest.approx(500.0 * (x[1] - x.mean()), rel=1e-6, abs=1e-12)


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


def test_transient_recording_exports_on_a_time_timeline(transient_rec: Path, tmp_path: Path) -> None:
    rec = tmrotor.read(transient_rec)
    out = tmp_path / "transient.rrd"
    assert trr.main([str(transient_rec), "-o", str(out)]) == 0
    n_rev, n_samples = len(rec.revolutions), len(rec.samples)
    rows: dict[str, int] = collections.Counter()
    timelines: dict[str, set] = collections.defaultdict(set)
    for chunk in RrdReader(out).stream():
        if not chunk.is_static:
            rows[chunk.entity_path] += chunk.num_rows
            timelines[chunk.entity_path].update(chunk.timeline_names)
    assert rows["/transient/omega_rad_s"] == n_rev
    for node in rec.run_info.nodes:
        assert rows[f"/transient/amplitude_um/{node.rotor}/node{node.id}"] == n_rev
        assert rows[f"/transient/samples_um/{node.rotor}/node{node.id}/x"] == n_samples
    for key in rec.bearing_columns:
        assert rows[f"/transient/clearance_um/{key}"] == n_rev
    temps = [k for k in rows if k.startswith("/transient/temperatures/")]
    assert len(temps) == len(rec.run_info.thermal_nodes)
    assert all(t == {"time"} for p, t in timelines.items() if p.startswith("/transient/"))
    # the values: µm of the recording's metres, at the recording's times
    chunk = next(
        c for c in RrdReader(out).stream() if c.entity_path == "/transient/amplitude_um/HP/node14"
    )
    batch = chunk.to_record_batch().to_pydict()
    values = next(v for k, v in batch.items() if k.endswith("Scalars:scalars"))
    assert values[-1][0] == pytest.approx(rec.revolutions["amp_rms_node14_m"].iloc[-1] * 1e6)
    assert time_panel_timeline(out) == [["time"]]
