"""PX4 uORB topics as plain data: one slotted dataclass per topic (PX4 ``msg/*.msg``).

The simulator's modules pass these between them, and the flight recorder writes them to the
ULog as they are: each field carries its ULog type (``ulog("float")``), and the ULog format
definitions (``FORMATS``) are derived from the dataclass fields, so the two cannot drift.
Names, field names, types and field order follow PX4 v1.15 (a subset of fields, in PX4's order),
so ``pyulog`` and the analysis read our logs exactly like PX4's: e.g.
``position_setpoint_triplet`` nests three ``position_setpoint`` and reads back as
``current.lat``, ``next.valid`` and so on.

A published topic is never changed (treat it as frozen). The classes are slotted but not
``frozen=True``: a frozen dataclass builds through ``object.__setattr__`` per field, ~10x slower,
and ``vehicle_local_position`` (36 fields) is built on every 50 Hz tick. Flat topics are
flattened by ``operator.attrgetter`` (one tuple, in C), nested and array fields by a generated
function.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import Any, TypeVar

__all__ = [
    "FORMATS",
    "RECORD",
    "TOPICS",
    "ActuatorArmed",
    "BatteryStatus",
    "CollisionConstraints",
    "DistanceSensor",
    "FailureDetectorStatus",
    "GeofenceResult",
    "HomePosition",
    "HoverThrustEstimate",
    "ManualControlSetpoint",
    "MissionResult",
    "ObstacleDistance",
    "ObstacleDistanceFused",
    "OffboardControlMode",
    "PositionSetpoint",
    "PositionSetpointTriplet",
    "TrajectorySetpoint",
    "VehicleAngularVelocity",
    "VehicleAttitude",
    "VehicleAttitudeGroundtruth",
    "VehicleCommand",
    "VehicleCommandAck",
    "VehicleGlobalPosition",
    "VehicleLandDetected",
    "VehicleLocalPosition",
    "VehicleLocalPositionGroundtruth",
    "VehicleLocalPositionSetpoint",
    "VehicleStatus",
    "command",
    "local_position",
    "quaternion",
    "setpoint",
    "topic_name",
    "ulog_values",
]

T = TypeVar("T")

#: topic name → ULog field definitions ("float x"), in definition order
FORMATS: dict[str, list[str]] = {}
#: topic dataclass → a function returning its flat ULog values (arrays and nested topics spread)
_FLATTEN: dict[type, Callable[[Any], tuple[object, ...]]] = {}
_NAME: dict[type, str] = {}


def ulog(ulog_type: str) -> Any:
    """A topic field with its ULog type (``float``, ``uint8_t``, ``float[3]``, a nested topic)."""
    return field(metadata={"ulog": ulog_type})


def topic(name: str) -> Callable[[type[T]], type[T]]:
    """Register a topic dataclass under its uORB name: its ULog format and its flattener."""

    def register(cls: type[T]) -> type[T]:
        parts = []
        for f in fields(cls):  # type: ignore[arg-type]
            kind = f.metadata["ulog"]
            if "[" in kind:
                parts.append(f"*o.{f.name}")
            elif kind in FORMATS:
                parts.append(f"*_flat[{kind!r}](o.{f.name})")
            else:
                parts.append(f"o.{f.name}")
        FORMATS[name] = [f"{f.metadata['ulog']} {f.name}" for f in fields(cls)]  # type: ignore[arg-type]
        names = [f.name for f in fields(cls)]  # type: ignore[arg-type]
        if all(p == f"o.{n}" for p, n in zip(parts, names, strict=True)) and len(names) > 1:
            _FLATTEN[cls] = operator.attrgetter(*names)
        else:
            flat_by_name = {n: _FLATTEN[c] for c, n in _NAME.items()}
            _FLATTEN[cls] = eval(f"lambda o: ({', '.join(parts)},)", {"_flat": flat_by_name})
        _NAME[cls] = name
        RECORD[cls] = (name, _FLATTEN[cls])
        return cls

    return register


#: topic dataclass → (uORB name, flattener): what the recorder needs, in one lookup
RECORD: dict[type, tuple[str, Callable[[Any], tuple[object, ...]]]] = {}


def topic_name(msg: object) -> str:
    return _NAME[type(msg)]


def ulog_values(msg: object) -> tuple[object, ...]:
    """The flat values of one ULog data record of ``msg``, in format order."""
    return _FLATTEN[type(msg)](msg)


@topic("position_setpoint")
@dataclass(slots=True)
class PositionSetpoint:
    timestamp: int = ulog("uint64_t")
    lat: float = ulog("double")
    lon: float = ulog("double")
    vx: float = ulog("float")
    vy: float = ulog("float")
    vz: float = ulog("float")
    alt: float = ulog("float")
    yaw: float = ulog("float")
    loiter_radius: float = ulog("float")
    acceptance_radius: float = ulog("float")
    cruising_speed: float = ulog("float")
    cruising_throttle: float = ulog("float")
    valid: bool = ulog("bool")
    type: int = ulog("uint8_t")
    loiter_direction_counter_clockwise: bool = ulog("bool")
    gliding_enabled: bool = ulog("bool")


@topic("vehicle_local_position")
@dataclass(slots=True)
class VehicleLocalPosition:
    timestamp: int = ulog("uint64_t")
    timestamp_sample: int = ulog("uint64_t")
    x: float = ulog("float")
    y: float = ulog("float")
    z: float = ulog("float")
    vx: float = ulog("float")
    vy: float = ulog("float")
    vz: float = ulog("float")
    z_deriv: float = ulog("float")
    ax: float = ulog("float")
    ay: float = ulog("float")
    az: float = ulog("float")
    heading: float = ulog("float")
    delta_heading: float = ulog("float")
    dist_bottom: float = ulog("float")
    eph: float = ulog("float")
    epv: float = ulog("float")
    evh: float = ulog("float")
    evv: float = ulog("float")
    ref_lat: float = ulog("double")
    ref_lon: float = ulog("double")
    ref_alt: float = ulog("float")
    ref_timestamp: int = ulog("uint64_t")
    vxy_max: float = ulog("float")
    vz_max: float = ulog("float")
    hagl_min: float = ulog("float")
    hagl_max: float = ulog("float")
    xy_valid: bool = ulog("bool")
    z_valid: bool = ulog("bool")
    v_xy_valid: bool = ulog("bool")
    v_z_valid: bool = ulog("bool")
    xy_global: bool = ulog("bool")
    z_global: bool = ulog("bool")
    dist_bottom_valid: bool = ulog("bool")
    heading_good_for_control: bool = ulog("bool")
    dead_reckoning: bool = ulog("bool")


@topic("vehicle_global_position")
@dataclass(slots=True)
class VehicleGlobalPosition:
    timestamp: int = ulog("uint64_t")
    timestamp_sample: int = ulog("uint64_t")
    lat: float = ulog("double")
    lon: float = ulog("double")
    alt: float = ulog("float")
    alt_ellipsoid: float = ulog("float")
    eph: float = ulog("float")
    epv: float = ulog("float")
    terrain_alt: float = ulog("float")
    terrain_alt_valid: bool = ulog("bool")
    dead_reckoning: bool = ulog("bool")


@topic("vehicle_attitude")
@dataclass(slots=True)
class VehicleAttitude:
    timestamp: int = ulog("uint64_t")
    timestamp_sample: int = ulog("uint64_t")
    q: tuple[float, float, float, float] = ulog("float[4]")
    delta_q_reset: tuple[float, float, float, float] = ulog("float[4]")
    quat_reset_counter: int = ulog("uint8_t")


@topic("vehicle_angular_velocity")
@dataclass(slots=True)
class VehicleAngularVelocity:
    """Body rates (FRD, rad/s) as the gyro reads them, and their rate of change."""

    timestamp: int = ulog("uint64_t")
    timestamp_sample: int = ulog("uint64_t")
    xyz: tuple[float, float, float] = ulog("float[3]")
    xyz_derivative: tuple[float, float, float] = ulog("float[3]")


@topic("vehicle_attitude_groundtruth")
@dataclass(slots=True)
class VehicleAttitudeGroundtruth(VehicleAttitude):
    """The simulated body's true attitude, as PX4 SITL logs it next to the estimate."""


