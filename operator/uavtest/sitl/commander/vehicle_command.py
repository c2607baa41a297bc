"""COMMAND_LONG / COMMAND_INT → vehicle_command, handled by one function per command.

Like PX4's ``Commander::handle_command``: the command is logged as ``vehicle_command``, its
handler (``HANDLERS``, keyed by MAV_CMD) returns the MAV_RESULT, the result is logged as
``vehicle_command_ack`` and sent back as COMMAND_ACK (with any message the command asked for).
Commands without a handler are UNSUPPORTED.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from uavtest.px4.modes import NavState, nav_state_from_custom_mode
from uavtest.sitl import mav
from uavtest.sitl.commander.arming import Reason
from uavtest.sitl.commander.failure_injection import inject_failure
from uavtest.sitl.mav import MavCmd, MavResult, MavSeverity, Msg
from uavtest.sitl.mavlink_streams import STREAMS, autopilot_version
from uavtest.sitl.telemetry import MESSAGE_IDS
from uavtest.sitl.uorb import VehicleCommand, VehicleCommandAck, command

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["HANDLERS", "Handler", "handle_command"]

#: (vehicle, command, replies to append to) → MAV_RESULT
Handler = Callable[["Vehicle", VehicleCommand, list[Msg]], MavResult]

_AUTOPILOT_VERSION = 148
_HOME_POSITION = 242


def _arm_disarm(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    t, cmdr = v.time_us, v.commander
    if c.param1 >= 0.5:
        return cmdr.arm(t, Reason.EXTERNAL)
    if v.land.landed or round(c.param2) == mav.FORCE_DISARM_MAGIC or not cmdr.armed:
        if cmdr.armed:
            cmdr.disarm(t, Reason.EXTERNAL, "Disarmed by external command")
        return MavResult.ACCEPTED
    v.text(MavSeverity.CRITICAL, "Disarming denied: not landed")
    return MavResult.DENIED


def _set_mode(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    if int(c.param1) & 1:
        return v.commander.set_mode(nav_state_from_custom_mode(int(c.param2), int(c.param3)))
    return MavResult.DENIED


def _takeoff(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    cmdr = v.commander
    if cmdr.crashed:
        return MavResult.DENIED
    p7 = c.param7
    alt = p7 - cmdr.home[5] + cmdr.home[2] if math.isfinite(p7) else None
    cmdr.user_nav_state = NavState.AUTO_TAKEOFF
    cmdr.switch(NavState.AUTO_TAKEOFF, v.time_us, target_alt=alt)
    return MavResult.ACCEPTED


def _land(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    return v.commander.set_mode(NavState.AUTO_LAND)


def _return(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    return v.commander.set_mode(NavState.AUTO_RTL)


def _mission_start(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    if not v.nav.mission:
        return MavResult.DENIED
    first = int(c.param1)
    if 0 < first < len(v.nav.mission):
        v.nav.set_current(first)
    cmdr = v.commander
    result = MavResult.ACCEPTED
    if not cmdr.armed:
        result = cmdr.arm(v.time_us, Reason.MISSION_START)
    if result == MavResult.ACCEPTED:
        result = cmdr.set_mode(NavState.AUTO_MISSION)
    return result


def _change_speed(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    if c.param2 > 0:
        v.nav.speed = c.param2
    elif c.param2 == -2:
        v.nav.speed = math.nan
    return MavResult.ACCEPTED


def _message_interval(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    v.schedule.set_interval(int(c.param1), int(c.param2), v.time_us)
    return MavResult.ACCEPTED


def _request(v: Vehicle, wanted: int, extra: list[Msg]) -> MavResult:
    if wanted == _AUTOPILOT_VERSION:
        extra.append(autopilot_version(v))
    elif wanted in MESSAGE_IDS and (wanted != _HOME_POSITION or v.home_set):
        extra.append(STREAMS[MESSAGE_IDS[wanted]](v, v.time_us))
    else:
        return MavResult.UNSUPPORTED
    return MavResult.ACCEPTED


def _request_message(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    return _request(v, int(c.param1), extra)


def _request_capabilities(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    return _request(v, _AUTOPILOT_VERSION, extra)


HANDLERS: dict[int, Handler] = {
    MavCmd.COMPONENT_ARM_DISARM: _arm_disarm,
    MavCmd.DO_SET_MODE: _set_mode,
    MavCmd.NAV_TAKEOFF: _takeoff,
    MavCmd.NAV_LAND: _land,
    MavCmd.NAV_RETURN_TO_LAUNCH: _return,
    MavCmd.MISSION_START: _mission_start,
    MavCmd.DO_CHANGE_SPEED: _change_speed,
    MavCmd.SET_MESSAGE_INTERVAL: _message_interval,
    MavCmd.REQUEST_MESSAGE: _request_message,
    MavCmd.REQUEST_AUTOPILOT_CAPABILITIES: _request_capabilities,
    MavCmd.INJECT_FAILURE: inject_failure,
}


def vehicle_command(msg: Msg, t: int) -> VehicleCommand:
    """The vehicle_command of a COMMAND_LONG or COMMAND_INT (x, y in 1e-7 degrees)."""
    f = msg.fields
    p1, p2, p3, p4 = (float(f.get(k, 0.0)) for k in ("param1", "param2", "param3", "param4"))
    if msg.name == "COMMAND_INT":
        p5, p6, p7 = int(f.get("x", 0)) / 1e7, int(f.get("y", 0)) / 1e7, float(f.get("z", 0.0))
    else:
        p5, p6, p7 = float(f.get("param5", 0.0)), float(f.get("param6", 0.0)), float(f.get("param7", 0.0))
    return command(
        t,
        int(f.get("command", 0)),
        (p1, p2, p3, p4, p5, p6, p7),
        (msg.sysid, msg.compid),
        (int(f.get("target_system", 0)), int(f.get("target_component", 0))),
        True,
    )


def handle_command(v: Vehicle, msg: Msg) -> list[Msg]:
    """Handle one COMMAND_LONG / COMMAND_INT; returns the COMMAND_ACK and any requested message."""
    if int(msg.fields.get("target_system", 0)) not in (0, mav.SYSTEM_ID):
        return []
    t = v.time_us
    c = vehicle_command(msg, t)
    v.recorder.data(c)
    extra: list[Msg] = []
    handler = HANDLERS.get(c.command)
    result = MavResult.UNSUPPORTED if handler is None else handler(v, c, extra)
    v.recorder.data(VehicleCommandAck(t, c.command, int(result), 0, 0, msg.sysid, msg.compid, True))
    v.drain_nav_events()
    ack = Msg(
        "COMMAND_ACK",
        {
            "command": c.command,
            "result": int(result),
            "progress": 0,
            "result_param2": 0,
            "target_system": msg.sysid,
            "target_component": msg.compid,
        },
    )
    return [ack, *extra]
