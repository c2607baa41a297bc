"""COMMAND_LONG / COMMAND_INT → vehicle_command, handled by one function per command.

Like PX4's ``Commander::handle_command``: the command is logged as ``vehicle_command``, its
handler (``HANDLERS``, keyed by MAV_CMD) returns the MAV_RESULT, the result is logged as
``vehicle_command_ack`` and sent back as COMMAND_ACK (with any message the command asked for).
Commands without a handler are not modelled by the built-in simulator: they are answered
MAV_RESULT_UNSUPPORTED with a STATUSTEXT naming them (``unsupported``), never DENIED (DENIED means
the vehicle refused). Mode changes to a nav state the simulator does not fly go the same way
(``commander.FLOWN_NAV_STATES`` is the one table of flown modes).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from uavtest.px4.modes import NavState, nav_state_from_custom_mode
from uavtest.sitl import mav
from uavtest.sitl.commander.arming import Reason
from uavtest.sitl.commander.commander import FLOWN_NAV_STATES
from uavtest.sitl.commander.failure_injection import inject_failure
from uavtest.sitl.mav import MavCmd, MavResult, MavSeverity, Msg
from uavtest.sitl.mavlink_io import command_name, custom_mode_name
from uavtest.sitl.mavlink_streams import STREAMS, autopilot_version
from uavtest.sitl.telemetry import MESSAGE_IDS
from uavtest.sitl.uorb import VehicleCommand, VehicleCommandAck, command

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["HANDLERS", "MISSION_PLANNER", "Handler", "handle_command"]

#: (vehicle, command, replies to append to) → MAV_RESULT
Handler = Callable[["Vehicle", VehicleCommand, list[Msg]], MavResult]

_AUTOPILOT_VERSION = 148
_GET_MESSAGE_INTERVAL = 510  # MAV_CMD_GET_MESSAGE_INTERVAL


def unsupported(v: Vehicle, what: str) -> MavResult:
    """What the built-in vehicle does not model: a STATUSTEXT naming it, and UNSUPPORTED."""
    v.text(MavSeverity.WARNING, f"{what} not supported by the built-in simulator")
    return MavResult.UNSUPPORTED


_HOME_POSITION = 242
MISSION_PLANNER = 190  # MAV_COMP_ID_MISSIONPLANNER
_INT32_MAX = 2**31 - 1
#: VEHICLE_CMD_RESULT_CANCELLED (PX4 msg/VehicleCommandAck.msg; MAVLink MAV_RESULT_CANCELLED,
#: which the installed pymavlink's common dialect lacks, so MavResult does not carry it)
RESULT_CANCELLED = 6


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
        main, sub = int(c.param2), int(c.param3)
        ns = nav_state_from_custom_mode(main, sub)
        if ns is None or ns not in FLOWN_NAV_STATES:
            return unsupported(v, f"Mode {custom_mode_name(main, sub)}")
        # Commander.cpp: the refusal is printed only for a request from the mission planner
        return v.commander.set_mode(ns, announce=c.from_external and c.source_component == MISSION_PLANNER)
    return MavResult.DENIED


def _takeoff(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    cmdr = v.commander
    if cmdr.crashed:
        return MavResult.DENIED
    if not cmdr.may_switch(NavState.AUTO_TAKEOFF):
        return MavResult.TEMPORARILY_REJECTED
    p7 = c.param7
    alt = p7 - cmdr.home[5] + cmdr.home[2] if math.isfinite(p7) else None
    cmdr.user_mode_change()
    cmdr.intend(NavState.AUTO_TAKEOFF)
    cmdr.switch(NavState.AUTO_TAKEOFF, v.time_us, target_alt=alt)
    return MavResult.ACCEPTED


def _land(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    result = v.commander.set_mode(NavState.AUTO_LAND)
    if result == MavResult.ACCEPTED:
        v.text(MavSeverity.INFO, "Landing at current position")
    return result


def _return(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    result = v.commander.set_mode(NavState.AUTO_RTL)
    if result == MavResult.ACCEPTED:
        v.text(MavSeverity.INFO, "Returning to launch")
    return result


def _mission_start(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """Commander.cpp MISSION_START: DENIED without a valid mission ("Mission start denied! No
    valid mission") or a first item out of range; else the mode changes to Mission and the
    vehicle arms, both or TEMPORARILY_REJECTED ("Switching to Mission is currently not
    available")."""
    if not v.nav.mission_valid:  # a mission loaded and feasible
        v.text(MavSeverity.CRITICAL, "Mission start denied! No valid mission")
        return MavResult.DENIED
    first = int(c.param1) if math.isfinite(c.param1) else 0
    if not -1 <= first < len(v.nav.mission):
        return MavResult.DENIED
    if first > 0:
        v.nav.set_current(first, v.time_us / 1e6)
    cmdr = v.commander
    result = cmdr.set_mode(NavState.AUTO_MISSION, announce=False)
    if result == MavResult.ACCEPTED and not cmdr.armed:
        result = cmdr.arm(v.time_us, Reason.MISSION_START)
    if result != MavResult.ACCEPTED:
        v.text(MavSeverity.CRITICAL, "Switching to Mission is currently not available")
        return MavResult.TEMPORARILY_REJECTED
    return result


def _change_speed(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """PX4 navigator_main.cpp VEHICLE_CMD_DO_CHANGE_SPEED: param2 > 0 sets the cruise speed (in
    mission, hold and return alike), anything else resets it; always ACCEPTED."""
    if c.param2 > 0:
        v.nav.speed = c.param2
    else:
        v.nav.speed = math.nan
    return MavResult.ACCEPTED


def _local_z(v: Vehicle, amsl: float) -> float | None:
    return v.home_alt - amsl if math.isfinite(amsl) else None


def _reposition(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """DO_REPOSITION (Commander.cpp: only with MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, else
    UNSUPPORTED; switches to Hold; navigator_main.cpp moves the hold point only when armed):
    param1 ground speed (<= 0: cruise), param4 yaw in radians as PX4 v1.15 reads it (NaN: along
    the way), param5/6 lat/lon (NaN: keep), param7 altitude AMSL (NaN: keep)."""
    flags = int(c.param2) if math.isfinite(c.param2) else 0
    if not flags & 1 or flags & ~1:
        v.text(MavSeverity.WARNING, "Reposition without CHANGE_MODE flag unsupported")
        return MavResult.UNSUPPORTED
    cmdr = v.commander
    if cmdr.crashed:
        return MavResult.TEMPORARILY_REJECTED
    result = cmdr.set_mode(NavState.AUTO_LOITER)
    if result == MavResult.ACCEPTED and cmdr.armed:
        x = y = None
        if math.isfinite(c.param5) and math.isfinite(c.param6):
            x, y = v.proj.project(c.param5, c.param6)
        speed = c.param1 if math.isfinite(c.param1) and c.param1 > 0 else math.nan
        z = _local_z(v, c.param7)
        gx, gy = (v.st.x, v.st.y) if x is None or y is None else (x, y)
        if v.nav.geofence_allows_position(gx, gy, -(v.st.z if z is None else z)):
            yaw = c.param4 if math.isfinite(c.param4) else math.nan
            v.nav.reposition(v.st, x, y, z, yaw, speed)
        else:  # navigator_main.cpp: the hold stays where it was; commander has ACKed already
            v.text(MavSeverity.CRITICAL, "Reposition is outside geofence")
    return result


def _orbit(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """DO_ORBIT (Commander.cpp: switch to nav state ORBIT, ACCEPTED; the Orbit flight task takes
    the parameters, FlightTaskOrbit.cpp): see ``flight_task_orbit``."""
    cmdr = v.commander
    if cmdr.crashed or not cmdr.may_switch(NavState.ORBIT, announce=False):
        v.text(MavSeverity.CRITICAL, "Orbit command rejected")
        return MavResult.TEMPORARILY_REJECTED
    cmdr.user_mode_change()
    cmdr.intend(NavState.ORBIT)
    cmdr.failsafe = False
    cmdr.switch(NavState.ORBIT, v.time_us)
    x = y = None
    if math.isfinite(c.param5) and math.isfinite(c.param6):
        x, y = v.proj.project(c.param5, c.param6)
    orbit = v.nav.orbit
    orbit.rad_max = v.params["MC_ORBIT_RAD_MAX"]
    if not orbit.apply_command(
        (c.param1, c.param2, c.param3, c.param4, x, y, _local_z(v, c.param7)), v.st.yaw
    ):
        v.text(MavSeverity.CRITICAL, "Orbit radius limit exceeded")
        # PX4 switches to its failsafe flight task; the built-in vehicle holds where it is
        cmdr.switch(NavState.AUTO_LOITER, v.time_us)
    return MavResult.ACCEPTED


def _land_start(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """DO_LAND_START (navigator_main.cpp): with a DO_LAND_START item in the mission, MISSION_START
    from it (ACCEPTED); without one, CANCELLED ("planned mission landing not available")."""
    index = v.nav.land_start_index()
    if index is None:
        v.text(MavSeverity.WARNING, "planned mission landing not available")
        return RESULT_CANCELLED  # type: ignore[return-value]
    cmdr = v.commander
    v.nav.set_current(index, v.time_us / 1e6)
    if cmdr.armed and not v.land.landed:
        cmdr.set_mode(NavState.AUTO_MISSION)
    return MavResult.ACCEPTED


def _condition_yaw(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """CONDITION_YAW as a command: PX4 v1.15 has no handler for it (Commander.cpp default case:
    UNSUPPORTED); it only exists there as a mission item."""
    v.text(MavSeverity.WARNING, "CONDITION_YAW command unsupported (as PX4 v1.15)")
    return MavResult.UNSUPPORTED


def _message_interval(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """mavlink_receiver.cpp: on the link the command came from; FAILED for HEARTBEAT and for
    messages not streamed."""
    if v.schedule.set_interval(round(c.param1), c.param2, v.time_us):
        return MavResult.ACCEPTED
    return MavResult.FAILED


def _get_message_interval(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    """mavlink_receiver.cpp ``get_message_interval``: MESSAGE_INTERVAL of this link (0: not streamed)."""
    mid = round(c.param1)
    extra.append(Msg("MESSAGE_INTERVAL", {"message_id": mid, "interval_us": v.schedule.interval(mid)}))
    return MavResult.ACCEPTED


def _request(v: Vehicle, wanted: int, extra: list[Msg]) -> MavResult:
    if wanted == _AUTOPILOT_VERSION:
        extra.append(autopilot_version(v))
    elif wanted in MESSAGE_IDS and (wanted != _HOME_POSITION or v.home_set):
        msg = STREAMS[MESSAGE_IDS[wanted]](v, v.time_us)
        if msg is None:  # a stream with nothing to send (no range sensor, CP not running)
            return MavResult.DENIED
        extra.append(msg)
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
    MavCmd.DO_REPOSITION: _reposition,
    MavCmd.DO_ORBIT: _orbit,
    MavCmd.DO_LAND_START: _land_start,
    MavCmd.CONDITION_YAW: _condition_yaw,
    MavCmd.SET_MESSAGE_INTERVAL: _message_interval,
    _GET_MESSAGE_INTERVAL: _get_message_interval,
    MavCmd.REQUEST_MESSAGE: _request_message,
    MavCmd.REQUEST_AUTOPILOT_CAPABILITIES: _request_capabilities,
    MavCmd.INJECT_FAILURE: inject_failure,
}


def vehicle_command(msg: Msg, t: int) -> VehicleCommand:
    """The vehicle_command of a COMMAND_LONG or COMMAND_INT (x, y in 1e-7 degrees)."""
    f = msg.fields
    p1, p2, p3, p4 = (float(f.get(k, 0.0)) for k in ("param1", "param2", "param3", "param4"))
    if msg.name == "COMMAND_INT":
        x, y = int(f.get("x", 0)), int(f.get("y", 0))
        if x == _INT32_MAX and y == _INT32_MAX:  # mavlink_receiver.cpp: "not given" → NaN
            p5 = p6 = math.nan
        else:
            p5, p6 = x / 1e7, y / 1e7
        p7 = float(f.get("z", 0.0))
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
    result = unsupported(v, command_name(c.command)) if handler is None else handler(v, c, extra)
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
