"""PX4 and MAVLink conventions the runner relies on, as plain numbers (no pymavlink here).

PX4 packs its flight mode into HEARTBEAT.custom_mode: main mode in bits 16-23, sub mode in bits
24-31; DO_SET_MODE takes base mode MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, main mode, sub mode.
"""

from __future__ import annotations

from enum import IntEnum

from uavtest.mavlink_numbers import LandedState, MissionResult, ParamType
from uavtest.mavlink_numbers import MavCmd as Cmd
from uavtest.mavlink_numbers import MavResult as AckResult
from uavtest.px4.modes import AutoSubMode, MainMode, encode_custom_mode, split_custom_mode
from uavtest.spec.models import FlightMode

__all__ = [
    "AUTO_MODES",
    "FORCE_DISARM_MAGIC",
    "MODE_FLAG_CUSTOM_MODE_ENABLED",
    "PX4_MODES",
    "AckResult",
    "Autopilot",
    "Cmd",
    "LandedState",
    "MavType",
    "MissionResult",
    "ParamType",
    "custom_mode",
    "mode_name",
    "result_name",
]

MODE_FLAG_CUSTOM_MODE_ENABLED = 1
FORCE_DISARM_MAGIC = 21196.0  # ARM_DISARM param2: disarm even in the air


class Autopilot(IntEnum):
    GENERIC = 0
    PX4 = 12
    INVALID = 8


class MavType(IntEnum):
    GCS = 6
    ONBOARD_CONTROLLER = 18


def result_name(enum: type[IntEnum], value: int) -> str:
    """``DENIED`` for a known number, else the number."""
    try:
        return enum(value).name
    except ValueError:
        return str(value)


#: a test's flight modes as PX4 main/sub modes (numbers in ``uavtest.px4.modes``)
PX4_MODES: dict[FlightMode, tuple[int, int]] = {
    FlightMode.MANUAL: (MainMode.MANUAL, 0),
    FlightMode.ALTITUDE: (MainMode.ALTCTL, 0),
    FlightMode.POSITION: (MainMode.POSCTL, 0),
    FlightMode.MISSION: (MainMode.AUTO, AutoSubMode.MISSION),
    FlightMode.HOLD: (MainMode.AUTO, AutoSubMode.LOITER),
    FlightMode.RETURN: (MainMode.AUTO, AutoSubMode.RTL),
    FlightMode.LAND: (MainMode.AUTO, AutoSubMode.LAND),
    FlightMode.TAKEOFF: (MainMode.AUTO, AutoSubMode.TAKEOFF),
    FlightMode.OFFBOARD: (MainMode.OFFBOARD, 0),
}

#: modes in which the vehicle flies by itself: sticks stop when one of these is selected
AUTO_MODES = frozenset(
    {FlightMode.MISSION, FlightMode.HOLD, FlightMode.RETURN, FlightMode.LAND, FlightMode.TAKEOFF}
)


def custom_mode(mode: FlightMode) -> int:
    """HEARTBEAT.custom_mode of a PX4 flight mode."""
    return encode_custom_mode(*PX4_MODES[mode])


def mode_name(custom: int) -> str:
    """The FlightMode name of a PX4 custom_mode, or ``main/sub`` numbers when it is another mode."""
    main, sub = split_custom_mode(custom)
    for mode, (m, s) in PX4_MODES.items():
        if (m, s) == (main, sub) or (m != MainMode.AUTO and m == main):
            return mode.value
    return f"{main}/{sub}"
