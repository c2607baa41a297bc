"""Stage 5: what the runner watches during the flight (pure).

Minimum 3-D distance to the obstacles and collision, geofence, altitude, from each
LOCAL_POSITION_NED. The box maths is ``uavtest.analysis.geometry``'s (the same convention the
verdict uses), done per point in plain floats with the boxes prepared once — the monitor runs for
every position message, so it must cost microseconds, not a numpy call.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from uavtest.analysis.geometry import obstacle_arrays
from uavtest.runner.events import LocalPosition
from uavtest.spec.models import Geofence, Obstacle

__all__ = ["CLIMB_THRESHOLD", "FlightMonitor"]

CLIMB_THRESHOLD = 0.5  # metres above the first position that count as airborne


class FlightMonitor:
    """Folds positions into the online metrics."""

    def __init__(
        self, obstacles: Sequence[Obstacle], geofence: Geofence | None = None, *, radius: float = 0.0
    ) -> None:
        arrays = obstacle_arrays(obstacles)
        self._boxes = [
            (
                float(c[0]),
                float(c[1]),
                float(c[2]),
                float(h[0]),
                float(h[1]),
                float(h[2]),
                math.cos(yaw),
                math.sin(yaw),
            )
            for c, h, yaw in zip(arrays["centre"], arrays["half"], arrays["yaw"], strict=True)
        ]
        self.geofence = geofence
        self.radius = radius
        self.min_distance = math.inf
        self.last_distance = math.inf  # at the latest position (inf without obstacles)
        self.collision: LocalPosition | None = None  # the first position inside a box
        self.geofence_violation = 0.0
        self.max_altitude = -math.inf
        self.airborne = False
        self.samples = 0
        self._ground_z: float | None = None

    @property
    def has_obstacles(self) -> bool:
        return bool(self._boxes)

    def distance(self, x: float, y: float, z: float) -> float:
        """3-D distance from NED point (x, y, z) to the nearest box, minus the radius, floored at 0."""
        alt = -z
        best = math.inf
        for cx, cy, ca, hl, hw, hh, cos, sin in self._boxes:
            dx, dy = x - cx, y - cy
            ou = max(abs(cos * dx + sin * dy) - hl, 0.0)
            ov = max(abs(-sin * dx + cos * dy) - hw, 0.0)
            oa = max(abs(alt - ca) - hh, 0.0)
            d = math.sqrt(ou * ou + ov * ov + oa * oa)
            if d < best:
                best = d
        return max(best - self.radius, 0.0) if self.radius else best

    def on_position(self, p: LocalPosition) -> None:
        self.samples += 1
        if self._ground_z is None:
            self._ground_z = p.z
        if not self.airborne and self._ground_z - p.z > CLIMB_THRESHOLD:
            self.airborne = True
        if -p.z > self.max_altitude:
            self.max_altitude = -p.z
        if self._boxes:
            d = self.distance(p.x, p.y, p.z)
            self.last_distance = d
            if d < self.min_distance:
                self.min_distance = d
            if d <= 0.0 and self.collision is None:
                self.collision = p
        fence = self.geofence
        if fence is not None:
            ox = max(fence.min_x - p.x, 0.0, p.x - fence.max_x)
            oy = max(fence.min_y - p.y, 0.0, p.y - fence.max_y)
            oz = max(fence.min_z - p.z, 0.0, p.z - fence.max_z)
            out = math.sqrt(ox * ox + oy * oy + oz * oz)
            if out > self.geofence_violation:
                self.geofence_violation = out
