"""Real PX4 SITL (SIH) crashing mid-flight and started again in the same working directory (as a
Kubernetes sidecar restarts in its pod): the runner sees the new boot's clock and ends the replica
`error`, exit 3 — never a verdict on half a flight.

Runs when ``UAVTEST_PX4_BIN`` names a PX4 v1.15 SITL binary; skips otherwise. PX4 runs as
instance 9 (MAVLink to 127.0.0.1:14549), so it does not meet another test's instance 0.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from harness.px4_sitl import px4_binary, start_px4, stop_px4
from uavtest.analysis.models import ReplicaResult, Verdict

pytestmark = [pytest.mark.integration, pytest.mark.px4, pytest.mark.slow]

INSTANCE = 9
PORT = 14540 + INSTANCE


@pytest.fixture
def px4_exe() -> Path:
    return px4_binary()


@pytest.fixture
def rootfs(tmp_path: Path) -> Iterator[Path]:
    path = tmp_path / "rootfs"
    path.mkdir()
    yield path
    shutil.rmtree(path, ignore_errors=True)


def test_px4_restarted_mid_flight_is_an_error_not_a_verdict(
    px4_exe: Path, rootfs: Path, tmp_path: Path
) -> None:
    test = tmp_path / "hover.yaml"
    doc = {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": "px4-reboot"},
        "spec": {
            "timeout": 300,
            "vehicle": {"simulator": "px4", "params": {"MIS_TAKEOFF_ALT": 5.0}},
            "mission": {"takeoffAltitude": 5, "waypoints": [{"x": 0, "y": 0, "z": -5, "hold": 30}]},
            "commands": [{"at": 1, "action": "mode", "mode": "mission"}],
        },
    }
    test.write_text(yaml.safe_dump(doc))
    store = tmp_path / "store"
    cmd = [sys.executable, "-m", "uavtest.cli", "runner", "--test", str(test), "--store", str(store)]
    cmd += ["--run-id", "px4", "--connect", f"udpin:127.0.0.1:{PORT}", "--connect-timeout", "60"]
    logs = [open(tmp_path / f"px4-{n}.log", "wb") for n in ("first", "second")]  # noqa: SIM115
    sims = [start_px4(px4_exe, rootfs, logs[0], INSTANCE)]
    runner = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert runner.stderr is not None
        seen = []
        for line in runner.stderr:  # the vehicle armed: crash PX4 and start it again, same folder
            seen.append(line)
            if re.search(r"vehicle \d+/\d+: .*, armed$", line.rstrip()):
                sims[0].kill()
                sims[0].wait(10)
                sims.append(start_px4(px4_exe, rootfs, logs[1], INSTANCE))
                break
        assert len(sims) == 2, "PX4 never armed:\n" + "".join(seen)[-4000:]
        out, err = runner.communicate(timeout=600)
    finally:
        for proc in (runner, *sims):
            stop_px4(proc)  # type: ignore[arg-type]
        for f in logs:
            f.close()
    stderr = "".join(seen) + err
    result = ReplicaResult.model_validate_json(out.strip().splitlines()[-1])
    assert (runner.returncode, result.verdict) == (3, Verdict.ERROR), f"{result.reason}\n{stderr[-4000:]}"
    times = re.match(
        r"the vehicle rebooted mid-flight \(time since boot went from (\d+\.\d) s to (\d+\.\d) s\): "
        r"simulator restarted; no verdict on a half flight$",
        result.reason,
    )
    assert times is not None, result.reason
    assert float(times[2]) < float(times[1])