@topic("vehicle_local_position_groundtruth")
@dataclass(slots=True)
class VehicleLocalPositionGroundtruth(VehicleLocalPosition):
    """The simulated body's true position and velocity, as PX4 SITL logs them next to the estimate."""


@topic("vehicle_status")
@dataclass(slots=True)
class VehicleStatus:
    timestamp: int = ulog("uint64_t")
    armed_time: int = ulog("uint64_t")
    takeoff_time: int = ulog("uint64_t")
    nav_state_timestamp: int = ulog("uint64_t")
    arming_state: int = ulog("uint8_t")
    latest_arming_reason: int = ulog("uint8_t")
    latest_disarming_reason: int = ulog("uint8_t")
    nav_state_user_intention: int = ulog("uint8_t")
    nav_state: int = ulog("uint8_t")
    failure_detector_status: int = ulog("uint16_t")
    hil_state: int = ulog("uint8_t")
    vehicle_type: int = ulog("uint8_t")
    failsafe: bool = ulog("bool")
    gcs_connection_lost: bool = ulog("bool")
    system_type: int = ulog("uint8_t")
    system_id: int = ulog("uint8_t")
    component_id: int = ulog("uint8_t")
    pre_flight_checks_pass: bool = ulog("bool")


@topic("vehicle_land_detected")
@dataclass(slots=True)
class VehicleLandDetected:
    timestamp: int = ulog("uint64_t")
    freefall: bool = ulog("bool")
    ground_contact: bool = ulog("bool")
    maybe_landed: bool = ulog("bool")
    landed: bool = ulog("bool")
    in_ground_effect: bool = ulog("bool")
    in_descend: bool = ulog("bool")
    has_low_throttle: bool = ulog("bool")
    vertical_movement: bool = ulog("bool")
    horizontal_movement: bool = ulog("bool")
    close_to_ground_or_skipped_check: bool = ulog("bool")
    at_rest: bool = ulog("bool")


