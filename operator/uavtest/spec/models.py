"""Pydantic models of a UavTest: the single source of the test file format and of the CRD.

Field names are camelCase on the wire (Kubernetes API conventions) and snake_case in Python.
Unknown fields are rejected so a typo is reported with its field path.
Coordinates are PX4 local NED (x North, y East, z Down, metres from home).
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from pydantic.alias_generators import to_camel

from uavtest.spec.bounds import (
    LOCAL_MAX,
    Altitude,
    AltitudeAmsl,
    Degrees,
    Distance,
    Down,
    Duration,
    FaultInstance,
    Height,
    Latitude,
    Local,
    Longitude,
    NonNegativeDuration,
    ObstacleSize,
    OrbitRadius,
    ParamFloat,
    ParamInt,
    PositiveDistance,
    Seed,
    Speed,
    SpeedFactor,
    StickAxis,
    Throttle,
    Velocity,
    WindSpeed,
    YawRate,
)

__all__ = [
    "API_GROUP",
    "API_VERSION",
    "KIND",
    "Assertions",
    "Avoidance",
    "BoxPosition",
    "BoxSize",
    "Command",
    "CommandAction",
    "Fault",
    "FaultType",
    "FaultUnit",
    "FlightMode",
    "Geofence",
    "Goto",
    "Home",
    "Metadata",
    "Mission",
    "MissionItem",
    "MissionItemKind",
    "Obstacle",
    "Orbit",
    "RangeSensor",
    "ReferenceTrajectory",
    "Setpoint",
    "SetpointFrame",
    "Similarity",
    "SimilarityMetric",
    "Simulator",
    "Sticks",
    "UavTest",
    "UavTestSpec",
    "Vehicle",
    "Waypoint",
    "Wind",
    "World",
    "YawCommand",
    "YawDirection",
]

API_GROUP = "uavtest.io"
API_VERSION = f"{API_GROUP}/v1alpha1"
KIND = "UavTest"


class Model(BaseModel):
    """Base: camelCase aliases, forbid unknown fields, accept both spellings in Python."""

    model_config = ConfigDict(
        alias_generator=to_camel,
        populate_by_name=True,
        extra="forbid",
        frozen=False,
    )

    def dump(self) -> dict[str, Any]:
        """The wire form: camelCase keys, defaults left out where unset."""
        return self.model_dump(by_alias=True, exclude_none=True, mode="json")


# --------------------------------------------------------------------------- vehicle


class Simulator(StrEnum):
    BUILTIN = "builtin"
    PX4 = "px4"


class Avoidance(StrEnum):
    """What keeps the vehicle off obstacles, besides the pilot or the plan."""

    NONE = "none"  # PX4 v1.15 defaults: nothing; a box on the path is a collision
    COLLISION_PREVENTION = "collision-prevention"  # PX4's CP_* in position mode, fed by a range sensor
    LOCAL_PLANNER = "local-planner"  # PX4-Avoidance's local planner (COM_OBS_AVOID 1), the competition's SUT


class RangeSensor(Model):
    """The simulated scanning range sensor (2-D lidar) that feeds Collision Prevention
    (``obstacle_distance``: 72 bins of 5 degrees, body frame): the built-in vehicle carries it; for
    PX4 SITL the runner sends its scans (``uavtest.runner.obstacle_distance``)."""

    fov: float = Field(
        360.0,
        gt=0,
        le=360,
        allow_inf_nan=False,
        description="horizontal field of view, degrees, centred on the vehicle's front",
    )
    min_range: float = Field(0.2, ge=0, le=10, allow_inf_nan=False, description="minimum distance, metres")
    max_range: float = Field(12.0, gt=0, le=600, allow_inf_nan=False, description="maximum distance, metres")
    rate: float = Field(10.0, gt=0, le=50, allow_inf_nan=False, description="scans per second, Hz")

    @model_validator(mode="after")
    def _min_below_max(self) -> RangeSensor:
        if self.min_range >= self.max_range:
            raise ValueError(f"minRange {self.min_range} is not below maxRange {self.max_range}")
        return self


#: PX4 parameters are INT32 or FLOAT; a float must be finite
ParamValue = ParamInt | ParamFloat


class Vehicle(Model):
    simulator: Simulator = Field(Simulator.BUILTIN, description="builtin (uavtest sitl) or px4 (PX4 SITL)")
    image: str | None = Field(None, description="container image of the simulator (cluster engine only)")
    params: dict[str, ParamValue] = Field(
        default_factory=dict, max_length=1000, description="PX4 parameters set before flight, NAME: value"
    )
    params_file: str | None = Field(
        None, description="PX4 params CSV (NAME, value); relative to the test file; inlined by render"
    )
    avoidance: Avoidance = Field(
        Avoidance.NONE,
        description=(
            "none; collision-prevention (PX4 Collision Prevention in position mode, a simulated "
            "range sensor); local-planner (PX4-Avoidance's local planner in missions, as the UAV "
            "Testing Competition flies)"
        ),
    )
    range_sensor: RangeSensor | None = Field(
        None,
        description=(
            "the simulated range sensor (px4: the runner sends PX4 its scans as OBSTACLE_DISTANCE); "
            "attached with avoidance collision-prevention (these defaults if not given) or when given"
        ),
    )
    speed_factor: SpeedFactor | None = Field(
        None,
        description=(
            "simulator: px4 only: PX4_SIM_SPEED_FACTOR, times real time; "
            "default: the engine's measured reliable speed (the built-in simulator runs lockstep, "
            "as fast as it can)"
        ),
    )


# --------------------------------------------------------------------------- world


class Home(Model):
    lat: Latitude = Field(47.397742, description="latitude, degrees")
    lon: Longitude = Field(8.545594, description="longitude, degrees")
    alt: AltitudeAmsl = Field(488.0, description="altitude AMSL, metres")


class BoxSize(Model):
    l: ObstacleSize = Field(description="length along x (North) before yaw, metres")  # noqa: E741
    w: ObstacleSize = Field(description="width along y (East) before yaw, metres")
    h: ObstacleSize = Field(description="height, metres")


class BoxPosition(Model):
    x: Local = Field(description="centre North, metres")
    y: Local = Field(description="centre East, metres")
    z: Altitude = Field(0.0, description="base height above ground, metres (Aerialist convention, up)")
    r: Degrees = Field(0.0, description="yaw, degrees")


class Obstacle(Model):
    size: BoxSize
    position: BoxPosition


class Wind(Model):
    mean_speed: WindSpeed = Field(0.0, description="mean wind speed, m/s")
    max_speed: WindSpeed | None = Field(None, description="maximum speed in gusts, m/s")
    direction: Degrees = Field(0.0, description="direction the wind blows towards, degrees from North")
    gusts: bool = Field(True, description="random gusts between mean and max speed")

    @model_validator(mode="after")
    def _max_not_below_mean(self) -> Wind:
        if self.max_speed is not None and self.max_speed < self.mean_speed:
            raise ValueError(f"maxSpeed {self.max_speed} is below meanSpeed {self.mean_speed}")
        return self


class World(Model):
    home: Home = Field(default_factory=Home)
    obstacles: list[Obstacle] = Field(default_factory=list, max_length=100, description="box obstacles")
    wind: Wind = Field(default_factory=Wind)


# --------------------------------------------------------------------------- mission


class MissionItemKind(StrEnum):
    """Mission item kinds, with their MAV_CMD numbers in ``MISSION_ITEM_CMD``."""

    TAKEOFF = "takeoff"
    WAYPOINT = "waypoint"
    LAND = "land"
    RETURN = "return"
    LOITER_TIME = "loiterTime"
    CHANGE_SPEED = "changeSpeed"
    LAND_START = "landStart"  # DO_LAND_START: a marker MAV_CMD_DO_LAND_START (and Return, RTL_TYPE) jumps to


MISSION_ITEM_CMD: dict[MissionItemKind, int] = {
    MissionItemKind.TAKEOFF: 22,
    MissionItemKind.WAYPOINT: 16,
    MissionItemKind.LAND: 21,
    MissionItemKind.RETURN: 20,
    MissionItemKind.LOITER_TIME: 19,
    MissionItemKind.CHANGE_SPEED: 178,
    MissionItemKind.LAND_START: 189,
}


class MissionItem(Model):
    """One mission item in global coordinates, altitude relative to home (MAV_FRAME_GLOBAL_RELATIVE_ALT)."""

    kind: MissionItemKind
    lat: Latitude | None = None
    lon: Longitude | None = None
    alt: Altitude | None = Field(None, description="metres above home")
    hold: NonNegativeDuration = Field(0.0, description="hold / loiter time at the item, seconds")
    speed: Speed | None = Field(None, description="changeSpeed: ground speed m/s")
    yaw: Degrees | None = Field(
        None,
        description="takeoff, waypoint, loiterTime, land: heading, degrees clockwise from North "
        "(param4); none: PX4's MPC_YAW_MODE",
    )


class Waypoint(Model):
    """A NED waypoint relative to home: z is Down, so 10 m up is z: -10."""

    x: Local = Field(description="North, metres")
    y: Local = Field(description="East, metres")
    z: Down = Field(description="Down, metres; negative is up")
    hold: NonNegativeDuration = Field(0.0, description="seconds to hold at the waypoint")
    yaw: Degrees | None = Field(
        None,
        description="heading on the way to and at the waypoint, degrees clockwise from North "
        "(MAV_CMD_NAV_WAYPOINT param4); default: PX4's MPC_YAW_MODE (0: face the waypoint)",
    )


class Mission(Model):
    plan: dict[str, Any] | None = Field(
        None, description="inline QGroundControl .plan document (JSON as YAML)"
    )
    plan_file: str | None = Field(None, description="QGroundControl .plan file; inlined by render")
    waypoints: list[Waypoint] | None = Field(
        None, max_length=1000, description="NED waypoints, flown after takeoff"
    )
    takeoff_altitude: Height = Field(10.0, description="metres above home")
    takeoff_speed: Speed | None = Field(None, description="climb speed m/s (PX4 MPC_TKO_SPEED)")
    land: bool = Field(True, description="land at the end of a waypoint mission")

    @model_validator(mode="after")
    def _one_source(self) -> Mission:
        sources = [
            n
            for n, v in (("plan", self.plan), ("planFile", self.plan_file), ("waypoints", self.waypoints))
            if v is not None
        ]
        if len(sources) > 1:
            raise ValueError(f"give only one of plan, planFile, waypoints (got {', '.join(sources)})")
        if not sources:
            raise ValueError("give one of plan, planFile or waypoints")
        return self


# --------------------------------------------------------------------------- commands


class FlightMode(StrEnum):
    MANUAL = "manual"
    ALTITUDE = "altitude"
    POSITION = "position"
    MISSION = "mission"
    HOLD = "hold"
    RETURN = "return"
    LAND = "land"
    TAKEOFF = "takeoff"
    OFFBOARD = "offboard"


class CommandAction(StrEnum):
    ARM = "arm"
    DISARM = "disarm"
    MODE = "mode"
    STICKS = "sticks"
    SPEED = "speed"
    SETPOINT = "setpoint"
    GOTO = "goto"
    ORBIT = "orbit"
    LAND_START = "land_start"
    YAW = "yaw"


class Sticks(Model):
    """MANUAL_CONTROL sticks: x, y, r in [-1, 1]; z (throttle) in [0, 1], 0.5 holds altitude."""

    x: StickAxis = 0.0
    y: StickAxis = 0.0
    z: Throttle = 0.5
    r: StickAxis = 0.0


class SetpointFrame(StrEnum):
    LOCAL = "local"  # SET_POSITION_TARGET_LOCAL_NED, MAV_FRAME_LOCAL_NED
    GLOBAL = "global"  # SET_POSITION_TARGET_GLOBAL_INT, MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def _given(model: BaseModel, *names: str) -> list[str]:
    """The camelCase names of the fields of ``names`` that are set (not None)."""
    return [to_camel(n) for n in names if getattr(model, n) is not None]


class Setpoint(Model):
    """An offboard setpoint, streamed at 20 Hz until the next one, a non-offboard mode or a disarm.

    Local frame (default): position ``x, y, z`` (NED metres from home) and / or velocity
    ``vx, vy, vz`` (NED m/s); every axis needs its position or its velocity (PX4's position
    controller refuses a setpoint with an axis that has neither). Global frame: ``lat, lon, alt``
    (alt metres above home), optionally with a velocity. ``yaw`` (deg) or ``yawRate`` (deg/s),
    not both.
    """

    frame: SetpointFrame = Field(SetpointFrame.LOCAL, description="local (NED) or global (lat/lon/alt)")
    x: Local | None = Field(None, description="North, metres")
    y: Local | None = Field(None, description="East, metres")
    z: Down | None = Field(None, description="Down, metres; negative is up")
    lat: Latitude | None = Field(None, description="global frame: latitude, degrees")
    lon: Longitude | None = Field(None, description="global frame: longitude, degrees")
    alt: Altitude | None = Field(None, description="global frame: metres above home")
    vx: Velocity | None = Field(None, description="North velocity, m/s")
    vy: Velocity | None = Field(None, description="East velocity, m/s")
    vz: Velocity | None = Field(None, description="Down velocity, m/s; negative climbs")
    yaw: Degrees | None = Field(None, description="heading, degrees from North")
    yaw_rate: YawRate | None = Field(None, description="yaw rate, deg/s (positive clockwise)")

    @model_validator(mode="after")
    def _px4_type_mask_rules(self) -> Setpoint:
        if self.yaw is not None and self.yaw_rate is not None:
            raise ValueError("give yaw or yawRate, not both (PX4 ignores one of them)")
        if self.frame is SetpointFrame.GLOBAL:
            wrong = _given(self, "x", "y", "z")
            if wrong:
                raise ValueError(f"frame global takes lat, lon, alt, not {', '.join(wrong)}")
            position = _given(self, "lat", "lon", "alt")
            if position and len(position) < 3:
                raise ValueError("frame global needs all of lat, lon, alt (PX4 ignores a partial position)")
            axes = [
                ("lat/lon", bool(position), "vx"),
                ("lat/lon", bool(position), "vy"),
                ("alt", bool(position), "vz"),
            ]
        else:
            wrong = _given(self, "lat", "lon", "alt")
            if wrong:
                raise ValueError(f"{', '.join(wrong)} only go with frame: global (local uses x, y, z)")
            axes = [(a, getattr(self, a) is not None, f"v{a}") for a in ("x", "y", "z")]
        missing = [f"{p} or {v}" for p, has, v in axes if not has and getattr(self, v) is None]
        if missing:
            raise ValueError(
                f"a setpoint needs a position or a velocity on every axis; missing: {'; '.join(missing)}"
            )
        return self


class Goto(Model):
    """MAV_CMD_DO_REPOSITION: fly to a point and hold there (PX4 switches to hold / loiter)."""

    x: Local | None = Field(None, description="North, metres")
    y: Local | None = Field(None, description="East, metres")
    z: Down | None = Field(None, description="Down, metres; negative is up")
    lat: Latitude | None = Field(None, description="latitude, degrees")
    lon: Longitude | None = Field(None, description="longitude, degrees")
    alt: Altitude | None = Field(None, description="metres above home")
    speed: Speed | None = Field(None, description="ground speed, m/s (default: the vehicle's cruise speed)")
    yaw: Degrees | None = Field(None, description="heading at the target, degrees (default: the vehicle's)")

    @model_validator(mode="after")
    def _one_point(self) -> Goto:
        local, glob = _given(self, "x", "y", "z"), _given(self, "lat", "lon", "alt")
        if local and glob:
            raise ValueError(f"give x, y, z or lat, lon, alt, not both (got {', '.join(local + glob)})")
        given = local or glob
        if len(given) != 3:
            raise ValueError(
                f"give all of x, y, z or all of lat, lon, alt (got {', '.join(given) or 'none'})"
            )
        return self


class Orbit(Model):
    """MAV_CMD_DO_ORBIT: circle a centre (multicopter orbit mode)."""

    radius: OrbitRadius = Field(description="metres")
    velocity: Speed | None = Field(None, description="tangential speed, m/s (default: PX4's)")
    clockwise: bool = Field(True, description="direction seen from above")
    x: Local | None = Field(None, description="centre North, metres (default: where the vehicle is)")
    y: Local | None = Field(None, description="centre East, metres")
    z: Down | None = Field(None, description="centre Down, metres (default: the current altitude)")

    @model_validator(mode="after")
    def _centre(self) -> Orbit:
        if (self.x is None) != (self.y is None):
            raise ValueError("give both x and y of the centre, or neither (the vehicle's position)")
        return self


class YawDirection(StrEnum):
    SHORTEST = "shortest"
    CLOCKWISE = "clockwise"
    COUNTER_CLOCKWISE = "counterClockwise"


class YawCommand(Model):
    """MAV_CMD_CONDITION_YAW: turn to a heading."""

    heading: Degrees = Field(description="degrees: from North (absolute) or from the current heading")
    rate: YawRate | None = Field(None, description="deg/s (default: the vehicle's)")
    relative: bool = Field(False, description="heading relative to the current one")
    direction: YawDirection = YawDirection.SHORTEST


class Command(Model):
    """A command at a time on the vehicle clock (seconds since the vehicle booted)."""

    at: NonNegativeDuration = Field(description="seconds on the vehicle clock")
    action: CommandAction
    mode: FlightMode | None = Field(None, description="for action mode")
    sticks: Sticks | None = Field(None, description="for action sticks")
    speed: Speed | None = Field(None, description="for action speed: ground speed m/s")
    setpoint: Setpoint | None = Field(None, description="for action setpoint: offboard setpoint")
    goto: Goto | None = Field(None, description="for action goto: MAV_CMD_DO_REPOSITION")
    orbit: Orbit | None = Field(None, description="for action orbit: MAV_CMD_DO_ORBIT")
    yaw: YawCommand | None = Field(None, description="for action yaw: MAV_CMD_CONDITION_YAW")

    @model_validator(mode="after")
    def _arguments_match_action(self) -> Command:
        needs = {
            CommandAction.MODE: "mode",
            CommandAction.STICKS: "sticks",
            CommandAction.SPEED: "speed",
            CommandAction.SETPOINT: "setpoint",
            CommandAction.GOTO: "goto",
            CommandAction.ORBIT: "orbit",
            CommandAction.YAW: "yaw",
        }
        for action, field in needs.items():
            given = getattr(self, field) is not None
            if self.action == action and not given:
                raise ValueError(f"action {action.value} needs field '{field}'")
            if self.action != action and given:
                raise ValueError(f"field '{field}' only goes with action {action.value}")
        return self


# --------------------------------------------------------------------------- faults


class FaultUnit(StrEnum):
    """PX4 FAILURE_UNIT (MAV_CMD_INJECT_FAILURE param1), named as PX4's ``failure`` command does."""

    GYRO = "gyro"
    ACCEL = "accel"
    MAG = "mag"
    BARO = "baro"
    GPS = "gps"
    OPTICAL_FLOW = "optical_flow"
    VIO = "vio"
    DISTANCE_SENSOR = "distance_sensor"
    AIRSPEED = "airspeed"
    BATTERY = "battery"
    MOTOR = "motor"
    SERVO = "servo"
    AVOIDANCE = "avoidance"
    RC_SIGNAL = "rc_signal"
    MAVLINK_SIGNAL = "mavlink_signal"


