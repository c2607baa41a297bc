"""A scanning range sensor for PX4 SITL: OBSTACLE_DISTANCE from the test's boxes (pure).

PX4 v1.15's SIH has no obstacle sensor, and its world has no obstacles: Collision Prevention
(``CP_DIST``) gets no data and, with ``CP_GO_NO_DATA`` 0, lets the pilot fly nowhere. On a real
vehicle a companion computer (or a lidar driver) publishes ``obstacle_distance``; PX4's MAVLink
receiver turns an OBSTACLE_DISTANCE message into that topic, stamped when it arrives
(``handle_message_obstacle_distance``). The runner plays that companion for a PX4 SITL vehicle
whose test carries a range sensor: from PX4's own estimate (LOCAL_POSITION_NED, the heading of
ATTITUDE) it scans the test's boxes exactly as the built-in vehicle's sensor does
(``uavtest.sitl.sensor_obstacle_distance_sim.scan``: 72 bins of 5 degrees, body frame, field of
view, range) and sends the scan at the sensor's rate of *vehicle* time. PX4's own Collision
Prevention then acts on it: a PX4 team's firmware meets the boxes it is tested against.

The scan is taken where PX4 *believes* it is (its EKF2 estimate), not at the truth SIH keeps to
itself: a sensor sees from the true position, so this sensor is as wrong as EKF2 (decimetres).
PX4 drops data older than 0.5 s of its clock (``RANGE_STREAM_TIMEOUT_US``): at a speed factor
of 20 that is 25 ms of wall time, so a busy machine may starve it (give a lower
``vehicle.speedFactor``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from uavtest.runner.events import ObstacleDistance
from uavtest.sitl.sensor_obstacle_distance_sim import (
    INCREMENT_DEG,
    MAV_DISTANCE_SENSOR_LASER,
    MAV_FRAME_BODY_FRD,
    scan,
)
from uavtest.sitl.simulator_sih import World
from uavtest.spec.models import Obstacle, RangeSensor

__all__ = ["ObstacleDistanceFeed"]


@dataclass(slots=True)
class ObstacleDistanceFeed:
    """Fed PX4's heading and positions, returns an OBSTACLE_DISTANCE whenever a scan is due."""

    sensor: RangeSensor
    obstacles: Sequence[Obstacle] = ()
    yaw: float = math.nan  # the latest ATTITUDE heading (rad); no scan before one
    next_ms: float = 0.0  # vehicle time of the next scan
    sent: int = 0
    _world: World = field(init=False)

    def __post_init__(self) -> None:
        self._world = World(self.obstacles)

    @property
    def interval_ms(self) -> float:
        return 1000.0 / self.sensor.rate

    def on_attitude(self, yaw: float) -> None:
        self.yaw = yaw

    def on_position(self, time_ms: int, x: float, y: float, z: float) -> ObstacleDistance | None:
        """The scan due at vehicle time ``time_ms`` from (x, y, z) NED, else None. A clock that
        went back (a reboot) starts the schedule over."""
        if self.yaw != self.yaw:
            return None
        if time_ms + self.interval_ms < self.next_ms:
            self.next_ms = time_ms
        if time_ms < self.next_ms:
            return None
        self.next_ms = max(self.next_ms + self.interval_ms, time_ms)
        s = self.sensor
        self.sent += 1
        return ObstacleDistance(
            time_usec=time_ms * 1000,
            distances=scan(self._world, x, y, z, self.yaw, s),
            min_cm=round(s.min_range * 100),
            max_cm=round(s.max_range * 100),
            increment=INCREMENT_DEG,
            angle_offset=0.0,
            frame=MAV_FRAME_BODY_FRD,
            sensor_type=MAV_DISTANCE_SENSOR_LASER,
        )