@topic("actuator_armed")
@dataclass(slots=True)
class ActuatorArmed:
    timestamp: int = ulog("uint64_t")
    armed: bool = ulog("bool")
    prearmed: bool = ulog("bool")
    ready_to_arm: bool = ulog("bool")
    lockdown: bool = ulog("bool")
    manual_lockdown: bool = ulog("bool")
    force_failsafe: bool = ulog("bool")


@topic("vehicle_command")
@dataclass(slots=True)
class VehicleCommand:
    timestamp: int = ulog("uint64_t")
    param5: float = ulog("double")
    param6: float = ulog("double")
    param1: float = ulog("float")
    param2: float = ulog("float")
    param3: float = ulog("float")
    param4: float = ulog("float")
    param7: float = ulog("float")
    command: int = ulog("uint32_t")
    target_system: int = ulog("uint8_t")
    target_component: int = ulog("uint8_t")
    source_system: int = ulog("uint8_t")
    source_component: int = ulog("uint16_t")
    confirmation: int = ulog("uint8_t")
    from_external: bool = ulog("bool")


@topic("vehicle_command_ack")
@dataclass(slots=True)
class VehicleCommandAck:
    timestamp: int = ulog("uint64_t")
    command: int = ulog("uint32_t")
    result: int = ulog("uint8_t")
    result_param1: int = ulog("uint8_t")
    result_param2: int = ulog("int32_t")
    target_system: int = ulog("uint8_t")
    target_component: int = ulog("uint16_t")
    from_external: bool = ulog("bool")


