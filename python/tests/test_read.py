"""tmrotor.read against recordings made by the binaries, checked against the raw messages
(read independently with mcap's seeking reader) and against the Rust `replay` tools."""

from __future__ import annotations

import hashlib
import io
import re
import shutil
from pathlib import Path
import subprocess

import numpy as np
import pandas as pd
import pytest
from conftest import rewrite_mcap, run

import tmrotor


def raw_messages(path: Path, topic: str) -> list:
    """Decoded messages of one topic, in file order, through mcap's summary-based reader
    (a different path from the package's front-to-back scan)."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [m.decoded_message for m in reader.iter_decoded_messages(topics=[topic])]


# ------------------------------------------------------------------ info, settings, model


def test_info_settings_and_model(sweep_rec: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    info = rec.info
    assert {
        "tool_name",
        "tool_version",
        "model_name",
        "model_sha256",
        "parameter",
        "complete",
        "notes",
        "points",
    } <= set(info)
    assert info["tool_name"] == "tmrotor"
    assert info["parameter"] == "omega"
    assert info["complete"] is True and info["status"] == "completed"
    assert info["notes"] == []
    assert info["points"] == len(rec.points) == len(raw_messages(sweep_rec, "/summary"))
    # settings parsed from RunInfo.settings_toml
    assert rec.settings["order"] == 2
    assert rec.settings["omega_start"] == 400.0 and rec.settings["omega_end"] == 460.0
    # the model text is the attachment named as RunInfo.model_name, and its hash matches
    assert info["model_name"] in rec.attachments
    assert rec.model_text and "[" in rec.model_text
    assert hashlib.sha256(rec.model_text.encode()).hexdigest() == info["model_sha256"]
    # basis of order 2 with lambda = 6/5: q = lcm of the denominators = 10
    assert [str(r) for r in rec.basis] == ["1/2", "3/5", "1", "6/5", "2", "12/5"]
    assert rec.period_denominator == 10


def test_synthetic_settings_are_nested_toml(synthetic_rec: Path) -> None:
    rec = tmrotor.read(synthetic_rec)
    assert rec.settings["hb"]["order"] == 1
    assert rec.info["model_name"] == "synthetic.toml"
    assert rec.model_text


# ------------------------------------------------------------------ the branch


@pytest.mark.parametrize("which", ["sweep_rec", "synthetic_rec", "mechanical_rec"])
def test_branch_has_one_row_per_summary_with_its_values(which: str, request) -> None:
    path = request.getfixturevalue(which)
    rec = tmrotor.read(path)
    summaries = raw_messages(path, "/summary")
    floquet = {m.index: m for m in raw_messages(path, "/floquet")}
    b = rec.branch
    assert len(b) == len(summaries) > 0
    assert list(b["index"]) == [s.index for s in summaries]
    assert b["index"].is_monotonic_increasing
    np.testing.assert_array_equal(b["omega_rad_s"], [s.omega_rad_s for s in summaries])
    np.testing.assert_array_equal(b["arc_length"], [s.arc_length for s in summaries])
    amp_cols = [f"amp_rms_node{n.id}_m" for n in rec.run_info.nodes]
    assert [c for c in b.columns if c.startswith("amp_rms_")] == amp_cols
    np.testing.assert_array_equal(
        b[amp_cols].to_numpy(), np.array([list(s.amplitude_rms_m) for s in summaries])
    )
    np.testing.assert_array_equal(b["newton_iterations"], [s.newton_iterations for s in summaries])
    # stability from /floquet; the summary's flag agrees
    for row, s in zip(b.itertuples(), summaries):
        f = floquet.get(s.index)
        if f is None:
            assert pd.isna(row.stable) and pd.isna(row.spectral_radius)
        else:
            assert row.stable == (f.stability == 1)
            assert row.stable == (s.stability == 1)
            assert row.spectral_radius == f.spectral_radius
            assert row.unstable_count == f.unstable_count
            assert row.real_above_one == f.real_above_one


def test_synthetic_bifurcations_and_unstable_points(synthetic_rec: Path) -> None:
    rec = tmrotor.read(synthetic_rec)
    bif = rec.bifurcations
    raw = raw_messages(synthetic_rec, "/bifurcations")
    assert len(bif) == len(raw) == 2
    assert list(bif["type"]) == ["saddle_node", "saddle_node"]
    assert list(bif["after_point"]) == [m.after_point for m in raw]
    assert list(bif["number"]) == [0, 1]
    np.testing.assert_array_equal(bif["omega_rad_s"], [m.omega_rad_s for m in raw])
    assert bif["unconfirmed"].dtype == "boolean"
    # the branch marks the point after each located fold, and the points between are unstable
    b = rec.branch.set_index("index")
    for after in bif["after_point"]:
        assert b.loc[after + 1, "bifurcation"] == "saddle_node"
    assert b["bifurcation"].isna().sum() == len(b) - 2
    unstable = b.index[b["stable"].eq(False).fillna(False)].tolist()
    assert unstable and all(bif["after_point"][0] < i <= bif["after_point"][1] for i in unstable)
    assert (b.loc[unstable, "unstable_count"] > 0).all()


def test_matches_replay_branch_csv(sweep_rec: Path, synthetic_rec: Path, replay_bin: Path) -> None:
    """Amplitudes, stability and the half-order share agree with `replay branch --csv`."""
    for path in (sweep_rec, synthetic_rec):
        rec = tmrotor.read(path)
        out = run(replay_bin, "branch", "--csv", path).stdout
        ref = pd.read_csv(io.StringIO(out))
        assert len(ref) == len(rec.branch)
        for n in rec.run_info.nodes:
            col = next(
                (c for c in (f"amp_rms_node{n.id}_m", f"amp_{n.id}_m") if c in ref.columns),
                None,
            )
            assert col is not None, f"no amplitude column for node {n.id} in {list(ref.columns)}"
            np.testing.assert_array_equal(rec.branch[f"amp_rms_node{n.id}_m"], ref[col])
        if "half_order_share" in ref.columns:
            # older replay versions print it with 5 significant digits
            np.testing.assert_allclose(
                rec.branch["half_order_share"], ref["half_order_share"], rtol=1e-4
            )


# ------------------------------------------------------------------ per-point tables


def test_per_point_tables_align_with_the_branch_and_the_messages(sweep_rec: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    run_info = rec.run_info
    for name in ("temperatures", "clearances", "bearing_loads", "thermal_forces"):
        df = getattr(rec, name)
        assert list(df.columns[:2]) == ["index", "omega_rad_s"], name
        pd.testing.assert_series_equal(df["index"], rec.branch["index"])
        pd.testing.assert_series_equal(df["omega_rad_s"], rec.branch["omega_rad_s"])
    temps = raw_messages(sweep_rec, "/temperatures")
    t = rec.temperatures
    assert t.shape == (len(temps), 2 + 3 * len(run_info.thermal_nodes))
    for n, tn in zip(temps[7].nodes, run_info.thermal_nodes):
        assert n.node_id == tn.id
        row = t[t["index"] == temps[7].index].iloc[0]
        assert row[f"tnode{tn.id}_mean_c"] == n.mean_c
        assert row[f"tnode{tn.id}_min_c"] == n.min_c
        assert row[f"tnode{tn.id}_max_c"] == n.max_c
    loads = raw_messages(sweep_rec, "/bearing_loads")
    bl = rec.bearing_loads
    for msg, row in zip(loads, bl.itertuples(index=False)):
        row = row._asdict()
        assert row["period_s"] == msg.period_s
        for k, b in zip(["bearing1", "bearing2", "bearing3", "bearing4"], msg.bearings):
            assert row[f"{k}_mean_n"] == b.mean_n
            assert row[f"{k}_min_n"] == min(b.radial_n)
            assert row[f"{k}_max_n"] == max(b.radial_n)
    clear = raw_messages(sweep_rec, "/clearance")
    c = rec.clearances
    np.testing.assert_array_equal(c["bearing3_delta_v_m"], [m.bearings[2].delta_v_m for m in clear])
    forces = raw_messages(sweep_rec, "/thermal_forces")
    np.testing.assert_array_equal(
        rec.thermal_forces["bearing2_generation_w"], [m.bearings[1].generation_w for m in forces]
    )
    # long tables: one row per multiplier / slow exponent
    floquet = raw_messages(sweep_rec, "/floquet")
    m = rec.multipliers
    assert len(m) == sum(len(f.multipliers) for f in floquet)
    first = m[m["index"] == floquet[3].index]
    np.testing.assert_array_equal(first["k"], np.arange(len(floquet[3].multipliers)))
    np.testing.assert_array_equal(first["re"], [z.re for z in floquet[3].multipliers])
    np.testing.assert_allclose(first["modulus"], np.hypot(first["re"], first["im"]), rtol=0)
    assert len(rec.slow_exponents) == sum(len(f.slow_exponents) for f in floquet) > 0
    # nodes
    nodes = rec.nodes
    assert (nodes["kind"] == "dynamic").sum() == len(run_info.nodes)
    assert (nodes["kind"] == "thermal").sum() == len(run_info.thermal_nodes)
    bearings = nodes[nodes["kind"] == "bearing"]
    assert list(bearings["column"]) == ["bearing1", "bearing2", "bearing3", "bearing4"]
    assert list(bearings["name"]) == ["1#", "2#", "3#", "4#"]
    assert list(bearings["id"]) == [0, 1, 2, 3]
    dyn = nodes[nodes["kind"] == "dynamic"]
    np.testing.assert_array_equal(
        dyn["axial_position_m"], [n.axial_position_m for n in run_info.nodes]
    )


def test_mechanical_recording_has_empty_thermal_tables(mechanical_rec: Path) -> None:
    rec = tmrotor.read(mechanical_rec)
    assert len(rec.points) > 0
    for name in ("temperatures", "clearances", "thermal_forces"):
        df = getattr(rec, name)
        assert list(df.columns) == ["index", "omega_rad_s"], name
        assert len(df) == len(rec.points)
    assert list(rec.bearing_loads.columns) == ["index", "omega_rad_s", "period_s"]
    assert len(rec.slow_exponents) == 0
    assert (rec.harmonics["kind"] == "mech").all()


def test_harmonics_layout(sweep_rec: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    run_info = rec.run_info
    h = rec.harmonics
    n_h = len(rec.basis)
    assert list(h.columns) == (
        ["index", "omega_rad_s", "kind", "dof", "column", "a0"]
        + [f"a{i}" for i in range(1, n_h + 1)]
        + [f"b{i}" for i in range(1, n_h + 1)]
    )
    assert len(h) == len(rec.points) * (run_info.n_mech + run_info.n_therm)
    assert h.attrs["basis"] == ["1/2", "3/5", "1/1", "6/5", "2/1", "12/5"]
    msg = raw_messages(sweep_rec, "/harmonics")[5]
    block = h[(h["index"] == msg.index) & (h["kind"] == "mech")]
    coeff_cols = (
        ["a0"] + [f"a{i}" for i in range(1, n_h + 1)] + [f"b{i}" for i in range(1, n_h + 1)]
    )
    np.testing.assert_array_equal(block[coeff_cols].to_numpy().ravel(), list(msg.mech))
    therm = h[(h["index"] == msg.index) & (h["kind"] == "therm")]
    np.testing.assert_array_equal(therm[coeff_cols].to_numpy().ravel(), list(msg.therm))
    node8 = next(n for n in run_info.nodes if n.id == 8)
    assert block.iloc[node8.dof_x]["column"] == "node8_x"
    assert block.iloc[node8.dof_y]["column"] == "node8_y"
    tn = run_info.thermal_nodes[0]
    assert therm.iloc[tn.dof]["column"] == f"tnode{tn.id}"


# ------------------------------------------------------------------ orbits


@pytest.mark.parametrize("which", ["sweep_rec", "synthetic_rec"])
def test_rederived_orbit_equals_recorded_orbit(which: str, request) -> None:
    path = request.getfixturevalue(which)
    rec = tmrotor.read(path)
    orbits = {m.index: m for m in raw_messages(path, "/orbits")}
    assert set(orbits) == set(rec.points)
    for point in rec.points:
        stored = rec.recorded_orbit(point)
        samples = len(stored)
        derived = rec.orbit(point, samples=samples)
        assert list(derived.columns) == list(stored.columns)
        assert derived.columns[0] == "t_s"
        assert derived.attrs["period_s"] == pytest.approx(orbits[point].period_s, rel=1e-14)
        np.testing.assert_allclose(derived["t_s"], stored["t_s"], rtol=1e-14, atol=0)
        disp = stored.drop(columns="t_s").to_numpy()
        scale = np.abs(disp).max()
        err = np.abs(derived.drop(columns="t_s").to_numpy() - disp).max()
        assert err <= 1e-12 * scale, f"point {point}: {err / scale:.2e} relative"
        # and against the raw message, node by node
        o = orbits[point]
        for n in o.nodes:
            np.testing.assert_allclose(
                derived[f"node{n.node_id}_x_m"], n.x_m, rtol=0, atol=1e-12 * scale
            )
            np.testing.assert_allclose(
                derived[f"node{n.node_id}_y_m"], n.y_m, rtol=0, atol=1e-12 * scale
            )


def test_orbit_sampling_and_period(sweep_rec: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    p = rec.points[4]
    o = rec.orbit(p)  # default 256 samples
    assert len(o) == 256
    omega = rec.branch.set_index("index").loc[p, "omega_rad_s"]
    period = 2 * np.pi * rec.period_denominator / omega
    assert o.attrs["period_s"] == pytest.approx(period, rel=1e-15)
    np.testing.assert_allclose(np.diff(o["t_s"]), period / 256, rtol=1e-9)
    cols = [f"node{n.id}_{a}_m" for n in rec.run_info.nodes for a in "xy"]
    assert list(o.columns) == ["t_s"] + cols
    # the orbit is periodic: the RMS radial amplitude from 256 samples equals Eq. 35 of /summary
    x = o[["node8_x_m"]].to_numpy().ravel()
    y = o[["node8_y_m"]].to_numpy().ravel()
    rms = np.sqrt(np.mean((x - x.mean()) ** 2 + (y - y.mean()) ** 2))
    assert rms == pytest.approx(rec.branch.set_index("index").loc[p, "amp_rms_node8_m"], rel=1e-10)
    with pytest.raises(KeyError):
        rec.orbit(10_000)


def test_matches_replay_orbit(sweep_rec: Path, replay_bin: Path) -> None:
    rec = tmrotor.read(sweep_rec)
    p = rec.points[-1]
    out = run(replay_bin, "orbit", sweep_rec, "--point", p, "--samples", 64).stdout
    ref = pd.read_csv(io.StringIO(out))
    mine = rec.orbit(p, samples=64)
    np.testing.assert_allclose(mine["t_s"], ref["t_s"], rtol=1e-14)
    scale = mine.drop(columns="t_s").abs().to_numpy().max()
    for n in rec.run_info.nodes:
        for axis in "xy":
            col = next(c for c in (f"node{n.id}_{axis}_m", f"{axis}_{n.id}_m") if c in ref.columns)
            np.testing.assert_allclose(
                mine[f"node{n.id}_{axis}_m"], ref[col], rtol=0, atol=1e-13 * scale
            )


def test_lean_recording_without_orbits(sweep_rec: Path, lean_rec: Path) -> None:
    full = tmrotor.read(sweep_rec)
    lean = tmrotor.read(lean_rec)
    assert "/orbits" not in lean.topics and "/scene" not in lean.topics
    assert lean.info["complete"] and lean.points == full.points
    for name in tmrotor.TABLES:
        pd.testing.assert_frame_equal(getattr(lean, name), getattr(full, name), obj=name)
    for p in (full.points[0], full.points[-1]):
        stored = full.recorded_orbit(p)
        derived = lean.orbit(p, samples=len(stored))
        scale = stored.drop(columns="t_s").abs().to_numpy().max()
        pd.testing.assert_frame_equal(derived, full.orbit(p, samples=len(stored)))
        pd.testing.assert_frame_equal(
            derived, stored, check_exact=False, rtol=0, atol=1e-12 * scale
        )
    with pytest.raises(ValueError, match="orbits"):
        lean.recorded_orbit(full.points[0])


def test_native_lean_recording(sweep_rec: Path, native_lean_rec: Path) -> None:
    """`tmrotor sweep --lean` of the same sweep: the same tables, orbits re-derived."""
    full = tmrotor.read(sweep_rec)
    lean = tmrotor.read(native_lean_rec)
    assert "/orbits" not in lean.topics and "/harmonics" in lean.topics
    assert lean.info["complete"] and lean.points == full.points
    for name in tmrotor.TABLES:
        pd.testing.assert_frame_equal(
            getattr(lean, name), getattr(full, name), check_exact=False, rtol=1e-12, obj=name
        )
    p = full.points[len(full.points) // 2]
    stored = full.recorded_orbit(p)
    scale = stored.drop(columns="t_s").abs().to_numpy().max()
    pd.testing.assert_frame_equal(
        lean.orbit(p, samples=len(stored)), stored, check_exact=False, rtol=0, atol=1e-12 * scale
    )


# ------------------------------------------------------------------ files cut short


def test_truncated_copy_reads_fewer_points(
    sweep_rec: Path, truncated_rec: Path, replay_bin: Path
) -> None:
    full = tmrotor.read(sweep_rec)
    cut = tmrotor.read(truncated_rec)  # no exception
    assert cut.info["complete"] is False
    assert cut.info["status"] is None
    assert any("cut short" in n for n in cut.info["notes"])
    assert 0 < len(cut.points) < len(full.points)
    assert cut.info["points"] == len(cut.points)
    # what was read is a prefix of the full branch, equal to it
    n = len(cut.points)
    assert cut.points == full.points[:n]
    pd.testing.assert_frame_equal(cut.branch, full.branch.iloc[:n])
    pd.testing.assert_frame_equal(cut.temperatures, full.temperatures.iloc[:n])
    pd.testing.assert_frame_equal(cut.orbit(cut.points[-1]), full.orbit(cut.points[-1]))
    # as many points as the Rust reader finds
    info = run(replay_bin, "info", truncated_rec).stdout
    m = re.search(r"^points:\s+(\d+)", info, re.MULTILINE)
    assert m and int(m.group(1)) == len(cut.points)


def test_cut_at_many_places_never_raises(sweep_rec: Path, tmp_path: Path) -> None:
    data = sweep_rec.read_bytes()
    counts = []
    for frac in (0.0, 0.01, 0.1, 0.33, 0.5, 0.77, 0.9, 0.999):
        f = tmp_path / f"cut{frac}.mcap"
        f.write_bytes(data[: max(int(frac * len(data)), 0)])
        if frac < 0.01:
            with pytest.raises(tmrotor.RecordingError):
                tmrotor.read(f)  # not even the magic bytes
            continue
        try:
            rec = tmrotor.read(f)
        except tmrotor.RecordingError as e:
            # only a file cut before /run_info may be refused, as "foreign"
            assert e.kind == "foreign" and frac <= 0.01, e
            continue
        assert rec.info["complete"] is False
        counts.append(len(rec.points))
    assert counts == sorted(counts) and counts[-1] > 0


def test_unfinished_recording(unfinished_rec: Path, synthetic_rec: Path) -> None:
    rec = tmrotor.read(unfinished_rec)
    full = tmrotor.read(synthetic_rec)
    assert rec.info["complete"] is False
    assert rec.info["status"] is None
    assert any("no run status" in n for n in rec.info["notes"])
    assert len(rec.points) > 0
    pd.testing.assert_frame_equal(rec.branch, full.branch.iloc[: len(rec.points)])


def test_partial_file_name(truncated_rec: Path, tmp_path: Path) -> None:
    partial = tmp_path / "run.mcap.partial"
    shutil.copy(truncated_rec, partial)
    direct = tmrotor.read(partial)
    assert direct.info["complete"] is False and len(direct.points) > 0
    # asking for the final name while only the .partial exists reads the .partial
    via_target = tmrotor.read(tmp_path / "run.mcap")
    assert via_target.path == partial
    assert via_target.points == direct.points
    assert any(".partial" in n for n in via_target.info["notes"])


def test_points_without_summary_are_dropped(synthetic_rec: Path, tmp_path: Path) -> None:
    """A point is complete only when its /summary was read: the rows of a point with its
    other messages but no /summary are dropped from every table."""
    full = tmrotor.read(synthetic_rec)
    last = full.points[-1]
    out = rewrite_mcap(
        synthetic_rec,
        tmp_path / "nosummary.mcap",
        lambda topic, m: not (topic == "/summary" and m.index == last),
    )
    rec = tmrotor.read(out)
    assert rec.points == full.points[:-1]
    assert any(f"point {last} skipped" in n for n in rec.info["notes"])
    for name in (
        "branch",
        "temperatures",
        "clearances",
        "bearing_loads",
        "thermal_forces",
        "multipliers",
    ):
        df = getattr(rec, name)
        assert last not in set(df["index"]), name
    assert rec.harmonics["index"].max() < last
    with pytest.raises(KeyError):
        rec.orbit(last)


def test_not_a_recording(tmp_path: Path, sweep_rec: Path) -> None:
    f = tmp_path / "x.mcap"
    f.write_text("hello")
    with pytest.raises(tmrotor.RecordingError) as e:
        tmrotor.read(f)
    assert e.value.kind == "not_mcap"
    with pytest.raises(tmrotor.RecordingError):
        tmrotor.read(tmp_path)  # a directory


def _replay_state(replay_bin: Path, f: Path) -> tuple[str, list[int]]:
    """``replay info``'s state line and ``replay branch --csv``'s point indices."""
    info = subprocess.run(
        [str(replay_bin), "info", str(f)], capture_output=True, text=True, check=False
    ).stdout
    state = next(
        (line.split(":", 1)[1].strip() for line in info.splitlines() if line.startswith("state:")),
        "",
    )
    csv = subprocess.run(
        [str(replay_bin), "branch", str(f), "--csv"], capture_output=True, text=True, check=False
    ).stdout.splitlines()
    points = [int(line.split(",")[0]) for line in csv[1:] if line]
    return state, points


@pytest.mark.parametrize("which", ["largest", "middle", "first"])
def test_damaged_chunks_are_read_like_replay(
    which: str, sweep_rec: Path, replay_bin: Path, tmp_path: Path
) -> None:
    """Bytes flipped inside one chunk of a finished file cost the points in that chunk,
    not the file: the package keeps the same points replay keeps, names the lost ones, and
    calls the file incomplete where replay does."""
    from mcap.reader import make_reader

    with open(sweep_rec, "rb") as fh:
        chunks = sorted(make_reader(fh).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
    c = {
        "largest": max(chunks, key=lambda c: c.chunk_length),
        "middle": chunks[len(chunks) // 2],
        "first": chunks[1],
    }[which]
    at = c.chunk_start_offset + c.chunk_length - 40  # in the compressed records
    data = bytearray(sweep_rec.read_bytes())
    data[at : at + 8] = bytes(b ^ 0xFF for b in data[at : at + 8])
    f = tmp_path / "damaged.mcap"
    f.write_bytes(bytes(data))
    rec = tmrotor.read(f)
    state, points = _replay_state(replay_bin, f)
    whole = tmrotor.read(sweep_rec)
    assert rec.points == points, (rec.points, points)
    assert len(rec.points) < len(whole.points) or c.message_index_offsets == {}
    assert not rec.info["complete"]
    assert state != "complete", state
    assert any("damaged" in n for n in rec.info["notes"]), rec.info["notes"]
    lost = sorted(set(whole.points) - set(rec.points))
    if lost and lost[-1] < rec.points[-1]:
        assert rec.missing_points == [i for i in lost if i < rec.points[-1]]
