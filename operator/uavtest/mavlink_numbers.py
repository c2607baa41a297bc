"""MAVLink ``common.xml`` numbers both ends of the wire use: the simulator and the runner.

Plain ``IntEnum``s, no pymavlink (each end keeps pymavlink behind its own adapter module);
``tests/unit/sitl/test_modes.py`` checks them against pymavlink's dialect.
"""

from __future__ import annotations

from enum import IntEnum

__all__ = [
    "REPOSITION_FLAGS_CHANGE_MODE",
    "SYS_STATUS_PREARM_CHECK",
    "FailureType",
    "FailureUnit",
    "LandedState",
    "MavCmd",
    "MavFrame",
    "MavResult",
    "MissionResult",
    "ParamType",
    "PositionTargetMask",
]

#: MAV_SYS_STATUS_PREARM_CHECK: PX4 sets this bit of SYS_STATUS.onboard_control_sensors_health while
#: its pre-arm checks pass for the current mode (the same bit the simulator sets once it is ready)
SYS_STATUS_PREARM_CHECK = 0x10000000


class MavCmd(IntEnum):
    """MAV_CMD."""

    NAV_WAYPOINT = 16
    NAV_LOITER_UNLIM = 17
    NAV_LOITER_TIME = 19
    NAV_RETURN_TO_LAUNCH = 20
    NAV_LAND = 21
    NAV_TAKEOFF = 22
    DO_ORBIT = 34
    CONDITION_YAW = 115
    DO_SET_MODE = 176
    DO_CHANGE_SPEED = 178
    DO_SET_HOME = 179
    DO_LAND_START = 189
    DO_REPOSITION = 192
    MISSION_START = 300
    COMPONENT_ARM_DISARM = 400
    INJECT_FAILURE = 420
    SET_MESSAGE_INTERVAL = 511
    REQUEST_MESSAGE = 512
    REQUEST_AUTOPILOT_CAPABILITIES = 520
    SET_CAMERA_MODE = 530


class MavResult(IntEnum):
    """MAV_RESULT (COMMAND_ACK.result)."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4
    IN_PROGRESS = 5
    COMMAND_LONG_ONLY = 7
    COMMAND_INT_ONLY = 8


class MissionResult(IntEnum):
    """MAV_MISSION_RESULT (MISSION_ACK.type)."""

    ACCEPTED = 0
    ERROR = 1
    UNSUPPORTED_FRAME = 2
    UNSUPPORTED = 3
    NO_SPACE = 4
    INVALID = 5
    INVALID_PARAM1 = 6
    INVALID_PARAM2 = 7
    INVALID_PARAM3 = 8
    INVALID_PARAM4 = 9
    INVALID_PARAM5_X = 10
    INVALID_PARAM6_Y = 11
    INVALID_PARAM7 = 12
    INVALID_SEQUENCE = 13
    DENIED = 14
    OPERATION_CANCELLED = 15


class ParamType(IntEnum):
    """MAV_PARAM_TYPE (PX4 uses INT32 and REAL32)."""

    UINT8 = 1
    INT8 = 2
    UINT16 = 3
    INT16 = 4
    UINT32 = 5
    INT32 = 6
    UINT64 = 7
    INT64 = 8
    REAL32 = 9
    REAL64 = 10


class LandedState(IntEnum):
    """MAV_LANDED_STATE (EXTENDED_SYS_STATE.landed_state)."""

    UNDEFINED = 0
    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4


class MavFrame(IntEnum):
    """MAV_FRAME (the ones the runner sends and the simulator reads)."""

    GLOBAL = 0  # COMMAND_INT: altitude AMSL
    LOCAL_NED = 1
    GLOBAL_RELATIVE_ALT = 3
    GLOBAL_INT = 5
    GLOBAL_RELATIVE_ALT_INT = 6
    BODY_NED = 8
    GLOBAL_TERRAIN_ALT_INT = 11
    BODY_FRD = 12


class PositionTargetMask(IntEnum):
    """POSITION_TARGET_TYPEMASK: a set bit means the field is ignored."""

    X_IGNORE = 1
    Y_IGNORE = 2
    Z_IGNORE = 4
    VX_IGNORE = 8
    VY_IGNORE = 16
    VZ_IGNORE = 32
    AX_IGNORE = 64
    AY_IGNORE = 128
    AZ_IGNORE = 256
    FORCE_SET = 512
    YAW_IGNORE = 1024
    YAW_RATE_IGNORE = 2048


#: MAV_DO_REPOSITION_FLAGS_CHANGE_MODE: DO_REPOSITION param2; PX4 answers UNSUPPORTED without it
REPOSITION_FLAGS_CHANGE_MODE = 1


class FailureUnit(IntEnum):
    """FAILURE_UNIT (MAV_CMD_INJECT_FAILURE param1)."""

    SENSOR_GYRO = 0
    SENSOR_ACCEL = 1
    SENSOR_MAG = 2
    SENSOR_BARO = 3
    SENSOR_GPS = 4
    SENSOR_OPTICAL_FLOW = 5
    SENSOR_VIO = 6
    SENSOR_DISTANCE_SENSOR = 7
    SENSOR_AIRSPEED = 8
    SYSTEM_BATTERY = 100
    SYSTEM_MOTOR = 101
    SYSTEM_SERVO = 102
    SYSTEM_AVOIDANCE = 103
    SYSTEM_RC_SIGNAL = 104
    SYSTEM_MAVLINK_SIGNAL = 105


class FailureType(IntEnum):
    """FAILURE_TYPE (MAV_CMD_INJECT_FAILURE param2)."""

    OK = 0
    OFF = 1
    STUCK = 2
    GARBAGE = 3
    WRONG = 4
    SLOW = 5
    DELAYED = 6
    INTERMITTENT = 7