@topic("position_setpoint_triplet")
@dataclass(slots=True)
class PositionSetpointTriplet:
    timestamp: int = ulog("uint64_t")
    previous: PositionSetpoint = field(metadata={"ulog": "position_setpoint"})
    current: PositionSetpoint = field(metadata={"ulog": "position_setpoint"})
    next: PositionSetpoint = field(metadata={"ulog": "position_setpoint"})


@topic("mission_result")
@dataclass(slots=True)
class MissionResult:
    timestamp: int = ulog("uint64_t")
    mission_id: int = ulog("uint32_t")
    geofence_id: int = ulog("uint32_t")
    home_position_counter: int = ulog("uint32_t")
    seq_reached: int = ulog("int32_t")
    seq_current: int = ulog("uint16_t")
    seq_total: int = ulog("uint16_t")
    valid: bool = ulog("bool")
    warning: bool = ulog("bool")
    finished: bool = ulog("bool")
    failure: bool = ulog("bool")
    item_do_jump_changed: int = ulog("uint16_t")
    item_changed_index: int = ulog("uint16_t")
    item_do_jump_remaining: int = ulog("uint16_t")
    execution_mode: int = ulog("uint8_t")


@topic("manual_control_setpoint")
@dataclass(slots=True)
class ManualControlSetpoint:
    timestamp: int = ulog("uint64_t")
    timestamp_sample: int = ulog("uint64_t")
    valid: bool = ulog("bool")
    data_source: int = ulog("uint8_t")
    roll: float = ulog("float")
    pitch: float = ulog("float")
    yaw: float = ulog("float")
    throttle: float = ulog("float")
    flaps: float = ulog("float")
    aux1: float = ulog("float")
    aux2: float = ulog("float")
    sticks_moving: bool = ulog("bool")
    buttons: int = ulog("uint16_t")


@topic("home_position")
@dataclass(slots=True)
class HomePosition:
    timestamp: int = ulog("uint64_t")
    lat: float = ulog("double")
    lon: float = ulog("double")
    alt: float = ulog("float")
    x: float = ulog("float")
    y: float = ulog("float")
    z: float = ulog("float")
    yaw: float = ulog("float")
    valid_alt: bool = ulog("bool")
    valid_hpos: bool = ulog("bool")
    valid_lpos: bool = ulog("bool")
    manual_home: bool = ulog("bool")
    update_count: int = ulog("uint32_t")


@topic("trajectory_setpoint")
@dataclass(slots=True)
class TrajectorySetpoint:
    timestamp: int = ulog("uint64_t")
    position: tuple[float, float, float] = ulog("float[3]")
    velocity: tuple[float, float, float] = ulog("float[3]")
    acceleration: tuple[float, float, float] = ulog("float[3]")
    yaw: float = ulog("float")
    yawspeed: float = ulog("float")


@topic("vehicle_local_position_setpoint")
@dataclass(slots=True)
class VehicleLocalPositionSetpoint:
    """PX4 msg/VehicleLocalPositionSetpoint.msg: what PositionControl made of the trajectory
    setpoint, its acceleration (NED, gravity excluded) and normalised thrust setpoints."""

    timestamp: int = ulog("uint64_t")
    x: float = ulog("float")
    y: float = ulog("float")
    z: float = ulog("float")
    vx: float = ulog("float")
    vy: float = ulog("float")
    vz: float = ulog("float")
    acceleration: tuple[float, float, float] = ulog("float[3]")
    thrust: tuple[float, float, float] = ulog("float[3]")
    yaw: float = ulog("float")
    yawspeed: float = ulog("float")


@topic("hover_thrust_estimate")
@dataclass(slots=True)
class HoverThrustEstimate:
    """PX4 msg/HoverThrustEstimate.msg: mc_hover_thrust_estimator's state and its last fusion."""

    timestamp: int = ulog("uint64_t")
    timestamp_sample: int = ulog("uint64_t")
    hover_thrust: float = ulog("float")
    hover_thrust_var: float = ulog("float")
    accel_innov: float = ulog("float")
    accel_innov_var: float = ulog("float")
    accel_innov_test_ratio: float = ulog("float")
    accel_noise_var: float = ulog("float")
    valid: bool = ulog("bool")


