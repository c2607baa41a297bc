"""MAV_CMD_INJECT_FAILURE as PX4 v1.15 routes it.

``mavlink_receiver.cpp``: with ``SYS_FAILURE_EN`` 0 the command is answered DENIED at once;
otherwise it becomes a vehicle_command and the module that simulates the unit answers:
``FailureInjector`` (commander/failure_detector: SYSTEM_MOTOR), ``battery_simulator``
(SYSTEM_BATTERY: OK / OFF) and the simulator (SENSOR_GPS). PX4 sends no ACK at all for a unit
no module takes; the built-in vehicle says so instead: COMMAND_ACK UNSUPPORTED and a STATUSTEXT
"failure injection of <unit>/<type> not supported by the built-in simulator".
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from uavtest.mavlink_numbers import FailureType, FailureUnit
from uavtest.sitl.mav import MavResult, MavSeverity, Msg
from uavtest.sitl.ulog_writer import LOG_LEVEL
from uavtest.sitl.uorb import VehicleCommand

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["inject_failure"]


def _name(enum: type, value: int) -> str:
    try:
        return enum(value).name.lower()
    except ValueError:
        return str(value)


def inject_failure(v: Vehicle, c: VehicleCommand, extra: list[Msg]) -> MavResult:
    if int(v.params["SYS_FAILURE_EN"]) == 0:
        v.text(MavSeverity.CRITICAL, "Failure injection disabled by SYS_FAILURE_EN param")
        return MavResult.DENIED
    unit, kind, instance = int(c.param1 + 0.5), int(c.param2 + 0.5), int(c.param3 + 0.5)
    result: MavResult | None = None
    if unit == FailureUnit.SYSTEM_MOTOR:
        result = v.failure_injector.inject(kind, instance)
    elif unit == FailureUnit.SYSTEM_BATTERY:
        result = v.battery.inject(kind, instance) if v.battery.enabled else None
    elif unit == FailureUnit.SENSOR_GPS:
        result = v.gps.inject(kind, instance, v.time_us)
    what = f"{_name(FailureUnit, unit)}/{_name(FailureType, kind)}"
    if result == MavResult.ACCEPTED:  # PX4_WARN on the console: the log has it, no STATUSTEXT
        v.recorder.text(LOG_LEVEL["warning"], v.time_us, f"CMD_INJECT_FAILURE, {what} (instance {instance})")
        v.commander.status_dirty = True
        v.sim.faulty = True
        return result
    _long_text(v, MavSeverity.WARNING, f"failure injection of {what} not supported by the built-in simulator")
    return MavResult.UNSUPPORTED


def _long_text(v: Vehicle, severity: int, text: str) -> None:
    """A STATUSTEXT longer than 50 characters, in MAVLink 2 chunks (same id, chunk_seq 0, 1, ...)."""
    text_id = v.time_us // 1000 % 65535 + 1  # deterministic, distinct per message time
    chunks = [text[i : i + 50] for i in range(0, len(text), 50)]
    for seq, chunk in enumerate(chunks):
        v._out.append(
            Msg("STATUSTEXT", {"severity": int(severity), "text": chunk, "id": text_id, "chunk_seq": seq})
        )
    v.recorder.text(LOG_LEVEL["warning"], v.time_us, text)
