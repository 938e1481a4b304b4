"""The sweep's truncation check (``/truncation``): every located bifurcation of the run's
branch re-solved at the order + 1 and + 2, read as a table."""

from __future__ import annotations

from pathlib import Path

import tmrotor

from conftest import run


def test_the_sweeps_bifurcations_carry_their_truncation_verdicts(
    tmrotor_bin: Path, recdir: Path
) -> None:
    out = recdir / "window.mcap"
    run(tmrotor_bin, "sweep", "--omega", "515:530", "--lean", "-q", "-o", out)
    rec = tmrotor.read(out)
    bif = rec.bifurcations
    tr = rec.truncation
    assert len(bif) >= 2
    located = tr[tr["located"]]
    # one row per bifurcation and order, numbered as on /bifurcations
    assert sorted(set(located["number"])) == sorted(bif["number"])
    assert sorted(set(tr["order"])) == [4, 5]
    assert set(tr["recorded_order"]) == {3}
    assert set(tr["outcome"]) <= {"converged", "moved", "vanished", "failed"}
    assert set(tr["verdict"]) <= {"holds", "moved", "vanished", "unsettled", "unchecked"}
    found = tr[tr["outcome"].isin(["converged", "moved"])]
    assert found["found_omega_rad_s"].notna().all()
    # found within the window of ±1 rad/s around where the sweep put it
    assert ((found["found_omega_rad_s"] - found["omega_rad_s"]).abs() <= 1.0).all()
