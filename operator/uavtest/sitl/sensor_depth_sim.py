"""A forward depth camera (named like PX4's ``simulation/sensor_*_sim`` modules): what PX4-Avoidance's
local planner sees of the test's boxes.

The competition's system under test flies PX4-Avoidance with ``iris_depth_camera``'s depth camera
(a RealSense-like sensor: about 86 deg horizontal field of view; the planner keeps points from
0.2 m to ``max_sensor_range_`` 15 m). Modelled as one horizontal row of rays (``World.ray``)
across the field of view, at the camera's frame rate, with depth noise growing with the square of
the distance (stereo depth) and a few dropped pixels, from a seeded stream. The planner turns the
hits into points (``uavtest.sitl.local_planner``). Rays are cast only when a box is within reach,
so a flight far from every box costs nothing here.
"""

from __future__ import annotations

import math
import random

from uavtest.sitl.simulator_sih import World

__all__ = ["DepthCamera"]

HFOV_DEG = 86.0  # horizontal field of view of the simulated depth camera
MAX_RANGE = 15.0  # m: PX4-Avoidance max_sensor_range_ (points beyond are discarded)
MIN_RANGE = 0.2  # m: min_sensor_range_
COLUMNS = 21  # rays across the field of view (4.3 deg apart, finer than the histogram's 6 deg bins)
DEPTH_NOISE = 0.002  # 1/m: depth standard deviation = DEPTH_NOISE * range^2 (stereo depth error)
DROPOUT = 0.03  # fraction of pixels without depth


class DepthCamera:
    """Casts the camera's rays from a pose; returns (bearing, range) per column (inf: nothing seen)."""

    def __init__(
        self, world: World, rng: random.Random, hfov_deg: float = HFOV_DEG, columns: int = COLUMNS
    ) -> None:
        self.world = world
        self.rng = rng
        self.hfov = math.radians(hfov_deg)
        self.columns = columns
        self.step = self.hfov / (columns - 1)
        self.offsets = [-self.hfov / 2 + i * self.step for i in range(columns)]
        self.max_range = MAX_RANGE

    def in_view(self, x: float, y: float) -> bool:
        """Whether any box is close enough to be seen from (x, y) (cheap pre-check)."""
        reach = self.max_range
        return any(math.hypot(x - b.cx, y - b.cy) - b.radius <= reach for b in self.world.boxes)

    def scan(self, x: float, y: float, z: float, yaw: float) -> list[tuple[float, float]]:
        """One frame from (x, y, z) NED looking along ``yaw``: (bearing rad, range m) per column."""
        if not self.in_view(x, y):
            return [(yaw + o, math.inf) for o in self.offsets]
        ray = self.world.ray
        gauss, uniform = self.rng.gauss, self.rng.random
        out: list[tuple[float, float]] = []
        rmax = self.max_range
        for o in self.offsets:
            b = yaw + o
            r = ray(x, y, z, math.cos(b), math.sin(b), 0.0, rmax)
            if r != math.inf:
                if uniform() < DROPOUT:
                    r = math.inf
                else:
                    r += gauss(0.0, DEPTH_NOISE * r * r)
                    if r < MIN_RANGE or r > rmax:
                        r = math.inf
            out.append((b, r))
        return out
