"""Altitude mode's stick, real PX4 v1.15 SIH against the built-in simulator.

Hovering in altitude mode, half pitch stick forward: PX4's StickTiltXY makes it an acceleration,
half of tan(MPC_MAN_TILT_MAX) g (19.3 degrees of pitch at 35), with no deadzone or expo; the
vehicle speeds up North until its drag balances the tilt. The built-in vehicle must tilt as far
and speed up alike. Runs when ``UAVTEST_PX4_BIN`` names a PX4 v1.15 SITL binary.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import yaml
from pyulog import ULog

from harness.engine_cli import uavtest_run

pytestmark = [pytest.mark.integration, pytest.mark.px4, pytest.mark.slow]

ALTCTL = 1  # vehicle_status.nav_state


def _test(simulator: str) -> dict:
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": f"altitude-stick-{simulator}"},
        "spec": {
            "seed": 1,
            "timeout": 50,
            "vehicle": {"simulator": simulator},
            "mission": {"takeoffAltitude": 10, "waypoints": [{"x": 0, "y": 0, "z": -10, "hold": 60}]},
            "commands": [
                {"at": 1, "action": "mode", "mode": "mission"},
                {"at": 30, "action": "sticks", "sticks": {"x": 0.0, "z": 0.5}},
                {"at": 31, "action": "mode", "mode": "altitude"},
                {"at": 34, "action": "sticks", "sticks": {"x": 0.5, "z": 0.5}},
            ],
            "assertions": {"missionCompleted": False},
        },
    }


def _fly(simulator: str, tmp_path: Path) -> tuple[list[float], list[float]]:
    """(pitch in degrees, North velocity) 1, 2, 3 and 4 s after the stick went forward."""
    test = tmp_path / f"{simulator}.yaml"
    test.write_text(yaml.safe_dump(_test(simulator)))
    out = uavtest_run(test, tmp_path / simulator)
    assert out.summary is not None, out.stderr[-3000:]
    (log,) = (tmp_path / simulator).rglob("flight.ulg")
    ulog = ULog(str(log))
    cmd = ulog.get_dataset("manual_control_setpoint").data
    pushed = int(cmd["timestamp"][np.nonzero(cmd["pitch"] > 0.4)[0][0]])
    st = ulog.get_dataset("vehicle_status").data
    assert st["nav_state"][np.searchsorted(st["timestamp"], pushed) - 1] == ALTCTL
    att = ulog.get_dataset("vehicle_attitude").data
    q0, q1, q2, q3 = (att[f"q[{j}]"] for j in range(4))
    pitch = np.degrees(np.arcsin(np.clip(2 * (q0 * q2 - q3 * q1), -1, 1)))
    lp = ulog.get_dataset("vehicle_local_position").data
    at = [pushed + k * 1e6 for k in (1, 2, 3, 4)]
    return (
        [float(np.interp(t, att["timestamp"].astype(float), pitch)) for t in at],
        [float(np.interp(t, lp["timestamp"].astype(float), lp["vx"])) for t in at],
    )


@pytest.mark.skipif(not os.environ.get("UAVTEST_PX4_BIN"), reason="UAVTEST_PX4_BIN is not set")
def test_altitude_mode_half_stick_tilts_and_speeds_up_like_px4_sih(tmp_path: Path) -> None:
    px4_pitch, px4_vx = _fly("px4", tmp_path)
    ours_pitch, ours_vx = _fly("builtin", tmp_path)
    expected = -np.degrees(np.arctan(0.5 * np.tan(np.radians(35.0))))  # nose down, -19.3
    for pitch in (px4_pitch, ours_pitch):
        assert all(abs(p - expected) < 1.0 for p in pitch), pitch
    assert max(abs(a - b) for a, b in zip(px4_pitch, ours_pitch, strict=True)) < 1.0
    # the speed is an estimate (vehicle_local_position.vx): EKF2's velocity error (0.2-0.4 m/s) makes
    # PX4's own runs differ (3.2-3.7 m/s 4 s after the stick over five runs); both speed up alike
    for vx in (px4_vx, ours_vx):
        assert 1.5 < vx[0] < vx[2] and 2.7 < vx[3] < 4.3, vx
    print(f"PX4 pitch {px4_pitch} vx {px4_vx}; built-in pitch {ours_pitch} vx {ours_vx}")
