"""MAVLink messages as plain data, and the MAVLink numbers the simulator uses.

The vehicle logic speaks in ``Msg`` values (a MAVLink message name and its fields, named as
in the MAVLink XML); ``mavlink_io`` is the one place that turns them into bytes and back.
The enum values are MAVLink ``common.xml`` numbers (checked against pymavlink in the tests).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

from uavtest.mavlink_numbers import (
    SYS_STATUS_PREARM_CHECK,
    LandedState,
    MavCmd,
    MavResult,
    MissionResult,
    ParamType,
)

__all__ = [
    "SYS_STATUS_PREARM_CHECK",
    "SYS_STATUS_SENSORS",
    "LandedState",
    "MavCmd",
    "MavFrame",
    "MavResult",
    "MavSeverity",
    "MavState",
    "MissionResult",
    "MissionType",
    "Msg",
    "ParamType",
]

SYSTEM_ID = 1
COMPONENT_ID = 1
MAV_TYPE_QUADROTOR = 2
MAV_TYPE_GCS = 6
MAV_AUTOPILOT_PX4 = 12
FORCE_DISARM_MAGIC = 21196


@dataclass(frozen=True, slots=True)
class Msg:
    """One MAVLink message: its name (``"HEARTBEAT"``) and fields; sender ids when received."""

    name: str
    fields: Mapping[str, Any] = field(default_factory=dict)
    sysid: int = 0
    compid: int = 0

    def get(self, key: str, default: Any = None) -> Any:
        return self.fields.get(key, default)


class MissionType(IntEnum):
    MISSION = 0
    FENCE = 1
    RALLY = 2
    ALL = 255


class MavFrame(IntEnum):
    GLOBAL = 0
    LOCAL_NED = 1
    MISSION = 2
    GLOBAL_RELATIVE_ALT = 3
    GLOBAL_INT = 5
    GLOBAL_RELATIVE_ALT_INT = 6


class MavState(IntEnum):
    UNINIT = 0
    BOOT = 1
    STANDBY = 3
    ACTIVE = 4
    CRITICAL = 5
    EMERGENCY = 6


class MavSeverity(IntEnum):
    EMERGENCY = 0
    ALERT = 1
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6
    DEBUG = 7


# MAV_SYS_STATUS_SENSOR bits a healthy PX4 multicopter reports (gyro, accel, mag, baro, GPS,
# angular rate / attitude / yaw / z-altitude / xy-position control, motor outputs, AHRS,
# battery) plus MAV_SYS_STATUS_PREARM_CHECK (set when ready to arm).
SYS_STATUS_SENSORS = 1 | 2 | 4 | 8 | 32 | 1024 | 2048 | 4096 | 8192 | 16384 | 32768 | 2097152 | 33554432
SYS_STATUS_GPS = 32