class FaultType(StrEnum):
    """PX4 FAILURE_TYPE (MAV_CMD_INJECT_FAILURE param2)."""

    OK = "ok"
    OFF = "off"
    STUCK = "stuck"
    GARBAGE = "garbage"
    WRONG = "wrong"
    SLOW = "slow"
    DELAYED = "delayed"
    INTERMITTENT = "intermittent"


class Fault(Model):
    """A failure injected at a time on the vehicle clock (MAV_CMD_INJECT_FAILURE; the runner sets
    SYS_FAILURE_EN=1, without which PX4 refuses it)."""

    at: NonNegativeDuration = Field(description="seconds on the vehicle clock")
    unit: FaultUnit
    type: FaultType
    instance: FaultInstance = Field(0, description="0: all instances; motor: 1..N; sensors: instance + 1")

    @field_validator("type", mode="before")
    @classmethod
    def _bare_off(cls, value: object) -> object:
        """YAML 1.1 reads a bare ``off`` as false: take it as the failure type off."""
        return "off" if value is False else value


# --------------------------------------------------------------------------- assertions


class SimilarityMetric(StrEnum):
    DTW = "dtw"
    FRECHET = "frechet"


class ReferenceTrajectory(Model):
    """A reference trajectory inline: rows of t (s), x, y, z (NED metres)."""

    points: list[Annotated[list[Local], Field(min_length=4, max_length=4)]] = Field(
        min_length=2, max_length=10000
    )