@topic("offboard_control_mode")
@dataclass(slots=True)
class OffboardControlMode:
    """PX4 msg/OffboardControlMode.msg: which setpoint fields an offboard client controls."""

    timestamp: int = ulog("uint64_t")
    position: bool = ulog("bool")
    velocity: bool = ulog("bool")
    acceleration: bool = ulog("bool")
    attitude: bool = ulog("bool")
    body_rate: bool = ulog("bool")
    thrust_and_torque: bool = ulog("bool")
    direct_actuator: bool = ulog("bool")


@topic("geofence_result")
@dataclass(slots=True)
class GeofenceResult:
    """PX4 msg/GeofenceResult.msg (published by the navigator's geofence_breach_check)."""

    timestamp: int = ulog("uint64_t")
    geofence_max_dist_triggered: bool = ulog("bool")
    geofence_max_alt_triggered: bool = ulog("bool")
    geofence_custom_fence_triggered: bool = ulog("bool")
    geofence_action: int = ulog("uint8_t")


@topic("battery_status")
@dataclass(slots=True)
class BatteryStatus:
    """msg/BatteryStatus.msg (the fields PX4's battery library fills for battery_simulator)."""

    timestamp: int = ulog("uint64_t")
    connected: bool = ulog("bool")
    voltage_v: float = ulog("float")
    voltage_filtered_v: float = ulog("float")
    current_a: float = ulog("float")
    current_filtered_a: float = ulog("float")
    current_average_a: float = ulog("float")
    discharged_mah: float = ulog("float")
    remaining: float = ulog("float")
    scale: float = ulog("float")
    time_remaining_s: float = ulog("float")
    temperature: float = ulog("float")
    cell_count: int = ulog("uint8_t")
    source: int = ulog("uint8_t")
    priority: int = ulog("uint8_t")
    capacity: int = ulog("uint16_t")
    id: int = ulog("uint8_t")
    faults: int = ulog("uint16_t")
    warning: int = ulog("uint8_t")


@topic("failure_detector_status")
@dataclass(slots=True)
class FailureDetectorStatus:
    """msg/FailureDetectorStatus.msg."""

    timestamp: int = ulog("uint64_t")
    fd_roll: bool = ulog("bool")
    fd_pitch: bool = ulog("bool")
    fd_alt: bool = ulog("bool")
    fd_ext: bool = ulog("bool")
    fd_arm_escs: bool = ulog("bool")
    fd_battery: bool = ulog("bool")
    fd_imbalanced_prop: bool = ulog("bool")
    fd_motor: bool = ulog("bool")
    imbalanced_prop_metric: float = ulog("float")
    motor_failure_mask: int = ulog("uint16_t")


@topic("obstacle_distance")
@dataclass(slots=True)
class ObstacleDistance:
    """msg/ObstacleDistance.msg (fields in PX4's size order): a range sensor's scan, 72 bins of
    ``increment`` degrees from ``angle_offset`` (``frame`` MAV_FRAME_BODY_FRD: 0 is the front,
    positive to the right), cm; ``max_distance`` + 1 no obstacle in range, UINT16_MAX no data."""

    timestamp: int = ulog("uint64_t")
    increment: float = ulog("float")
    angle_offset: float = ulog("float")
    distances: tuple[int, ...] = ulog("uint16_t[72]")
    min_distance: int = ulog("uint16_t")
    max_distance: int = ulog("uint16_t")
    frame: int = ulog("uint8_t")
    sensor_type: int = ulog("uint8_t")


@topic("obstacle_distance_fused")
@dataclass(slots=True)
class ObstacleDistanceFused(ObstacleDistance):
    """The same message as Collision Prevention's map (10-degree bins, 36 used), PX4's
    ``obstacle_distance_fused`` (what the OBSTACLE_DISTANCE stream sends)."""


