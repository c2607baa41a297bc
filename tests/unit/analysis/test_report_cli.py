"""``uavtest report`` as a user runs it: every real log, table and JSON, exit codes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

# the same folder the shared_data fixture gives (tests/conftest.py); needed here to parametrize
REPO = Path(__file__).resolve().parents[3]
SHARED_DATA = Path(os.environ.get("UAVTEST_SHARED_DATA", REPO.parent / "shared" / "data"))
LOGS = sorted(SHARED_DATA.rglob("*.ulg")) if SHARED_DATA.is_dir() else []


def uavtest(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", "from uavtest.cli import main; main()", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize("log", LOGS, ids=[p.name for p in LOGS])
def test_report_json_on_every_shared_log(shared_data: Path, log: Path) -> None:
    run = uavtest("report", log, "--json")
    assert "Traceback" not in run.stderr
    assert run.returncode in (0, 1), run.stderr
    report = json.loads(run.stdout)
    assert report["verdict"] == ("pass" if run.returncode == 0 else "fail")
    assert report["log_samples"] > 0 and report["topics"] > 0
    if report["took_off"]:
        assert report["metrics"]["flight_time"] == pytest.approx(
            report["landing_time"] - report["takeoff_time"], abs=0.2
        )
    else:
        assert report["samples"] == 0 and "never took off" in report["reason"]


def test_report_table_on_the_square_mission(shared_data: Path) -> None:
    run = uavtest("report", shared_data / "px4-sih" / "square-mission.ulg")
    assert run.returncode == 0, run.stderr
    assert "40.2 s" in run.stdout and "136.0 s → 176.2 s" in run.stdout
    assert "completed (4/4 items)" in run.stdout
    assert "verdict: pass" in run.stdout


def test_report_with_a_reference_and_a_plot(shared_data: Path, tmp_path: Path) -> None:
    out = tmp_path / "flight.png"
    run = uavtest(
        "report",
        shared_data / "px4-sih" / "competition-mission1-run2.ulg",
        "--reference",
        shared_data / "px4-sih" / "competition-mission1-run1.ulg",
        "--plot",
        out,
        "--json",
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert 0.05 < report["dtw_per_step"] < 1.0
    assert report["frechet"] > report["dtw_per_step"]
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_with_a_native_test_that_the_flight_fails(shared_data: Path, tmp_path: Path) -> None:
    # a 12 m tall box across the first leg of the square (x = 15, 10 m up): a collision
    test = {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": "square"},
        "spec": {
            "mission": {"waypoints": [{"x": 30, "y": 0, "z": -10}, {"x": 30, "y": 30, "z": -10}]},
            "world": {"obstacles": [{"size": {"l": 2, "w": 6, "h": 12}, "position": {"x": 15, "y": 0}}]},
        },
    }
    path = tmp_path / "square.yaml"
    path.write_text(yaml.safe_dump(test))
    run = uavtest("report", shared_data / "px4-sih" / "square-mission.ulg", "--test", path, "--json")
    assert run.returncode == 1, run.stderr
    report = json.loads(run.stdout)
    assert report["metrics"]["collision"] is True
    assert report["metrics"]["min_obstacle_distance"] == 0.0
    assert "collision" in report["reason"]


def test_missing_log_is_bad_input(tmp_path: Path) -> None:
    run = uavtest("report", tmp_path / "nope.ulg")
    assert run.returncode == 2
    assert "nope.ulg" in run.stderr and "Traceback" not in run.stderr