class Similarity(Model):
    metric: SimilarityMetric = SimilarityMetric.DTW
    threshold: PositiveDistance = Field(description="largest allowed distance, metres (DTW: mean per step)")
    log_file: str | None = Field(None, description="reference PX4 ULog; relative to the test file")
    reference: ReferenceTrajectory | None = Field(None, description="inline reference (render fills it)")

    @model_validator(mode="after")
    def _one_reference(self) -> Similarity:
        if (self.log_file is None) == (self.reference is None):
            raise ValueError("give exactly one of logFile or reference")
        return self


class Geofence(Model):
    """An axis-aligned NED box the vehicle must stay in (metres from home)."""

    min_x: Local = -LOCAL_MAX
    max_x: Local = LOCAL_MAX
    min_y: Local = -LOCAL_MAX
    max_y: Local = LOCAL_MAX
    min_z: Local = Field(-LOCAL_MAX, description="Down: -120 means at most 120 m up")
    max_z: Local = LOCAL_MAX

    @model_validator(mode="after")
    def _min_below_max(self) -> Geofence:
        for axis in ("x", "y", "z"):
            low, high = getattr(self, f"min_{axis}"), getattr(self, f"max_{axis}")
            if not low < high:
                raise ValueError(
                    f"min{axis.upper()} {low:g} is not below max{axis.upper()} {high:g}: the box is empty"
                )
        return self


