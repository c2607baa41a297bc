"""No silent pass, end to end: ``uavtest run`` with real simulator and runner processes on tests
whose vehicle never takes off. Each case asserts the verdict and its reason."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from harness.engine_cli import uavtest_run

pytestmark = pytest.mark.integration

BOX = {"size": {"l": 2, "w": 2, "h": 10}, "position": {"x": 20, "y": 0, "z": 0, "r": 0}}


def write_test(tmp_path: Path, name: str, spec: dict[str, Any]) -> Path:
    doc = {"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest", "metadata": {"name": name}, "spec": spec}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def only_result(tmp_path: Path, name: str) -> dict[str, Any]:
    (run,) = (tmp_path / "out" / "local" / name).iterdir()
    return json.loads((run / "replica-0" / "result.json").read_text())


def test_the_issues_offboard_test_is_never_a_pass(tmp_path: Path) -> None:
    """Arm, then offboard, with an obstacle and noCollision + minObstacleDistance: on main this was
    exit 0, pass, flight time 0.0 s. Armed without a setpoint stream the built-in simulator, like
    PX4 v1.15, refuses offboard (TEMPORARILY_REJECTED: fail, the vehicle's refusal) — never pass."""
    spec = {
        "replicas": 1,
        "seed": 1,
        "timeout": 60,
        "world": {"obstacles": [BOX]},
        "commands": [{"at": 1, "action": "arm"}, {"at": 2, "action": "mode", "mode": "offboard"}],
        "assertions": {"noCollision": True, "minObstacleDistance": 1.5},
    }
    out = uavtest_run(write_test(tmp_path, "offboard", spec), tmp_path / "out", "--replicas", "1")
    assert out.summary is not None, out.stderr[-3000:]
    (r,) = out.summary["results"]
    assert r["verdict"] != "pass" and out.code != 0
    if r["verdict"] == "fail":
        assert out.code == 1
        assert r["reason"].startswith(
            "the vehicle never took off: vehicle refused mode offboard (COMMAND_ACK "
        )
        assert "noCollision not judged: the vehicle never took off" in r["reason"]
        assert "minObstacleDistance not judged: the vehicle never took off" in r["reason"]
        judged = {a["name"]: a["passed"] for a in r["assertions"]}
        assert judged == {"noCollision": False, "minObstacleDistance": False}
    else:
        assert r["verdict"] == "error" and out.code == 3
        assert r["reason"] == (
            "the built-in simulator does not support mode offboard; fly this test with simulator: px4"
        )
    assert only_result(tmp_path, "offboard") == r


def test_a_refused_mode_is_fail_with_the_vehicles_statustext(tmp_path: Path) -> None:
    """``mode mission`` without a mission: the vehicle arms, then rejects the mode saying why."""
    spec = {"seed": 2, "timeout": 30, "commands": [{"at": 1, "action": "mode", "mode": "mission"}]}
    out = uavtest_run(write_test(tmp_path, "no-mission", spec), tmp_path / "out", "--replicas", "1")
    assert out.code == 1, out.stderr[-3000:]
    assert out.summary is not None
    (r,) = out.summary["results"]
    assert r["verdict"] == "fail"
    assert r["reason"] == (
        "the vehicle never took off: vehicle refused mode mission (COMMAND_ACK TEMPORARILY_REJECTED): "
        '"Switching to Mission is currently not available"'  # PX4 v1.15's words
    )
    assert r["metrics"]["flight_time"] == 0.0


def test_a_mission_px4_would_refuse_is_fail_saying_why(tmp_path: Path) -> None:
    """A QGC plan whose takeoff follows a waypoint (as an ArduPilot-style file puts home first):
    PX4 v1.15 refuses it ("Mission rejected: takeoff not first waypoint item") and so does the
    built-in vehicle: fail, never took off, the rejection in the reason; never a pass."""
    home = [47.397742, 8.545594, 488.0]

    def item(cmd: int, alt: float) -> dict[str, Any]:
        return {
            "type": "SimpleItem",
            "command": cmd,
            "frame": 3,
            "params": [0, 0, 0, None, 47.3979, 8.545594, alt],
        }

    plan = {
        "fileType": "Plan",
        "version": 1,
        "mission": {
            "version": 2,
            "plannedHomePosition": home,
            "items": [item(16, 10), item(22, 10), item(21, 0)],
        },
    }
    spec = {"replicas": 1, "seed": 1, "timeout": 60, "mission": {"plan": plan}}
    out = uavtest_run(write_test(tmp_path, "refused-plan", spec), tmp_path / "out", "--replicas", "1")
    assert out.summary is not None, out.stderr[-3000:]
    (r,) = out.summary["results"]
    assert r["verdict"] == "fail" and out.code == 1
    assert r["reason"].startswith("the vehicle never took off: vehicle refused mode mission")
    assert '"Mission rejected: takeoff not first waypoint item"' in r["reason"]


def test_a_ground_test_keeps_passing(tmp_path: Path) -> None:
    """By design no flight (arm, disarm): judged as before, obstacles or not."""
    spec = {
        "seed": 3,
        "timeout": 30,
        "world": {"obstacles": [BOX]},
        "commands": [{"at": 1, "action": "arm"}, {"at": 3, "action": "disarm"}],
    }
    out = uavtest_run(write_test(tmp_path, "ground", spec), tmp_path / "out", "--replicas", "1")
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None
    (r,) = out.summary["results"]
    assert (r["verdict"], r["reason"]) == ("pass", "")
    assert out.summary["warnings"] == [] and r["warnings"] == []


def test_replica_processes_run_the_engine_entry_not_the_cli(tmp_path: Path) -> None:
    """``uavtest runner`` / ``uavtest sitl`` still work; the engine starts ``uavtest.engine.entry``."""
    import subprocess
    import sys

    for command in ("runner", "sitl"):
        for module in ("uavtest.cli", "uavtest.engine.entry"):
            proc = subprocess.run(
                [sys.executable, "-m", module, command, "--help"], capture_output=True, text=True, check=False
            )
            assert proc.returncode == 0 and "--test" in proc.stdout, (module, command, proc.stderr)
