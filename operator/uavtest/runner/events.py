"""The runner's vocabulary: decoded MAVLink messages in, messages to send out.

Frozen, slotted dataclasses that validate on construction (as h11's events). The pure runner core
speaks only these; ``uavtest.runner.link`` is the one place that turns them into MAVLink bytes
and back. Outgoing messages carry no target system: the link addresses the connected vehicle.
"""

from __future__ import annotations

from dataclasses import dataclass

from uavtest.mavlink_numbers import SYS_STATUS_PREARM_CHECK

__all__ = [
    "ARMED_FLAG",
    "Attitude",
    "CommandAck",
    "CommandInt",
    "CommandLong",
    "ExtendedSysState",
    "GcsHeartbeat",
    "GlobalPosition",
    "Heartbeat",
    "HomePosition",
    "Incoming",
    "LocalPosition",
    "LockstepAnnounce",
    "LockstepGrant",
    "LogData",
    "LogEntry",
    "LogRequestData",
    "LogRequestEnd",
    "LogRequestList",
    "ManualControl",
    "MissionAck",
    "MissionCount",
    "MissionCurrent",
    "MissionItemInt",
    "MissionItemReached",
    "MissionRequest",
    "ObstacleDistance",
    "Outgoing",
    "ParamRequestRead",
    "ParamSet",
    "ParamValue",
    "PositionTargetGlobal",
    "PositionTargetLocal",
    "StatusText",
    "SysStatus",
    "VehicleTime",
]

ARMED_FLAG = 128  # MAV_MODE_FLAG_SAFETY_ARMED


# --------------------------------------------------------------------------- from the vehicle


@dataclass(frozen=True, slots=True)
class Heartbeat:
    sysid: int
    compid: int
    type: int
    autopilot: int
    base_mode: int
    custom_mode: int
    system_status: int

    @property
    def armed(self) -> bool:
        return bool(self.base_mode & ARMED_FLAG)


@dataclass(frozen=True, slots=True)
class LocalPosition:
    """LOCAL_POSITION_NED: metres from home, z Down."""

    time_ms: int
    x: float
    y: float
    z: float


@dataclass(frozen=True, slots=True)
class Attitude:
    """ATTITUDE, reduced to the heading (rad, clockwise from North): read only while the runner
    sends a scanning range sensor's OBSTACLE_DISTANCE (``uavtest.runner.obstacle_distance``)."""

    time_ms: int
    yaw: float


@dataclass(frozen=True, slots=True)
class GlobalPosition:
    """GLOBAL_POSITION_INT: degE7, relative altitude in mm."""

    time_ms: int
    lat: int
    lon: int
    relative_alt_mm: int


@dataclass(frozen=True, slots=True)
class HomePosition:
    """HOME_POSITION: where the vehicle's home is, degE7 and altitude AMSL in mm."""

    lat: int
    lon: int
    alt_mm: int


@dataclass(frozen=True, slots=True)
class VehicleTime:
    """Any other message stamped with time_boot_ms (SYSTEM_TIME, ATTITUDE)."""

    time_ms: int


@dataclass(frozen=True, slots=True)
class ParamValue:
    name: str
    value: float  # the wire float; INT32 parameters are byte-wise inside it
    param_type: int
    index: int = 0
    count: int = 0


@dataclass(frozen=True, slots=True)
class MissionRequest:
    """MISSION_REQUEST_INT or (older) MISSION_REQUEST: the vehicle asks for item ``seq``."""

    seq: int
    mission_type: int = 0


@dataclass(frozen=True, slots=True)
class MissionAck:
    result: int
    mission_type: int = 0


@dataclass(frozen=True, slots=True)
class MissionItemReached:
    seq: int


@dataclass(frozen=True, slots=True)
class MissionCurrent:
    seq: int


@dataclass(frozen=True, slots=True)
class CommandAck:
    command: int
    result: int


@dataclass(frozen=True, slots=True)
class ExtendedSysState:
    landed_state: int  # MAV_LANDED_STATE: 0 unknown, 1 on ground, 2 in air, 3 takeoff, 4 landing


@dataclass(frozen=True, slots=True)
class SysStatus:
    """SYS_STATUS, reduced to what the runner uses: PX4 sets MAV_SYS_STATUS_PREARM_CHECK in
    ``onboard_control_sensors_health`` while its pre-arm checks pass in the current mode."""

    sensors_health: int

    @property
    def ready_to_arm(self) -> bool:
        return bool(self.sensors_health & SYS_STATUS_PREARM_CHECK)


@dataclass(frozen=True, slots=True)
class StatusText:
    severity: int
    text: str


@dataclass(frozen=True, slots=True)
class LockstepAnnounce:
    """NAMED_VALUE_INT "LOCKSTEP": the simulator waits at vehicle time ``time_ms`` for a grant."""

    time_ms: int


@dataclass(frozen=True, slots=True)
class LogEntry:
    id: int
    num_logs: int
    last_log_num: int
    size: int


@dataclass(frozen=True, slots=True)
class LogData:
    id: int
    ofs: int
    data: bytes


Incoming = (
    Heartbeat
    | LocalPosition
    | Attitude
    | GlobalPosition
    | HomePosition
    | VehicleTime
    | ParamValue
    | MissionRequest
    | MissionAck
    | MissionItemReached
    | MissionCurrent
    | CommandAck
    | ExtendedSysState
    | StatusText
    | LockstepAnnounce
    | LogEntry
    | LogData
)


# --------------------------------------------------------------------------- to the vehicle


@dataclass(frozen=True, slots=True)
class GcsHeartbeat:
    """HEARTBEAT of a ground station (MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID)."""


