"""Every example in examples/ has the outcome its header promises (real sitl and runner)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml

from harness.engine_cli import uavtest_run

pytestmark = pytest.mark.integration


def test_hover_passes(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/hover.yaml", tmp_path)
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None
    assert out.summary["passed"] == 3 and out.summary["flakiness"] == 0.0
    for r in out.summary["results"]:
        assert r["metrics"]["mission_completed"] is True
        assert 4.0 < r["metrics"]["max_altitude"] < 6.5


def test_obstacle_pass_passes_with_clearance(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/obstacle-pass.yaml", tmp_path)
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["passed"] == 3
    assert out.summary["min_obstacle_distance"]["min"] > 1.5


def test_collision_fails(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/collision.yaml", tmp_path)
    assert out.code == 1, out.stderr[-3000:]
    assert out.summary is not None
    assert out.summary["failed"] == 3 and out.summary["flakiness"] == 1.0 and not out.summary["flaky"]
    for r in out.summary["results"]:
        assert r["metrics"]["collision"] is True
        assert "collision" in r["reason"].lower()


def test_near_miss_in_wind_is_flaky(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/near-miss-wind.yaml", tmp_path)
    assert out.code == 1, out.stderr[-3000:]
    assert out.summary is not None
    assert out.summary["errors"] == 0
    assert 0 < out.summary["flakiness"] < 1 and out.summary["flaky"] is True
    failed = [r for r in out.summary["results"] if r["verdict"] == "fail"]
    not_near_miss = [
        (r["index"], r["reason"]) for r in failed if r["metrics"]["min_obstacle_distance"] >= 1.5
    ]
    assert not not_near_miss, f"replicas that failed for another reason than the near miss: {not_near_miss}"
    assert all(not r["metrics"]["collision"] for r in failed)  # a near miss, not a crash


def test_cluster_example_is_a_valid_three_replica_test_that_passes(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/uavtest.yaml", tmp_path)
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["replicas"] == 3 and out.summary["passed"] == 3


def test_geofence_return_comes_back_from_the_fence(repo_root: Path, tmp_path: Path) -> None:
    """PX4 v1.15: breach of the 50 m GF_MAX_HOR_DIST circle → "Geofence violation", Hold for
    COM_FAIL_ACT_T (5 s), Return, land at home; the path never leaves the box around the fence."""
    import csv

    from pyulog import ULog

    out = uavtest_run(repo_root / "examples/geofence-return.yaml", tmp_path, "--replicas", "2")
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["passed"] == 2 and out.summary["errors"] == 0
    for r in out.summary["results"]:
        assert r["metrics"]["geofence_violation"] == 0.0 and r["metrics"]["mission_completed"] is False
        assert 14.0 < r["metrics"]["max_altitude"] < 16.5  # RTL_RETURN_ALT 15
    for replica in sorted(tmp_path.rglob("replica-*")):
        log = ULog(str(replica / "flight.ulg"))
        texts = [m.message for m in log.logged_messages]
        # rtl_direct.cpp: the return altitude AMSL (home's float32 altitude + 15, ceilf), then above home
        home_amsl = float(log.get_dataset("home_position").data["alt"][-1])
        breach = texts.index("Geofence violation: exceeding maximum distance to Home")
        assert texts[breach + 1 : breach + 4] == [
            "Failsafe activated: entering Hold for 5 seconds",
            "Failsafe activated",
            f"RTL: start return at {math.ceil(home_amsl + 15)} m (15 m above destination)",
        ]
        assert texts[-3:] == ["RTL: land at destination", "Landing detected", "Disarmed by landing"]
        rows = list(csv.DictReader((replica / "trajectory.csv").open()))
        assert 50.0 < max(float(row["x"]) for row in rows) < 60.0  # crossed the fence, then braked
        assert abs(float(rows[-1]["x"])) < 2.5 and abs(float(rows[-1]["y"])) < 2.5  # home


def test_collision_prevention_stops_the_pilot_short_of_the_wall(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/collision-prevention.yaml", tmp_path)
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["passed"] == 3
    for r in out.summary["results"]:
        assert r["metrics"]["collision"] is False
        # near CP_DIST (2 m), past it by the braking overshoot (30 seeds: 0.4-1.8 m)
        assert 0.3 < r["metrics"]["min_obstacle_distance"] < 2.5
    assert any("only in position mode" in w for w in out.summary["warnings"])
    # the same test without CP_DIST: CP off (said so), the pilot flies into the wall
    test = yaml.safe_load((repo_root / "examples/collision-prevention.yaml").read_text())
    del test["spec"]["vehicle"]["params"]["CP_DIST"]
    off = tmp_path / "cp-off.yaml"
    off.write_text(yaml.safe_dump(test))
    out = uavtest_run(off, tmp_path / "off")
    assert out.code == 1, out.stderr[-3000:]
    assert out.summary is not None and out.summary["failed"] == 3
    assert all(r["metrics"]["collision"] for r in out.summary["results"])
    assert any("CP_DIST is -1" in w for w in out.summary["warnings"])
