"""The UAV Testing Competition's outcomes of a flight: its 2-D distance, points, hard / soft fail.

What the competition (skhatiri/UAV-Testing-Competition, evaluated with Aerialist) measures, so a
uavtest user gets the same numbers:

- **distance** (``competition_distance``): Aerialist's ``Trajectory.min_distance_to_obstacles``
  per obstacle, the smallest over the obstacles (the competition's ``TestCase.get_distances``).
  The flight's ``vehicle_local_position`` samples are averaged over 0.5 s windows
  (``downsample_time``: the first window is [t0, t0 + 0.5 s], each next one (start, start + 0.5 s]),
  joined into a line, the line widened to 0.25 m (``VEHICLE_WIDTH``) and its 2-D distance taken
  to each box's footprint (shapely ``box(-l/2, -w/2, l/2, w/2)`` turned by ``r`` degrees about its
  centre from x (North) towards y (East), then moved to (x, y)). Heights do not count: flying over
  a box is 0 m. That is ``max(0, line distance - 0.125 m)`` (shapely's buffer rounds its caps
  with 16 segments per quarter circle: at most 0.2 mm apart).
- **points** (``competition_points``, the README's ``point(sim)``): 5 if the distance is
  < 0.25 m, 2 if < 1 m, 1 if < 1.5 m, else 0 (every bound strict). The competition averages a
  test's points over its runs (5 of them).
- **hard fail**: a collision with an obstacle; **soft fail**: the vehicle did not keep the safe
  distance (the competition's is 1.5 m). The failed assertions' messages, and so the verdict's
  reason, start with these names (``HARD_FAIL``, ``SOFT_FAIL``).

uavtest measures in its own frame: the flight from takeoff to landing, relative to PX4's home.
Aerialist takes the whole log relative to its first sample; in Gazebo the vehicle boots at rest at
home, so the two differ by the estimator's drift on the ground (centimetres).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from uavtest.analysis.geometry import line_distances_2d
from uavtest.analysis.trajectory import Trajectory
from uavtest.spec.models import Obstacle

__all__ = [
    "HALF_WIDTH",
    "HARD_FAIL",
    "POINTS",
    "SAMPLE_PERIOD",
    "SOFT_FAIL",
    "SOFT_FAIL_DISTANCE",
    "competition_distance",
    "competition_points",
    "window_means",
]

SAMPLE_PERIOD = 0.5  # s: Aerialist's TRJ_SMPL_PRD (500000 µs)
HALF_WIDTH = 0.125  # m: half Aerialist's VEHICLE_WIDTH (0.25 m), the line's buffer
#: (distance below which, points), first match wins; 0 points otherwise
POINTS: tuple[tuple[float, int], ...] = ((0.25, 5), (1.0, 2), (1.5, 1))
SOFT_FAIL_DISTANCE = 1.5  # m: the competition's minimum safe distance
HARD_FAIL = "hard fail"  # the competition's name for a collision (a failed noCollision)
SOFT_FAIL = "soft fail"  # ... for a safe distance not kept (a failed minObstacleDistance)


def window_means(trajectory: Trajectory, period: float = SAMPLE_PERIOD) -> np.ndarray:
    """Aerialist's ``downsample_time``: the mean (x, y) of each ``period`` window, shape (k, 2).

    Windows start at the first sample: [t0, t0 + period], then (t0 + period, t0 + 2 period], ...;
    an empty window gives no point. Times are compared in whole microseconds, as the log has them.
    """
    if not len(trajectory):
        return np.zeros((0, 2))
    us = np.round(trajectory.t * 1e6).astype(np.int64)
    step = round(period * 1e6)
    window = np.maximum(-(-(us - us[0]) // step) - 1, 0)  # ceil((t - t0) / period) - 1, t0 in window 0
    _, first, counts = np.unique(window, return_index=True, return_counts=True)
    xy = np.column_stack((trajectory.x, trajectory.y))
    return np.add.reduceat(xy, first, axis=0) / counts[:, None]


def competition_distance(trajectory: Trajectory, obstacles: Sequence[Obstacle]) -> float | None:
    """The competition's min distance (metres, 2-D) of the flight to the obstacles, as its
    evaluation measures it (module doc); None without obstacles or without a flight."""
    if not obstacles or not len(trajectory):
        return None
    xy = window_means(trajectory)
    line = line_distances_2d(xy[:, 0], xy[:, 1], obstacles)
    return float(np.maximum(line - HALF_WIDTH, 0.0).min())


def competition_points(distance: float | None) -> int | None:
    """The competition's points for one run: 5 below 0.25 m, 2 below 1 m, 1 below 1.5 m, else 0;
    None when there is no distance (no obstacles, no flight)."""
    if distance is None:
        return None
    return next((points for bound, points in POINTS if distance < bound), 0)
