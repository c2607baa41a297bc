"""Pydantic models of a UavTest: the single source of the test file format and of the CRD.

Field names are camelCase on the wire (Kubernetes API conventions) and snake_case in Python.
Unknown fields are rejected so a typo is reported with its field path.
Coordinates are PX4 local NED (x North, y East, z Down, metres from home).
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator
from pydantic.alias_generators import to_camel

from uavtest.spec.bounds import (
    LOCAL_MAX,
    Altitude,
    AltitudeAmsl,
    Degrees,
    Distance,
    Down,
    Duration,
    Height,
    Latitude,
    Local,
    Longitude,
    NonNegativeDuration,
    ObstacleSize,
    ParamFloat,
    ParamInt,
    PositiveDistance,
    Seed,
    Speed,
    StickAxis,
    Throttle,
    WindSpeed,
)

__all__ = [
    "API_GROUP",
    "API_VERSION",
    "KIND",
    "Assertions",
    "BoxPosition",
    "BoxSize",
    "Command",
    "CommandAction",
    "FlightMode",
    "Geofence",
    "Home",
    "Metadata",
    "Mission",
    "MissionItem",
    "MissionItemKind",
    "Obstacle",
    "ReferenceTrajectory",
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


MISSION_ITEM_CMD: dict[MissionItemKind, int] = {
    MissionItemKind.TAKEOFF: 22,
    MissionItemKind.WAYPOINT: 16,
    MissionItemKind.LAND: 21,
    MissionItemKind.RETURN: 20,
    MissionItemKind.LOITER_TIME: 19,
    MissionItemKind.CHANGE_SPEED: 178,
}


class MissionItem(Model):
    """One mission item in global coordinates, altitude relative to home (MAV_FRAME_GLOBAL_RELATIVE_ALT)."""

    kind: MissionItemKind
    lat: Latitude | None = None
    lon: Longitude | None = None
    alt: Altitude | None = Field(None, description="metres above home")
    hold: NonNegativeDuration = Field(0.0, description="hold / loiter time at the item, seconds")
    speed: Speed | None = Field(None, description="changeSpeed: ground speed m/s")


class Waypoint(Model):
    """A NED waypoint relative to home: z is Down, so 10 m up is z: -10."""

    x: Local = Field(description="North, metres")
    y: Local = Field(description="East, metres")
    z: Down = Field(description="Down, metres; negative is up")
    hold: NonNegativeDuration = Field(0.0, description="seconds to hold at the waypoint")


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


class Sticks(Model):
    """MANUAL_CONTROL sticks: x, y, r in [-1, 1]; z (throttle) in [0, 1], 0.5 holds altitude."""

    x: StickAxis = 0.0
    y: StickAxis = 0.0
    z: Throttle = 0.5
    r: StickAxis = 0.0


class Command(Model):
    """A command at a time on the vehicle clock (seconds since the vehicle booted)."""

    at: NonNegativeDuration = Field(description="seconds on the vehicle clock")
    action: CommandAction
    mode: FlightMode | None = Field(None, description="for action mode")
    sticks: Sticks | None = Field(None, description="for action sticks")
    speed: Speed | None = Field(None, description="for action speed: ground speed m/s")

    @model_validator(mode="after")
    def _arguments_match_action(self) -> Command:
        needs = {CommandAction.MODE: "mode", CommandAction.STICKS: "sticks", CommandAction.SPEED: "speed"}
        for action, field in needs.items():
            given = getattr(self, field) is not None
            if self.action == action and not given:
                raise ValueError(f"action {action.value} needs field '{field}'")
            if self.action != action and given:
                raise ValueError(f"field '{field}' only goes with action {action.value}")
        return self


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
    assertions: Assertions = Field(default_factory=Assertions)

    @model_validator(mode="after")
    def _mission_or_commands(self) -> UavTestSpec:
        if self.mission is None and not self.commands and self.commands_file is None:
            raise ValueError("a test needs a mission or commands (or both)")
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
