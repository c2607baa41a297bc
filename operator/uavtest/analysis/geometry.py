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

``line_distances_2d`` is the other measure, the one Aerialist and the UAV Testing Competition
use: in the (x, y) plane only, from the polyline through the samples to each box's footprint
(heights ignored, so flying over a box is a distance of 0). ``uavtest.analysis.competition``
applies it the way they do.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from uavtest.spec.models import Obstacle

__all__ = [
    "box_corners",
    "collides",
    "distances_to_obstacles",
    "line_distances_2d",
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


def line_distances_2d(x: ArrayLike, y: ArrayLike, obstacles: Sequence[Obstacle]) -> np.ndarray:
    """Per obstacle, the 2-D distance (metres) from the polyline through the points (x, y) to the
    obstacle's footprint (its yawed l × w rectangle); 0 where the line enters or crosses it.

    Heights are ignored. One point is a degenerate line (its distance to each footprint). Shape
    (m,) for m obstacles; empty without obstacles, ``inf`` per obstacle without points.
    Vectorized over segments and boxes: a segment that misses a rectangle is nearest to it at one
    of its two ends or at one of the four corners (both shapes are convex).
    """
    px = np.atleast_1d(np.asarray(x, dtype=np.float64))
    py = np.atleast_1d(np.asarray(y, dtype=np.float64))
    if not obstacles:
        return np.zeros(0)
    if not px.size:
        return np.full(len(obstacles), np.inf)
    boxes = obstacle_arrays(obstacles)
    cx, cy, _ = boxes["centre"].T  # (m,)
    half = boxes["half"][:, :2]  # (m, 2): l/2 along u, w/2 along v
    cos, sin = np.cos(boxes["yaw"]), np.sin(boxes["yaw"])
    dx = px[:, None] - cx[None, :]  # (n, m)
    dy = py[:, None] - cy[None, :]
    p = np.stack((cos * dx + sin * dy, -sin * dx + cos * dy), axis=-1)  # (n, m, 2) in each box's frame
    outside = np.maximum(np.abs(p) - half, 0.0)
    point = np.sqrt((outside**2).sum(axis=-1))  # (n, m): each point to each footprint
    if len(px) == 1:
        return point[0]
    a, d = p[:-1], p[1:] - p[:-1]  # segments a + t d, t in [0, 1]: (n-1, m, 2)
    # does the segment enter the rectangle? (Liang–Barsky clipping on both axes)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - a) / d
        t2 = (half - a) / d
    moving = d != 0.0
    lo = np.where(moving, np.minimum(t1, t2), -np.inf)
    hi = np.where(moving, np.maximum(t1, t2), np.inf)
    still_inside = moving | (np.abs(a) <= half)
    enter = np.maximum(lo.max(axis=-1), 0.0)
    leave = np.minimum(hi.min(axis=-1), 1.0)
    hits = still_inside.all(axis=-1) & (enter <= leave)  # (n-1, m)
    # otherwise: the nearer of its ends and the footprint's corners nearest to it
    signs = np.array([[1.0, 1.0], [1.0, -1.0], [-1.0, -1.0], [-1.0, 1.0]])
    corners = half[:, None, :] * signs[None, :, :]  # (m, 4, 2)
    dd = (d * d).sum(axis=-1)  # (n-1, m)
    rel = corners[None, :, :, :] - a[:, :, None, :]  # (n-1, m, 4, 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(dd[..., None] > 0, (rel * d[:, :, None, :]).sum(axis=-1) / dd[..., None], 0.0)
    t = np.clip(t, 0.0, 1.0)
    gap = rel - t[..., None] * d[:, :, None, :]
    corner = np.sqrt((gap**2).sum(axis=-1)).min(axis=-1)  # (n-1, m)
    segment = np.minimum(np.minimum(point[:-1], point[1:]), corner)
    return np.where(hits, 0.0, segment).min(axis=0)


def box_corners(obstacle: Obstacle) -> np.ndarray:
    """The four (x, y) corners of the obstacle's footprint, in order around it: shape (4, 2)."""
    hl, hw = obstacle.size.l / 2, obstacle.size.w / 2
    r = np.radians(obstacle.position.r)
    local = np.array([[hl, hw], [hl, -hw], [-hl, -hw], [-hl, hw]])
    rot = np.array([[np.cos(r), -np.sin(r)], [np.sin(r), np.cos(r)]])
    return local @ rot.T + np.array([obstacle.position.x, obstacle.position.y])