def _name16(name: str) -> None:
    if not name or len(name.encode()) > 16:
        raise ValueError(f"parameter name must be 1-16 bytes: {name!r}")


@dataclass(frozen=True, slots=True)
class ParamRequestRead:
    name: str

    def __post_init__(self) -> None:
        _name16(self.name)


@dataclass(frozen=True, slots=True)
class ParamSet:
    name: str
    value: float  # the wire float (already byte-wise encoded for integer types)
    param_type: int

    def __post_init__(self) -> None:
        _name16(self.name)
        if not 1 <= self.param_type <= 10:
            raise ValueError(f"MAV_PARAM_TYPE must be 1-10, got {self.param_type}")


@dataclass(frozen=True, slots=True)
class MissionCount:
    count: int

    def __post_init__(self) -> None:
        if not 0 <= self.count <= 65535:
            raise ValueError(f"mission count out of range: {self.count}")


@dataclass(frozen=True, slots=True)
class MissionItemInt:
    seq: int
    frame: int
    command: int
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0  # latitude degE7
    y: int = 0  # longitude degE7
    z: float = 0.0  # altitude, metres (relative to home in frame 6)
    current: int = 0
    autocontinue: int = 1


@dataclass(frozen=True, slots=True)
class CommandLong:
    command: int
    params: tuple[float, float, float, float, float, float, float] = (0.0,) * 7
    confirmation: int = 0

    def __post_init__(self) -> None:
        if len(self.params) != 7:
            raise ValueError("COMMAND_LONG has exactly 7 params")


@dataclass(frozen=True, slots=True)
class CommandInt:
    """COMMAND_INT: params 1-4, x / y latitude / longitude in degE7, z altitude in ``frame``."""

    command: int
    frame: int
    params: tuple[float, float, float, float] = (0.0,) * 4
    x: int = 0
    y: int = 0
    z: float = 0.0

    def __post_init__(self) -> None:
        if len(self.params) != 4:
            raise ValueError("COMMAND_INT has exactly 4 params (5-7 are x, y, z)")
        for name in ("x", "y"):
            if not -(2**31) <= getattr(self, name) < 2**31:
                raise ValueError(f"COMMAND_INT {name} must fit INT32")


@dataclass(frozen=True, slots=True)
class PositionTargetLocal:
    """SET_POSITION_TARGET_LOCAL_NED in MAV_FRAME_LOCAL_NED: metres, m/s, radians, rad/s; a set
    bit of ``type_mask`` (POSITION_TARGET_TYPEMASK) ignores its field."""

    time_ms: int
    type_mask: int
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    yaw: float = 0.0
    yaw_rate: float = 0.0

    def __post_init__(self) -> None:
        if not 0 <= self.type_mask <= 0xFFFF:
            raise ValueError("type_mask is a UINT16")


@dataclass(frozen=True, slots=True)
class PositionTargetGlobal:
    """SET_POSITION_TARGET_GLOBAL_INT in MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: degE7, metres above
    home, m/s NED, radians, rad/s."""

    time_ms: int
    type_mask: int
    lat: int = 0
    lon: int = 0
    alt: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    yaw: float = 0.0
    yaw_rate: float = 0.0

    def __post_init__(self) -> None:
        if not 0 <= self.type_mask <= 0xFFFF:
            raise ValueError("type_mask is a UINT16")


@dataclass(frozen=True, slots=True)
class ManualControl:
    """MANUAL_CONTROL: x, y, r in [-1000, 1000]; z (throttle) in [0, 1000], 500 holds altitude."""

    x: int
    y: int
    z: int
    r: int

    def __post_init__(self) -> None:
        for axis in ("x", "y", "r"):
            if not -1000 <= getattr(self, axis) <= 1000:
                raise ValueError(f"MANUAL_CONTROL {axis} must be in [-1000, 1000]")
        if not 0 <= self.z <= 1000:
            raise ValueError("MANUAL_CONTROL z must be in [0, 1000]")


@dataclass(frozen=True, slots=True)
class ObstacleDistance:
    """OBSTACLE_DISTANCE: a scan of ``len(distances)`` bins (cm; UINT16_MAX no data, max + 1
    nothing in range) of ``increment`` degrees from ``angle_offset``, in ``frame``."""

    time_usec: int
    distances: tuple[int, ...]
    min_cm: int
    max_cm: int
    increment: float
    angle_offset: float
    frame: int
    sensor_type: int = 0  # MAV_DISTANCE_SENSOR_LASER


@dataclass(frozen=True, slots=True)
class LockstepGrant:
    """NAMED_VALUE_INT "LOCKSTEP": simulate from ``seen_ms`` up to ``until_ms``."""

    seen_ms: int
    until_ms: int

    def __post_init__(self) -> None:
        if self.until_ms <= self.seen_ms:
            raise ValueError(f"a grant must move time forward ({self.seen_ms} -> {self.until_ms})")


@dataclass(frozen=True, slots=True)
class LogRequestList:
    start: int = 0
    end: int = 0xFFFF


@dataclass(frozen=True, slots=True)
class LogRequestData:
    id: int
    ofs: int
    count: int


@dataclass(frozen=True, slots=True)
class LogRequestEnd:
    pass


Outgoing = (
    GcsHeartbeat
    | ParamRequestRead
    | ParamSet
    | MissionCount
    | MissionItemInt
    | CommandLong
    | CommandInt
    | ManualControl
    | ObstacleDistance
    | PositionTargetLocal
    | PositionTargetGlobal
    | LockstepGrant
    | LogRequestList
    | LogRequestData
    | LogRequestEnd
)
