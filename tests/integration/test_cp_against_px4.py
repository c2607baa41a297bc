"""Collision Prevention without obstacle data, real PX4 v1.15 SIH against the built-in simulator.

PX4 v1.15's SIH has no obstacle-distance sensor (``simulator_sih`` publishes only a downward
``distance_sensor``), so the one CP behaviour real PX4 SIH can show is CP without data: with
CP_DIST > 0 and MPC_POS_MODE 0, full forward stick in position mode does not move the vehicle
(``collision_constraints`` adapted setpoint 0) and ~5 s later PX4 switches to Hold
(``_publishVehicleCmdDoLoiter``). The same test flown by the built-in simulator (no range
sensor) must do the same. Runs when ``UAVTEST_PX4_BIN`` names a PX4 v1.15 SITL binary.
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

POSCTL, LOITER = 2, 4  # vehicle_status.nav_state


def _test(simulator: str) -> dict:
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": f"cp-no-data-{simulator}"},
        "spec": {
            "seed": 1,
            "timeout": 90,
            "vehicle": {"simulator": simulator, "params": {"CP_DIST": 2.0, "MPC_POS_MODE": 0}},
            "mission": {"takeoffAltitude": 10, "waypoints": [{"x": 0, "y": 0, "z": -10, "hold": 60}]},
            "commands": [
                {"at": 1, "action": "mode", "mode": "mission"},
                {"at": 22, "action": "sticks", "sticks": {"x": 0.0, "z": 0.5}},  # sticks before the
                {"at": 25, "action": "mode", "mode": "position"},  # mode: PX4 wants manual control
                {"at": 28, "action": "sticks", "sticks": {"x": 1.0, "z": 0.5}},
            ],
            "assertions": {"missionCompleted": False, "minObstacleDistance": None},
        },
    }


def _fly(simulator: str, tmp_path: Path) -> tuple[float, float, float]:
    """(seconds from position mode to Hold, metres moved meanwhile, CP's last adapted speed)."""
    test = tmp_path / f"{simulator}.yaml"
    test.write_text(yaml.safe_dump(_test(simulator)))
    out = uavtest_run(test, tmp_path / simulator)
    assert out.summary is not None, out.stderr[-3000:]
    assert any("switches to Hold after 5 s" in w for w in out.summary["warnings"]), out.summary["warnings"]
    (log,) = (tmp_path / simulator).rglob("flight.ulg")
    ulog = ULog(str(log))
    st = ulog.get_dataset("vehicle_status").data
    ns, t = st["nav_state"], st["timestamp"]
    i_pos = int(np.argmax(ns == POSCTL))
    assert ns[i_pos] == POSCTL, "never in position mode"
    after = np.nonzero((ns == LOITER) & (t > t[i_pos]))[0]
    assert len(after), "never switched to Hold"
    t_pos, t_hold = t[i_pos], t[after[0]]
    lp = ulog.get_dataset("vehicle_local_position").data
    span = (lp["timestamp"] >= t_pos) & (lp["timestamp"] <= t_hold)
    moved = float(np.hypot(lp["x"][span] - lp["x"][span][0], lp["y"][span] - lp["y"][span][0]).max())
    cc = ulog.get_dataset("collision_constraints").data
    return (
        (t_hold - t_pos) / 1e6,
        moved,
        float(np.hypot(cc["adapted_setpoint[0]"], cc["adapted_setpoint[1]"]).max()),
    )


@pytest.mark.skipif(not os.environ.get("UAVTEST_PX4_BIN"), reason="UAVTEST_PX4_BIN is not set")
def test_cp_without_data_holds_still_then_hold_like_px4_sih(tmp_path: Path) -> None:
    px4_hold_s, px4_moved, px4_speed = _fly("px4", tmp_path)
    ours_hold_s, ours_moved, ours_speed = _fly("builtin", tmp_path)
    assert px4_speed == ours_speed == 0.0  # CP allowed no movement, full stick notwithstanding
    assert px4_moved < 1.0 and ours_moved < 1.0
    assert 5.0 < px4_hold_s < 6.5 and 5.0 < ours_hold_s < 6.5
    assert abs(px4_hold_s - ours_hold_s) < 1.0