@topic("collision_constraints")
@dataclass(slots=True)
class CollisionConstraints:
    """msg/CollisionConstraints.msg: the position-mode velocity setpoint before and after CP."""

    timestamp: int = ulog("uint64_t")
    original_setpoint: tuple[float, float] = ulog("float[2]")
    adapted_setpoint: tuple[float, float] = ulog("float[2]")


@topic("distance_sensor")
@dataclass(slots=True)
class DistanceSensor:
    """msg/DistanceSensor.msg (fields in PX4's size order), metres and radians."""

    timestamp: int = ulog("uint64_t")
    device_id: int = ulog("uint32_t")
    min_distance: float = ulog("float")
    max_distance: float = ulog("float")
    current_distance: float = ulog("float")
    variance: float = ulog("float")
    h_fov: float = ulog("float")
    v_fov: float = ulog("float")
    q: tuple[float, float, float, float] = ulog("float[4]")
    signal_quality: int = ulog("int8_t")
    type: int = ulog("uint8_t")
    orientation: int = ulog("uint8_t")


#: topics subscribed in every log, in this order (position_setpoint only nests)
TOPICS = [name for name in FORMATS if name != "position_setpoint"]

NAN = math.nan

# position_setpoint.type
SETPOINT_TYPE_POSITION = 0
SETPOINT_TYPE_LOITER = 2
SETPOINT_TYPE_TAKEOFF = 3
SETPOINT_TYPE_LAND = 4
SETPOINT_TYPE_IDLE = 5

#: an unused slot of position_setpoint_triplet
INVALID_SETPOINT = PositionSetpoint(
    0, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, False, 0, False, False
)


def setpoint(
    t_us: int, lat: float, lon: float, alt: float, yaw: float, kind: int, acceptance: float, speed: float
) -> PositionSetpoint:
    """One valid position_setpoint."""
    return PositionSetpoint(
        t_us, lat, lon, NAN, NAN, NAN, alt, yaw, 80.0, acceptance, speed, NAN, True, kind, False, False
    )


def quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """Hamilton quaternion (w, x, y, z) of ZYX Euler angles, as PX4's vehicle_attitude.q."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def local_position(
    t_us: int,
    pos: tuple[float, float, float],
    vel: tuple[float, float, float],
    acc: tuple[float, float, float],
    heading: float,
    ref: tuple[float, float, float],
    ref_t_us: int,
    valid: bool,
    dist_bottom: float | None = None,
    dist_bottom_valid: bool = True,
    z_deriv: float | None = None,
    cls: type[VehicleLocalPosition] = VehicleLocalPosition,
) -> VehicleLocalPosition:
    """``dist_bottom``: the distance to the ground (default: the altitude) and whether EKF2's
    terrain estimate is valid; ``z_deriv``: the altitude's derivative (default: ``vz``);
    ``cls``: ``VehicleLocalPositionGroundtruth`` for the truth."""
    x, y, z = pos
    vx, vy, vz = vel
    bottom = max(-z, 0.0) if dist_bottom is None else max(dist_bottom, 0.0)
    return cls(
        t_us, t_us, x, y, z, vx, vy, vz, vz if z_deriv is None else z_deriv, acc[0], acc[1], acc[2],
        heading, 0.0, bottom, 0.3, 0.4, 0.1, 0.1, ref[0], ref[1], ref[2], ref_t_us, NAN, NAN, NAN, NAN,
        valid, valid, valid, valid, valid, valid, dist_bottom_valid, valid, False,
    )  # fmt: skip


def command(
    t_us: int,
    cmd: int,
    params: tuple[float, float, float, float, float, float, float],
    source: tuple[int, int],
    target: tuple[int, int],
    external: bool,
) -> VehicleCommand:
    p1, p2, p3, p4, p5, p6, p7 = params
    return VehicleCommand(
        t_us, p5, p6, p1, p2, p3, p4, p7, cmd, target[0], target[1], source[0], source[1], 0, external
    )
