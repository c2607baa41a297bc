"""True 3-D distance from the vehicle to box obstacles.

Obstacles follow Aerialist's convention (``uavtest.spec.models.Obstacle``): size ``l, w, h``;
position ``x`` (North), ``y`` (East) of the box centre, ``z`` the base height measured UP from
the ground, yaw ``r`` in degrees. Before yaw, ``l`` runs along x (North) and ``w`` along y (East);
yaw turns the box from North towards East about its centre (as Aerialist's
``shapely.affinity.rotate(rect, r)`` on (x, y) does). The box spans altitudes ``z .. z + h``.

Vehicle positions are PX4 local NED (z Down), so the vehicle's altitude is ``-z``.

Unlike Aerialist, which measured in the (x, y) plane so that flying over a box counted as a hit,
the distance here is Euclidean in 3-D: 12 m above a 10 m tall box is 2 m away.

``radius`` (default 0: the vehicle is a point) is subtracted from every distance, floored at 0;
a collision is a distance of 0 — the point (or the vehicle's sphere) is inside or touching a box.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from uavtest.spec.models import Obstacle

__all__ = [
    "box_corners",
    "collides",
    "distances_to_obstacles",
    "min_distance_to_obstacles",
    "obstacle_arrays",
]

ArrayLike = float | Sequence[float] | np.ndarray


def obstacle_arrays(obstacles: Sequence[Obstacle]) -> dict[str, np.ndarray]:
    """Each obstacle's centre (x, y, altitude), half-extents (l/2, w/2, h/2) and yaw (rad), as arrays."""
    return {
        "centre": np.array(
            [[o.position.x, o.position.y, o.position.z + o.size.h / 2] for o in obstacles], dtype=np.float64
        ).reshape(-1, 3),
        "half": np.array(
            [[o.size.l / 2, o.size.w / 2, o.size.h / 2] for o in obstacles], dtype=np.float64
        ).reshape(-1, 3),
        "yaw": np.radians(np.array([o.position.r for o in obstacles], dtype=np.float64)),
    }


def distances_to_obstacles(
    x: ArrayLike, y: ArrayLike, z: ArrayLike, obstacles: Sequence[Obstacle], *, radius: float = 0.0
) -> np.ndarray:
    """Per point, the 3-D distance (metres) to the nearest obstacle; ``inf`` without obstacles.

    x, y, z: NED positions (scalars or equal-length arrays). Vectorized over points and boxes.
    """
    px = np.atleast_1d(np.asarray(x, dtype=np.float64))
    py = np.atleast_1d(np.asarray(y, dtype=np.float64))
    alt = -np.atleast_1d(np.asarray(z, dtype=np.float64))
    if not obstacles:
        return np.full(px.shape, np.inf)
    boxes = obstacle_arrays(obstacles)
    cx, cy, ca = boxes["centre"].T  # (m,)
    hl, hw, hh = boxes["half"].T
    cos, sin = np.cos(boxes["yaw"]), np.sin(boxes["yaw"])
    dx = px[:, None] - cx[None, :]  # (n, m)
    dy = py[:, None] - cy[None, :]
    # into each box's frame: u along l (yawed North towards East), v along w
    u = cos * dx + sin * dy
    v = -sin * dx + cos * dy
    a = alt[:, None] - ca[None, :]
    ou = np.maximum(np.abs(u) - hl, 0.0)
    ov = np.maximum(np.abs(v) - hw, 0.0)
    oa = np.maximum(np.abs(a) - hh, 0.0)
    dist = np.sqrt(ou * ou + ov * ov + oa * oa).min(axis=1)
    if radius:
        dist = np.maximum(dist - radius, 0.0)
    return dist


def min_distance_to_obstacles(
    x: ArrayLike, y: ArrayLike, z: ArrayLike, obstacles: Sequence[Obstacle], *, radius: float = 0.0
) -> float:
    """The smallest 3-D distance (metres) from the point(s) to any obstacle; ``inf`` without obstacles."""
    d = distances_to_obstacles(x, y, z, obstacles, radius=radius)
    return float(d.min()) if d.size else float("inf")


def collides(
    x: ArrayLike, y: ArrayLike, z: ArrayLike, obstacles: Sequence[Obstacle], *, radius: float = 0.0
) -> bool:
    """True when any point is inside or touching an obstacle (distance 0 after ``radius``)."""
    return bool(obstacles) and min_distance_to_obstacles(x, y, z, obstacles, radius=radius) <= 0.0


def box_corners(obstacle: Obstacle) -> np.ndarray:
    """The four (x, y) corners of the obstacle's footprint, in order around it: shape (4, 2)."""
    hl, hw = obstacle.size.l / 2, obstacle.size.w / 2
    r = np.radians(obstacle.position.r)
    local = np.array([[hl, hw], [hl, -hw], [-hl, -hw], [-hl, hw]])
    rot = np.array([[np.cos(r), -np.sin(r)], [np.sin(r), np.cos(r)]])
    return local @ rot.T + np.array([obstacle.position.x, obstacle.position.y])
