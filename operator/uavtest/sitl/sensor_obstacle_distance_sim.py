"""A simulated scanning range sensor (a 2-D lidar) that sees the test's boxes.

PX4 v1.15's SIH has no such sensor (its only range finder, ``send_dist_snsr``, faces down);
this stands in for the sensors PX4's Collision Prevention is fed by: a lidar driver such as
``lightware_sf45_serial`` or a companion computer sending OBSTACLE_DISTANCE, both publishing
``obstacle_distance``. The scan is what PX4's ``msg/ObstacleDistance.msg`` describes:

- 72 bins of 5 degrees in ``MAV_FRAME_BODY_FRD``, bin ``k`` centred ``k * 5`` degrees right of
  the vehicle's front (``angle_offset`` 0), distances in cm;
- bins outside the field of view (``fov`` degrees centred on the front) are ``UINT16_MAX``
  (no data); a bin that sees nothing within ``max_range`` is ``max_distance + 1`` (in range,
  no obstacle); an obstacle nearer than ``min_range`` is reported as measured (PX4's CP then
  ignores the bin, as it does for a real sensor);
- each bin is the nearest of three rays across it (its centre and +-1/3 of its width), cast
  horizontally from the vehicle's position against the boxes (``Box.ray``, what ``World.ray``
  casts; only rays that can reach a box are cast): the scan plane stays level (a gimballed
  scanner; a body-fixed one would tilt with the vehicle), the ground is not seen.

It also publishes one ``distance_sensor`` (forward facing, the front bin's reading, one bin's
width of field of view), as a PX4 lidar driver publishes its current reading beside the scan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.sitl.simulator_sih import World
from uavtest.sitl.uorb import DistanceSensor, ObstacleDistance
from uavtest.spec.models import RangeSensor

__all__ = [
    "BINS",
    "INCREMENT_DEG",
    "MAV_FRAME_BODY_FRD",
    "ROTATION_FORWARD_FACING",
    "UINT16_MAX",
    "ObstacleDistanceSim",
    "scan",
]

BINS = 72
INCREMENT_DEG = 5.0
UINT16_MAX = 65535
MAV_FRAME_BODY_FRD = 12
MAV_DISTANCE_SENSOR_LASER = 0
ROTATION_FORWARD_FACING = 0
#: DRV_DIST_DEVTYPE_SIM (0x9A) on the simulation bus (DeviceBusType_SIMULATION = 4), as SIH's
DEVICE_ID = (0x9A << 16) | 4


def _in_fov(k: int, fov_deg: float) -> bool:
    """Whether bin ``k``'s centre is within the field of view centred on the front."""
    angle = k * INCREMENT_DEG
    off = angle if angle <= 180.0 else 360.0 - angle
    return fov_deg >= 360.0 or off <= fov_deg / 2.0 + 1e-9


def scan(world: World, x: float, y: float, z: float, yaw: float, sensor: RangeSensor) -> tuple[int, ...]:
    """The 72 distances (cm) of a scan from (x, y, z) (NED) with heading ``yaw`` (rad).

    What ``World.ray`` sees along each ray, computed box by box: only the boxes the level scan
    plane cuts and within reach, and of their rays only those inside the sector the box's
    bounding circle subtends (the others cannot hit it).
    """
    max_range = sensor.max_range
    max_cm = round(max_range * 100)
    best = [math.inf] * BINS
    fov = sensor.fov
    for box in world.boxes:
        if not box.z_top <= z <= box.z_bottom:
            continue  # the scan plane passes above (or below) it
        dx, dy = box.cx - x, box.cy - y
        centre = math.hypot(dx, dy)
        if centre - box.radius > max_range:
            continue
        if centre <= box.radius:
            first, last = 0, BINS * 3 - 1  # around (or inside) it: every ray may hit
        else:
            bearing = math.degrees(math.atan2(dy, dx) - yaw)
            half = math.degrees(math.asin(box.radius / centre))
            step = INCREMENT_DEG / 3.0  # the rays are 1/3 bin apart
            first = math.floor((bearing - half) / step) - 1
            last = math.ceil((bearing + half) / step) + 1
        for r in range(first, last + 1):
            k = ((r + 1) // 3) % BINS  # ray r: bin (r + 1) // 3, offset (r + 1) % 3 - 1 thirds
            if best[k] == 0.0:
                continue
            a = yaw + math.radians(r * INCREMENT_DEG / 3.0)
            d = box.ray(x, y, z, math.cos(a), math.sin(a), 0.0)
            if d < best[k]:
                best[k] = d
    out = []
    for k in range(BINS):
        if not _in_fov(k, fov):
            out.append(UINT16_MAX)
        elif best[k] > max_range:
            out.append(max_cm + 1)
        else:
            out.append(min(round(best[k] * 100), max_cm))
    return tuple(out)


@dataclass(slots=True)
class ObstacleDistanceSim:
    """The sensor at its rate: ``update`` returns the new scan and forward reading when one is
    due at ``t_us``, else None."""

    sensor: RangeSensor
    next_us: int = 0
    last: ObstacleDistance | None = None
    last_range: DistanceSensor | None = None
    logged_us: int = -(10**9)  # when distance_sensor was last logged (the logger takes it at 1 Hz)

    @property
    def interval_us(self) -> int:
        return round(1e6 / self.sensor.rate)

    def update(
        self, t_us: int, world: World, x: float, y: float, z: float, yaw: float
    ) -> tuple[ObstacleDistance, DistanceSensor] | None:
        if t_us < self.next_us:
            return None
        self.next_us = max(self.next_us + self.interval_us, t_us)
        s = self.sensor
        distances = scan(world, x, y, z, yaw, s)
        od = ObstacleDistance(
            t_us,
            INCREMENT_DEG,
            0.0,
            distances,
            round(s.min_range * 100),
            round(s.max_range * 100),
            MAV_FRAME_BODY_FRD,
            MAV_DISTANCE_SENSOR_LASER,
        )
        front = distances[0]
        current = (
            s.max_range + 0.01 if front == UINT16_MAX or front > round(s.max_range * 100) else front / 100
        )
        ds = DistanceSensor(
            t_us,
            DEVICE_ID,
            s.min_range,
            s.max_range,
            current,
            0.0,
            math.radians(INCREMENT_DEG),
            math.radians(INCREMENT_DEG),
            (1.0, 0.0, 0.0, 0.0),
            -1,
            MAV_DISTANCE_SENSOR_LASER,
            ROTATION_FORWARD_FACING,
        )
        self.last, self.last_range = od, ds
        return od, ds
