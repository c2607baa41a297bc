"""PX4 v1.15's Collision Prevention (``src/lib/collision_prevention/CollisionPrevention.cpp``).

PX4 runs it only in the position-mode flight task ``FlightTaskManualPosition``
(``MPC_POS_MODE`` 0; the default acceleration-based task of ``MPC_POS_MODE`` 4 has none in
v1.15), when ``CP_DIST`` > 0; never in missions or other auto modes. It constrains the
horizontal velocity setpoint the sticks ask for (``modifySetpoint``):

- an internal map of 36 bins of 10 degrees in the body frame, filled from ``obstacle_distance``
  (every other 5-degree bin: the bin whose angle is ``ceil`` of the map bin's, PX4's index
  arithmetic) and from non-vertical ``distance_sensor`` readings (their field of view, the
  distance times the cosine of the pitch), keeping per bin the time, the sensor's range and
  whether it was ever seen (``_enterData`` decides which sensor wins a bin);
- the setpoint direction may turn by up to ``CP_GUIDE_ANG`` (whole 10-degree bins) towards the
  bin with the lowest cost: ``CP_DIST * 50 * bins turned - mean of 3 bins - the bin`` (cm);
- for every bin within 90 degrees of the direction, the speed is limited so the vehicle can
  stop ``max(min_distance, CP_DIST)`` short of the obstacle after travelling for ``CP_DELAY``
  (plus the data's age when the reading is in range) at its current speed towards the bin:
  ``min(MPC_XY_P * d, max speed to brake within d at MPC_ACC_HOR, MPC_JERK_MAX) / cos``;
- no data in the setpoint's bin stops the vehicle unless ``CP_GO_NO_DATA`` is 1 and the bin was
  never seen; no bin with data at all stops it; data older than 0.5 s is dropped; with no data
  for 0.5 s nothing moves, and after 5 s PX4 switches to Hold (``_publishVehicleCmdDoLoiter``).

The logic is pure functions over ``ObstacleMap``; ``CollisionPrevention`` is the flight task's
object (PX4 constructs it with the task, so the map restarts on every switch into position mode).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from uavtest.mavlink_numbers import MavFrame
from uavtest.sitl.uorb import CollisionConstraints, DistanceSensor, ObstacleDistance, ObstacleDistanceFused

__all__ = [
    "MAP_BINS",
    "MAP_INCREMENT_DEG",
    "RANGE_STREAM_TIMEOUT_US",
    "TIMEOUT_HOLD_US",
    "CollisionPrevention",
    "CpParams",
    "ObstacleMap",
    "adapt_setpoint_direction",
    "add_distance_sensor",
    "add_obstacle_distance",
    "constrain_setpoint",
    "max_speed_from_distance",
]

MAP_INCREMENT_DEG = 10  # INTERNAL_MAP_INCREMENT_DEG
MAP_BINS = 360 // MAP_INCREMENT_DEG  # INTERNAL_MAP_USED_BINS
MSG_BINS = 72
UINT16_MAX = 65535
RANGE_STREAM_TIMEOUT_US = 500_000
TIMEOUT_HOLD_US = 5_000_000
#: a longer pause between two position-mode ticks means the flight task was switched away and back
GAP_US = 30_000
MAV_FRAME_GLOBAL, MAV_FRAME_LOCAL_NED, MAV_FRAME_BODY_FRD = (
    int(MavFrame.GLOBAL),
    int(MavFrame.LOCAL_NED),
    int(MavFrame.BODY_FRD),
)
ROTATION_UPWARD_FACING, ROTATION_DOWNWARD_FACING, ROTATION_CUSTOM = 24, 25, 100
#: distance_sensor.orientation ROTATION_YAW_* → yaw offset (rad), _sensorOrientationToYawOffset
_YAW_OF_ORIENTATION = {i: math.radians(45 * i) if i <= 4 else math.radians(45 * i - 360) for i in range(8)}


@dataclass(frozen=True, slots=True)
class CpParams:
    """The parameters CollisionPrevention reads (CP_* and three of mc_pos_control's)."""

    dist: float = -1.0  # CP_DIST
    delay: float = 0.4  # CP_DELAY
    guide_ang: float = 30.0  # CP_GUIDE_ANG
    go_no_data: bool = False  # CP_GO_NO_DATA
    xy_p: float = 0.95  # MPC_XY_P
    jerk_max: float = 8.0  # MPC_JERK_MAX
    acc_hor: float = 3.0  # MPC_ACC_HOR


@dataclass(slots=True)
class ObstacleMap:
    """``_obstacle_map_body_frame`` and its per-bin bookkeeping (times in µs, ranges in cm)."""

    timestamp: int
    distances: list[int] = field(default_factory=lambda: [UINT16_MAX] * MSG_BINS)
    min_distance: int = UINT16_MAX
    max_distance: int = 0
    data_timestamps: list[int] = field(default_factory=list)
    data_maxranges: list[int] = field(default_factory=lambda: [0] * MAP_BINS)
    data_fov: list[bool] = field(default_factory=lambda: [False] * MAP_BINS)

    def __post_init__(self) -> None:
        if not self.data_timestamps:
            self.data_timestamps = [self.timestamp] * MAP_BINS

    def fused(self) -> ObstacleDistanceFused:
        """The map as PX4 publishes it (``obstacle_distance_fused``)."""
        return ObstacleDistanceFused(
            self.timestamp, float(MAP_INCREMENT_DEG), 0.0, tuple(self.distances), self.min_distance,
            self.max_distance, MAV_FRAME_BODY_FRD, 0,
        )  # fmt: skip


_BIN_COS = tuple(math.cos(math.radians(i * MAP_INCREMENT_DEG)) for i in range(MAP_BINS))
_BIN_SIN = tuple(math.sin(math.radians(i * MAP_INCREMENT_DEG)) for i in range(MAP_BINS))


def _wrap_360(deg: float) -> float:
    return deg % 360.0


def _wrap_bin(i: int) -> int:
    return i % MAP_BINS


def _enter_data(m: ObstacleMap, i: int, sensor_range: float, reading: float) -> bool:
    """``_enterData``: whether a reading (m) of a sensor of range ``sensor_range`` (m) takes bin i."""
    range_cm = int(100.0 * sensor_range + 0.5)
    have, have_range = m.distances[i], m.data_maxranges[i]
    if reading < sensor_range:
        return (have < have_range and range_cm <= have_range) or have >= have_range
    return (have >= have_range and range_cm >= have_range) or (have < have_range and range_cm == have_range)


def add_obstacle_distance(m: ObstacleMap, msg: ObstacleDistance, yaw: float, now_us: int) -> None:
    """``_updateObstacleMap`` for one ``obstacle_distance`` (``_addObstacleSensorData``)."""
    if now_us - msg.timestamp >= RANGE_STREAM_TIMEOUT_US or msg.increment <= 0.0:
        return
    m.timestamp = max(m.timestamp, msg.timestamp)
    m.max_distance = max(m.max_distance, msg.max_distance)
    m.min_distance = min(m.min_distance, msg.min_distance)
    factor = 1.0 / msg.increment
    if msg.frame in (MAV_FRAME_GLOBAL, MAV_FRAME_LOCAL_NED):
        shift = math.degrees(yaw)
    elif msg.frame == MAV_FRAME_BODY_FRD:
        shift = 0.0
    else:
        return  # PX4: "Obstacle message received in unsupported frame"
    for i in range(MAP_BINS):
        angle = float(i * MAP_INCREMENT_DEG)
        # PX4 reads distances[72] (past the array) when this rounds up to 72; wrap instead
        k = math.ceil(_wrap_360(shift + angle - msg.angle_offset) * factor) % MSG_BINS
        d = msg.distances[k]
        if d != UINT16_MAX and _enter_data(m, i, msg.max_distance * 0.01, d * 0.01):
            m.distances[i] = d
            m.data_timestamps[i] = m.timestamp
            m.data_maxranges[i] = msg.max_distance
            m.data_fov[i] = True


def add_distance_sensor(m: ObstacleMap, ds: DistanceSensor, pitch: float, now_us: int) -> None:
    """``_updateObstacleMap`` for one ``distance_sensor`` (``_addDistanceSensorData``);
    ``pitch``: the vehicle's pitch about the sensor's direction (rad)."""
    if now_us - ds.timestamp >= RANGE_STREAM_TIMEOUT_US or ds.orientation in (
        ROTATION_DOWNWARD_FACING,
        ROTATION_UPWARD_FACING,
    ):
        return
    m.timestamp = max(m.timestamp, ds.timestamp)
    m.max_distance = max(m.max_distance, int(ds.max_distance * 100.0))
    m.min_distance = min(m.min_distance, int(ds.min_distance * 100.0))
    reading = min(ds.current_distance, ds.max_distance)
    if reading <= ds.min_distance:
        return
    yaw = _YAW_OF_ORIENTATION.get(ds.orientation, 0.0)
    yaw_deg = math.degrees(yaw % (2 * math.pi))
    half = math.degrees(ds.h_fov / 2.0)
    lower = math.floor((yaw_deg - half) / MAP_INCREMENT_DEG)
    upper = math.floor((yaw_deg + half) / MAP_INCREMENT_DEG)
    lower += 1 if lower < 0 else 0  # "floor values above zero, ceil values below zero"
    upper += 1 if upper < 0 else 0
    if reading < ds.max_distance:
        reading *= math.cos(pitch)
    range_cm = int(100.0 * ds.max_distance + 0.5)
    for b in range(lower, upper + 1):
        i = _wrap_bin(b)
        if _enter_data(m, i, ds.max_distance, reading):
            m.distances[i] = int(100.0 * reading + 0.5)
            m.data_timestamps[i] = m.timestamp
            m.data_maxranges[i] = range_cm
            m.data_fov[i] = True


def max_speed_from_distance(jerk: float, accel: float, distance: float, final_speed: float = 0.0) -> float:
    """``math::trajectory::computeMaxSpeedFromDistance`` (TrajMath.hpp)."""
    b = 4.0 * accel * accel / jerk
    c = -2.0 * accel * distance - final_speed * final_speed
    return max(0.5 * (-b + math.sqrt(b * b - 4.0 * c)), final_speed)


def adapt_setpoint_direction(m: ObstacleMap, sp_index: int, cp_dist: float, guide_ang: float) -> int:
    """``_adaptSetpointDirection``: the bin to steer to (``sp_index`` if no better one)."""
    guidance_bins = math.floor(guide_ang / MAP_INCREMENT_DEG)
    best_cost = 9999.0
    best = sp_index
    d = m.distances
    for i in range(sp_index - guidance_bins, sp_index + guidance_bins + 1):
        mean = 0.0
        for j in (i - 1, i, i + 1):
            v = d[_wrap_bin(j)]
            mean += cp_dist * 100.0 if v == UINT16_MAX else v
        mean /= 3.0
        b = _wrap_bin(i)
        cost = cp_dist * 50.0 * abs(i - sp_index) - mean - d[b]
        if cost < best_cost and d[b] != UINT16_MAX:
            best_cost, best = cost, b
    return best


def constrain_setpoint(
    m: ObstacleMap, sp: tuple[float, float], vel: tuple[float, float], yaw: float, now_us: int, p: CpParams
) -> tuple[float, float]:
    """``_calculateConstrainedSetpoint`` after the map update: the allowed velocity setpoint
    (NED, m/s) for the stick setpoint ``sp``; drops stale bins from ``m`` as PX4 does."""
    if now_us - m.timestamp >= RANGE_STREAM_TIMEOUT_US:
        return 0.0, 0.0
    length = math.hypot(sp[0], sp[1])
    if length <= 0.001:
        return sp
    dir_x, dir_y = sp[0] / length, sp[1] / length
    vel_max = length
    keep = max(m.min_distance / 100.0, p.dist)
    sp_deg = _wrap_360(math.degrees(math.atan2(dir_y, dir_x) - yaw))
    sp_index = math.floor(sp_deg / MAP_INCREMENT_DEG)
    new_index = adapt_setpoint_direction(m, sp_index, p.dist, p.guide_ang)
    if new_index != sp_index:
        a = yaw + math.radians(new_index * MAP_INCREMENT_DEG)
        dir_x, dir_y = math.cos(a), math.sin(a)
        sp_index = new_index
    fov_bins = 0
    d = m.distances
    stamps, ranges = m.data_timestamps, m.data_maxranges
    cy, sy = math.cos(yaw), math.sin(yaw)
    stale_before = now_us - RANGE_STREAM_TIMEOUT_US
    min_cm = m.min_distance
    xy_p, delay = p.xy_p, p.delay
    b_jerk = 4.0 * p.acc_hor * p.acc_hor / p.jerk_max  # computeMaxSpeedFromDistance's b
    two_acc = 2.0 * p.acc_hor
    for i in range(MAP_BINS):
        if stamps[i] < stale_before:
            d[i] = UINT16_MAX
        di = d[i]
        if di == UINT16_MAX:
            if i == sp_index and (not p.go_no_data or m.data_fov[i]):
                vel_max = 0.0
            continue
        fov_bins += 1
        if di <= min_cm:
            continue
        c, s_ = _BIN_COS[i], _BIN_SIN[i]
        bx, by = cy * c - sy * s_, sy * c + cy * s_  # the bin's direction, local frame
        projection = dir_x * bx + dir_y * by
        if projection <= 0.0:
            continue
        distance = di * 0.01
        v_par = vel[0] * bx + vel[1] * by
        v_par = v_par if v_par > 0.0 else 0.0
        delay_distance = v_par * delay
        if distance < ranges[i] * 0.01:
            delay_distance += v_par * (now_us - stamps[i]) * 1e-6
        stop = distance - keep - delay_distance
        stop = stop if stop > 0.0 else 0.0
        smooth = 0.5 * (-b_jerk + math.sqrt(b_jerk * b_jerk + 4.0 * two_acc * stop))
        limit = xy_p * stop if xy_p * stop < smooth else smooth
        vel_max_bin = limit / projection if projection > 0.01 else vel_max
        if 0.0 <= vel_max_bin < vel_max:
            vel_max = vel_max_bin
    if fov_bins == 0:
        vel_max = 0.0
    return dir_x * vel_max, dir_y * vel_max


class CollisionPrevention:
    """The flight task's CollisionPrevention: ``modify_setpoint`` once per position-mode tick.

    The vehicle hands it the sensor data as it is published (``obstacle``, ``distance``), the
    time and the pitch (``now_us``, ``pitch``) before each controller tick; after each call,
    ``fused`` and ``constraints`` hold what PX4 publishes, and ``want_hold`` says the data has
    been missing long enough for PX4 to switch to Hold.
    """

    def __init__(self, params: CpParams, now_us: int) -> None:
        self.params = params
        self.obstacle: ObstacleDistance | None = None  # a new obstacle_distance not yet taken
        self.distance: DistanceSensor | None = None  # a new distance_sensor not yet taken
        self.pitch = 0.0
        self.max_speed = 0.0  # the stick scale, MPC_VEL_MANUAL
        self.now_us = now_us
        self._activate(now_us)

    def _activate(self, now_us: int) -> None:
        """PX4 constructs the task, and with it this object, on every switch into position mode."""
        self.map = ObstacleMap(now_us)
        self.activated_us = now_us  # _time_activated
        self.last_warning_us = 0  # _last_timeout_warning
        self.last_call_us = now_us
        self.fused: ObstacleDistanceFused | None = None  # published by the last call, not yet logged
        #: the last obstacle_distance_fused published (OBSTACLE_DISTANCE sends it while fresh)
        self.published: ObstacleDistanceFused | None = None
        self.constraints: CollisionConstraints | None = None
        self.want_hold = False
        self.interfering = False

    def __call__(self, sx: float, sy: float, vx: float, vy: float, yaw: float) -> tuple[float, float]:
        """The controller's hook (``Controller.velocity_constraint``): the stick velocity setpoint
        (NED) constrained, at the time and attitude the vehicle set (``now_us``, ``pitch``)."""
        now = self.now_us
        if now - self.last_call_us > GAP_US:
            self._activate(now)
        self.last_call_us = now
        return self.modify_setpoint((sx, sy), self.max_speed, (vx, vy), yaw, self.pitch, now)

    def modify_setpoint(
        self,
        sp: tuple[float, float],
        max_speed: float,
        vel: tuple[float, float],
        yaw: float,
        pitch: float,
        now_us: int,
    ) -> tuple[float, float]:
        """``modifySetpoint``: the allowed velocity setpoint for ``sp`` (NED, m/s)."""
        m, p = self.map, self.params
        if self.distance is not None:
            add_distance_sensor(m, self.distance, pitch, now_us)
            self.distance = None
        if self.obstacle is not None:
            add_obstacle_distance(m, self.obstacle, yaw, now_us)
            self.obstacle = None
        self.fused = m.fused()
        if now_us - m.timestamp >= RANGE_STREAM_TIMEOUT_US:
            new = 0.0, 0.0
            if now_us - self.last_warning_us > 1_000_000 and now_us - self.activated_us > 1_000_000:
                if now_us - m.timestamp > TIMEOUT_HOLD_US and now_us - self.activated_us > TIMEOUT_HOLD_US:
                    self.want_hold = True
                self.last_warning_us = now_us
        else:
            new = constrain_setpoint(m, sp, vel, yaw, now_us, p)
        tol = 0.05 * max_speed
        self.interfering = abs(new[0] - sp[0]) > tol or abs(new[1] - sp[1]) > tol
        self.constraints = CollisionConstraints(now_us, (sp[0], sp[1]), (new[0], new[1]))
        return new
