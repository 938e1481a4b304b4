"""The Foxglove layout shipped in viewers/foxglove/ resolves on a fresh recording, and the
checker (tools/check_foxglove_layout.py) rejects broken copies of it.

The recording is made by the tmrotor binary: $TMROTOR_BIN (default
target/release/tmrotor of this repository); without it the tests that need a recording
are skipped, except under CI=true, where that is a failure.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LAYOUT = ROOT / "viewers" / "foxglove" / "tmrotor-layout.json"
CHECKER = ROOT / "tools" / "check_foxglove_layout.py"
TMROTOR_BIN = Path(os.environ.get("TMROTOR_BIN", ROOT / "target" / "release" / "tmrotor"))


@pytest.fixture(scope="module")
def layout_recording(tmp_path_factory) -> Path:
    if not os.access(TMROTOR_BIN, os.X_OK):
        reason = f"no tmrotor binary at {TMROTOR_BIN} (build it or set TMROTOR_BIN)"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"{reason} (CI=true: required)")
        pytest.skip(reason)
    out = tmp_path_factory.mktemp("foxglove_layout") / "sweep.mcap"
    run = subprocess.run(
        [str(TMROTOR_BIN), "sweep", "--omega", "400:460", "--order", "2", "-q", "-o", str(out)],
        capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, f"tmrotor sweep failed ({run.returncode}):\n{run.stdout}\n{run.stderr}"
    assert out.is_file() and out.stat().st_size > 0
    return out


def check(layout: Path, recording: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(CHECKER), str(layout), str(recording)],
        capture_output=True, text=True, timeout=300,
    )


def shipped() -> dict:
    return json.loads(LAYOUT.read_text(encoding="utf-8"))


def write(doc: dict, path: Path) -> Path:
    path.write_text(json.dumps(doc, indent=2, ensure_ascii=False), encoding="utf-8")
    return path


def test_shipped_layout_resolves(layout_recording):
    run = check(LAYOUT, layout_recording)
    assert run.returncode == 0, run.stdout + run.stderr
    out = run.stdout
    assert out.rstrip().splitlines()[-1].startswith("OK:"), out
    # Every panel was checked, the paths the guide talks about among them.
    for panel in ("Plot!amplitude", "Plot!temperatures", "Plot!clearance", "Plot!floquet",
                  "3D!orbits", "RosOut!events", "StateTransitions!branch", "Table!nodes"):
        assert f"[{panel}]" in out, f"{panel} not checked:\n{out}"
    assert "x axis (default): /summary.omega_rad_s -> double" in out
    assert "/summary.amplitude_rms_unstable_um[7] -> double" in out
    assert "followTf 'rotor' is published by a foxglove.FrameTransform" in out
    assert "topic /log (foxglove.Log" in out


def test_shipped_layout_shape():
    doc = shipped()
    assert {"configById", "globalVariables", "userNodes", "layout"} <= set(doc)
    configs = doc["configById"]
    amplitude = configs["Plot!amplitude"]
    assert amplitude["xAxisVal"] == "custom"
    assert amplitude["xAxisPath"]["value"] == "/summary.omega_rad_s"
    # stable and unstable series of the same nodes in micrometres, unfiltered (NaN where
    # the point is of the other kind), so older Foxglove pairs them with the x axis
    values = [p["value"] for p in amplitude["paths"]]
    for k in (11, 7, 10):  # 2#, 3#, 4# bearing nodes in RunInfo.nodes order
        assert f"/summary.amplitude_rms_stable_um[{k}]" in values
        assert f"/summary.amplitude_rms_unstable_um[{k}]" in values
    for p in amplitude["paths"]:
        assert "{" not in p["value"], p
        assert p["xValuePath"] == "/summary.omega_rad_s"
    assert configs["3D!orbits"]["followTf"] == "rotor"
    assert configs["RosOut!events"]["topicToRender"] == "/log"


def test_misspelt_field_is_rejected(layout_recording, tmp_path):
    doc = shipped()
    series = doc["configById"]["Plot!amplitude"]["paths"][0]
    series["value"] = series["value"].replace("amplitude_rms_stable_um", "amplitude_rms_stabel_um")
    run = check(write(doc, tmp_path / "misspelt.json"), layout_recording)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "no field 'amplitude_rms_stabel_um' in tmrotor.v1.PointSummary" in run.stderr
    assert "did you mean 'amplitude_rms_stable_um'" in run.stderr
    assert "[Plot!amplitude] series 1 y" in run.stderr


def _set(doc: dict, panel: str, keys: list, value) -> None:
    target = doc["configById"][panel]
    for k in keys[:-1]:
        target = target[k]
    target[keys[-1]] = value


@pytest.mark.parametrize(
    ("panel", "keys", "value", "expected"),
    [
        ("Plot!amplitude", ["xAxisPath", "value"], "/summary.omega",
         "did you mean 'omega_rad_s'"),
        ("Plot!amplitude", ["paths", 0, "value"], "/summary{stabilty==1}.amplitude_rms_m[11]",
         "no field 'stabilty'"),
        ("Plot!amplitude", ["paths", 0, "xValuePath"], "/summary{stability=='STABILITY_STABLE'}.omega_rad_s",
         "decodes protobuf enums as their numbers"),
        ("Plot!amplitude", ["paths", 0, "value"], "/summary{stability==7}.amplitude_rms_m[11]",
         "7 is not a value of tmrotor.v1.Stability"),
        ("Plot!amplitude", ["paths", 0, "value"], "/summary.amplitude_rms_m[18]",
         "index [18] is out of range"),
        # what Foxglove Studio 1.48 showed: a filtered series paired with the unfiltered x
        # axis (error badge), and metres on an axis with three decimals (a flat line)
        ("Plot!amplitude", ["paths", 0, "value"], "/summary{stability==1}.amplitude_rms_m[11]",
         "filters whole messages"),
        ("Plot!amplitude", ["paths", 0, "value"], "/summary.amplitude_rms_m[11]",
         "Foxglove rounds the y-axis ticks to three decimals"),
        ("Plot!clearance", ["paths", 0, "value"], "/floquet.spectral_radius",
         "older Foxglove pairs them by position"),
        ("Plot!amplitude", ["paths", 0, "label"], "node 11 (4# bearing) stable",
         "RunInfo.nodes[11] is 'node 12'"),
        ("Plot!temperatures", ["paths", 0, "value"], "/temperature.nodes[51].mean_c",
         "topic /temperature (used by Plot!temperatures) is not in the recording"),
        ("Plot!clearance", ["paths", 0, "value"], "/clearance.bearings.delta_v_m",
         "index it (/clearance.bearings[0])"),
        ("3D!orbits", ["followTf"], "map",
         "followTf 'map' is not a frame"),
        ("RosOut!events", ["topicToRender"], "/rosout",
         "topic /rosout (used by RosOut!events) is not in the recording"),
    ],
)
def test_broken_copies_are_rejected(layout_recording, tmp_path, panel, keys, value, expected):
    doc = shipped()
    _set(doc, panel, keys, value)
    run = check(write(doc, tmp_path / "broken.json"), layout_recording)
    assert run.returncode == 1, run.stdout + run.stderr
    assert expected in run.stderr, run.stderr


def test_invalid_json_and_shape_are_rejected(layout_recording, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(LAYOUT.read_text(encoding="utf-8")[:-10], encoding="utf-8")
    run = check(bad, layout_recording)
    assert run.returncode == 1 and "is not valid JSON" in run.stderr, run.stderr

    doc = shipped()
    del doc["configById"]["Table!nodes"]  # used inside the Tab panel
    run = check(write(doc, tmp_path / "nocfg.json"), layout_recording)
    assert run.returncode == 1 and "'Table!nodes' has no entry in configById" in run.stderr, run.stderr


TRANSIENT_LAYOUT = LAYOUT.with_name("tmrotor-transient-layout.json")


@pytest.fixture(scope="module")
def transient_recording(tmp_path_factory) -> Path:
    if not os.access(TMROTOR_BIN, os.X_OK):
        reason = f"no tmrotor binary at {TMROTOR_BIN} (build it or set TMROTOR_BIN)"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"{reason} (CI=true: required)")
        pytest.skip(reason)
    out = tmp_path_factory.mktemp("foxglove_transient") / "transient.mcap"
    run = subprocess.run(
        [str(TMROTOR_BIN), "transient", "--speed", "400", "--duration", "0.2", "-q", "-o", str(out)],
        capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    return out


def test_shipped_transient_layout_resolves(transient_recording):
    run = check(TRANSIENT_LAYOUT, transient_recording)
    assert run.returncode == 0, run.stdout + run.stderr
    out = run.stdout
    assert out.rstrip().splitlines()[-1].startswith("OK:"), out
    for panel in ("Plot!amplitude", "Plot!temperatures", "Plot!clearance", "Plot!loads",
                  "Plot!displacement", "Plot!speed", "RosOut!events"):
        assert f"[{panel}]" in out, f"{panel} not checked:\n{out}"
    assert "/transient/revolution.amplitude_rms_um[13] -> double" in out