class Assertions(Model):
    no_collision: bool = Field(True, description="the vehicle must not touch an obstacle")
    min_obstacle_distance: Distance | None = Field(
        1.5, description="smallest allowed 3-D distance to any obstacle, metres (SBFT: 1.5)"
    )
    mission_completed: bool = Field(True, description="every mission item reached (when there is a mission)")
    max_flight_time: Duration | None = Field(None, description="seconds from takeoff to landing")
    geofence: Geofence | None = None
    similarity: Similarity | None = None


# --------------------------------------------------------------------------- test


class UavTestSpec(Model):
    replicas: int = Field(1, ge=1, le=1000, description="how many times the test is flown")
    parallelism: int | None = Field(
        None, ge=1, le=1000, description="replicas at once (default: all / cores)"
    )
    seed: Seed | None = Field(None, description="base seed; replica i flies with seed + i")
    timeout: Duration = Field(600.0, description="seconds of simulated time a replica may take")
    vehicle: Vehicle = Field(default_factory=Vehicle)
    world: World = Field(default_factory=World)
    mission: Mission | None = None
    commands: list[Command] = Field(
        default_factory=list, max_length=20000, description="timed commands on the vehicle clock"
    )
    commands_file: str | None = Field(None, description="Aerialist commands CSV; inlined by render")
    faults: list[Fault] = Field(
        default_factory=list,
        max_length=1000,
        description="failures injected on the vehicle clock (MAV_CMD_INJECT_FAILURE; sets SYS_FAILURE_EN=1)",
    )
    assertions: Assertions = Field(default_factory=Assertions)
    schedule: str | None = Field(
        None,
        max_length=256,
        description="cron schedule (5 fields, UTC) of runs in a cluster, e.g. '0 3 * * *'; "
        "unset: a run per spec change or re-run request only",
    )
    successful_runs_history_limit: int = Field(
        3, ge=0, le=100, description="finished passing runs kept in the cluster (newest first)"
    )
    failed_runs_history_limit: int = Field(
        3, ge=0, le=100, description="finished failing or erroring runs kept in the cluster (newest first)"
    )

    @field_validator("schedule")
    @classmethod
    def _cron(cls, value: str | None) -> str | None:
        if value is None:
            return None
        from datetime import UTC, datetime

        from cronsim import CronSim, CronSimError

        try:
            CronSim(value, datetime(2000, 1, 1, tzinfo=UTC))
        except CronSimError as e:
            raise ValueError(f"not a cron schedule ({e}): use 5 fields, e.g. '*/30 * * * *'") from None
        return value

    @model_validator(mode="after")
    def _mission_or_commands(self) -> UavTestSpec:
        if self.mission is None and not self.commands and self.commands_file is None:
            raise ValueError("a test needs a mission or commands (or both)")
        enabled = self.vehicle.params.get("SYS_FAILURE_EN")
        if self.faults and enabled is not None and enabled != 1:
            raise ValueError(
                f"faults need SYS_FAILURE_EN=1 (PX4 refuses MAV_CMD_INJECT_FAILURE otherwise); "
                f"vehicle.params sets it to {enabled}: leave it out, the runner sets it"
            )
        return self

    def replica_seed(self, index: int) -> int:
        """The seed replica ``index`` flies with: base seed + index (base 0 when unset)."""
        return (self.seed or 0) + index


class Metadata(Model):
    model_config = ConfigDict(extra="allow", alias_generator=to_camel, populate_by_name=True)

    name: str = Field(pattern=r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?$", max_length=63)
    namespace: str | None = None
    labels: dict[str, str] = Field(default_factory=dict)
    annotations: dict[str, str] = Field(default_factory=dict)


class UavTest(Model):
    api_version: Literal["uavtest.io/v1alpha1"] = API_VERSION
    kind: Literal["UavTest"] = KIND
    metadata: Metadata
    spec: UavTestSpec
