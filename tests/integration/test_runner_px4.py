"""`uavtest runner` unchanged against real PX4 SITL (SIH physics): wall clock, MAVLink log download.

Runs when ``UAVTEST_PX4_BIN`` names a PX4 SITL binary (``build/px4_sitl_default/bin/px4`` of a
PX4 v1.15 build); skips otherwise. PX4 instance 0 sends its onboard link to 14540, as always.
``UAVTEST_PX4_SPEED`` (default 10) sets PX4_SIM_SPEED_FACTOR.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from harness.px4_sitl import running_px4
from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.analysis.trajectory import Trajectory

pytestmark = [pytest.mark.integration, pytest.mark.px4, pytest.mark.slow]


@pytest.fixture
def px4(tmp_path: Path) -> Iterator[subprocess.Popen[bytes]]:
    with running_px4(tmp_path) as proc:
        yield proc


def test_the_runner_flies_a_mission_on_px4_and_downloads_its_log(
    px4: subprocess.Popen[bytes], tmp_path: Path
) -> None:
    test = tmp_path / "square.yaml"
    spec = {
        "timeout": 300,
        "vehicle": {"simulator": "px4", "params": {"MIS_TAKEOFF_ALT": 5.0, "MPC_XY_CRUISE": 8.0}},
        "mission": {
            "takeoffAltitude": 10,
            "waypoints": [{"x": 30, "y": 0, "z": -10}, {"x": 30, "y": 30, "z": -10}],
        },
        # as an Aerialist test would: PX4 SIH is ready ~36 s after boot, the runner arms 10 s later
        "commands": [{"at": 1, "action": "mode", "mode": "mission"}],
    }
    doc = {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": "px4-square"},
        "spec": spec,
    }
    test.write_text(yaml.safe_dump(doc))
    store = tmp_path / "store"
    cmd = [sys.executable, "-m", "uavtest.cli", "runner", "--test", str(test), "--store", str(store)]
    cmd += ["--run-id", "px4", "--connect", "udpin:127.0.0.1:14540", "--connect-timeout", "60"]
    done = subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        timeout=900,
    )
    result = ReplicaResult.model_validate_json(done.stdout.strip().splitlines()[-1])
    assert result.verdict is Verdict.PASS, f"{result.reason}\n{done.stderr[-4000:]}"
    assert done.returncode == 0
    assert "lockstep" not in done.stderr  # PX4 runs on its own clock
    replica = store / "local" / "px4-square" / "px4" / "replica-0"
    assert (replica / "flight.ulg").read_bytes()[:7] == b"ULog\x01\x12\x35"  # downloaded over MAVLink
    traj = Trajectory.from_csv((replica / "trajectory.csv").read_text())
    assert traj.x.max() > 28 and traj.y.max() > 28
    assert result.metrics is not None and result.metrics.mission_completed


def test_a_shared_folder_px4_does_not_write_to_falls_back_to_the_mavlink_download(
    px4: subprocess.Popen[bytes], tmp_path: Path
) -> None:
    # as in a pod whose PX4 image keeps its own working directory: the runner is given the shared
    # folder, finds no log there after the flight, and downloads PX4's log over MAVLink instead
    test = tmp_path / "hover.yaml"
    spec = {
        "timeout": 300,
        "vehicle": {"simulator": "px4", "params": {"MIS_TAKEOFF_ALT": 5.0}},
        "mission": {"takeoffAltitude": 5, "waypoints": [{"x": 0, "y": 0, "z": -5, "hold": 2}]},
        "commands": [{"at": 1, "action": "mode", "mode": "mission"}],
    }
    test.write_text(yaml.safe_dump({"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest",
                                    "metadata": {"name": "px4-fallback"}, "spec": spec}))  # fmt: skip
    shared = tmp_path / "shared"
    shared.mkdir()
    store = tmp_path / "store"
    cmd = [sys.executable, "-m", "uavtest.cli", "runner", "--test", str(test), "--store", str(store)]
    cmd += ["--run-id", "px4", "--connect", "udpin:127.0.0.1:14540", "--connect-timeout", "60"]
    cmd += ["--log-dir", str(shared)]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    result = ReplicaResult.model_validate_json(done.stdout.strip().splitlines()[-1])
    assert result.verdict is Verdict.PASS, f"{result.reason}\n{done.stderr[-4000:]}"
    assert "downloading it from the vehicle over MAVLink" in done.stderr
    ulog = (store / "local" / "px4-fallback" / "px4" / "replica-0" / "flight.ulg").read_bytes()
    assert ulog[:7] == b"ULog\x01\x12\x35"
    written = sorted((tmp_path / "rootfs" / "log").rglob("*.ulg"))  # what PX4 wrote, in its own folder
    assert [p.read_bytes() for p in written][-1] == ulog
