"""Which modes a vehicle switches to and arms in, without manual control: real PX4 v1.15 SIH and
the built-in simulator answer the same pymavlink client alike.

The client sends MANUAL_CONTROL only once, for half a second before any mode change: both switch
to Position mode (PX4's "force position control as initial state"). Then, with no manual control,
disarmed, Position mode is taken and arming in it refused
("Arming denied: Resolve system health failures first", the pre-arm bit cleared); in the air in
Hold, Position mode and Mission (none uploaded) are TEMPORARILY_REJECTED ("Switching to ... is
currently not available") and the vehicle holds; Return lands it, and disarmed it is back in Hold,
where it may arm. Runs when ``UAVTEST_PX4_BIN`` names a PX4 v1.15 SITL binary.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from harness.mavlink_client import GroundStation as Client
from harness.net import free_udp_port
from harness.px4_sitl import PX4_API_PORT, px4_binary, running_px4
from harness.sitl import free_running_argv, running_sitl

pytestmark = [pytest.mark.integration, pytest.mark.px4, pytest.mark.slow]

POSCTL, MISSION, LOITER = (3, 0), (4, 4), (4, 3)
SPEED = 4  # times real time: the client's waits are wall-clock
REJECTED = mavlink2.MAV_RESULT_TEMPORARILY_REJECTED
ACCEPTED = mavlink2.MAV_RESULT_ACCEPTED


def _exercise(port: int, settle_s: float) -> dict[str, object]:
    c = Client(port)
    try:
        c.until(lambda: c.prearm and c.mode is not None, 120, "ready to arm")
        c.settle(settle_s)  # PX4: its estimator settles before a takeoff (the runner's arm settle)
        out: dict[str, object] = {}
        for _ in range(10):  # 0.5 s of centred MAVLink sticks, before any mode change ...
            c.conn.mav.manual_control_send(1, 0, 0, 500, 0, 0)
            c.settle(0.05)
        c.settle(2)  # ... then none: manual control is lost again
        out["disarmed: first sticks"] = c.mode  # PX4: "force position control as initial state"
        out["disarmed: position mode"] = c.set_mode(POSCTL)
        c.settle(2)
        out["disarmed: in position mode, ready"] = (c.mode, c.prearm)
        out["disarmed: arm"] = c.command(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        out["disarmed: said"] = any("Resolve system health failures first" in t for t in c.texts)
        out["disarmed: hold"] = c.set_mode(LOITER)
        c.until(lambda: c.prearm, 10, "ready again in Hold")
        # at once: COM_DISARM_PRFLT disarms a vehicle left on the ground
        assert c.command(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, 1, settle=0) == ACCEPTED
        c.command(mavlink2.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
        c.until(lambda: c.mode == LOITER and c.alt > 2.0, 60, "hovering in Hold after the takeoff")
        c.settle(2)
        c.texts.clear()
        out["flying: position mode"] = c.set_mode(POSCTL)
        out["flying: mission"] = c.set_mode(MISSION)
        out["flying: said"] = sorted({t for t in c.texts if "currently not available" in t})
        out["flying: mode, armed"] = (c.mode, c.armed)
        out["flying: return"] = c.command(mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH)
        c.until(lambda: not c.armed, 90, "landed and disarmed")
        c.settle(2)
        out["landed: mode"] = c.mode
        return out
    finally:
        c.close()


EXPECTED = {
    "disarmed: first sticks": POSCTL,
    "disarmed: position mode": ACCEPTED,
    "disarmed: in position mode, ready": (POSCTL, False),
    "disarmed: arm": REJECTED,
    "disarmed: said": True,
    "disarmed: hold": ACCEPTED,
    "flying: position mode": REJECTED,
    "flying: mission": REJECTED,
    "flying: said": [
        "Switching to Mission is currently not available",
        "Switching to Position is currently not available",
    ],
    "flying: mode, armed": (LOITER, True),
    "flying: return": ACCEPTED,
    "landed: mode": LOITER,
}


def test_without_sticks_modes_are_refused_and_arming_too_like_px4_sih(tmp_path: Path) -> None:
    px4_binary()  # skips without UAVTEST_PX4_BIN
    with running_px4(tmp_path / "px4", speed=str(SPEED)):
        px4 = _exercise(PX4_API_PORT, settle_s=10)
    port = free_udp_port()
    with running_sitl(free_running_argv(port, tmp_path / "builtin", SPEED)):
        ours = _exercise(port, settle_s=0)
    assert px4 == EXPECTED, px4
    assert ours == px4
