"""How far apart two flights are: DTW and discrete Fréchet distance on 3-D positions.

Both trajectories are first resampled to a common rate (``SIMILARITY_RATE`` Hz, linear
interpolation) so that the numbers do not depend on the logging rate of either log.

- DTW (dtaidistance's C ``dtw_ndim``): ``raw`` is dtaidistance's distance, the square root of
  the summed squared Euclidean distances along the optimal warping path; ``per_step`` is the mean
  Euclidean distance (metres) along that path — comparable across flights of any length, and
  what a ``similarity`` threshold for ``dtw`` is compared with.
- Discrete Fréchet: the smallest over monotone couplings of the largest point distance (metres),
  an O(n·m) dynamic program vectorized over anti-diagonals with numpy (similaritymeasures'
  pure-Python loop took 0.3 s for 600×600 points; this takes a few milliseconds).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from dtaidistance import dtw_ndim

from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import BadInput

__all__ = [
    "SIMILARITY_RATE",
    "DtwResult",
    "discrete_frechet",
    "dtw",
    "dtw_points",
    "frechet",
    "similarity",
]

SIMILARITY_RATE = 2.0  # Hz


@dataclass(frozen=True, slots=True)
class DtwResult:
    """DTW distance: ``per_step`` mean metres along the warping path, ``raw`` as dtaidistance gives it."""

    per_step: float
    raw: float
    path_length: int


def _points(traj: Trajectory, rate: float | None, name: str) -> np.ndarray:
    if len(traj) == 0:
        raise BadInput(f"{name} trajectory is empty: no flight to compare")
    resampled = traj.resample(rate) if rate else traj
    return np.ascontiguousarray(resampled.positions(), dtype=np.float64)


def dtw_points(a: np.ndarray, b: np.ndarray) -> DtwResult:
    """DTW between two (n, 3) / (m, 3) point arrays (no resampling)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    raw = float(dtw_ndim.distance(a, b, use_c=True))
    path = np.asarray(dtw_ndim.warping_path(a, b, use_c=True), dtype=np.intp)
    steps = np.linalg.norm(a[path[:, 0]] - b[path[:, 1]], axis=1)
    return DtwResult(per_step=float(steps.mean()), raw=raw, path_length=len(path))


def dtw(a: Trajectory, b: Trajectory, *, rate: float | None = SIMILARITY_RATE) -> DtwResult:
    """DTW between two trajectories' 3-D positions, resampled to ``rate`` Hz (None: as they are)."""
    return dtw_points(_points(a, rate, "first"), _points(b, rate, "second"))


def discrete_frechet(a: np.ndarray, b: np.ndarray) -> float:
    """Discrete Fréchet distance (Eiter & Mannila) between (n, d) and (m, d) point arrays."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n, m = len(a), len(b)
    if n == 0 or m == 0:
        raise BadInput("Fréchet distance needs two non-empty curves")
    cost = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)) if n * m <= 4_000_000 else None
    ca = np.full((n, m), np.inf)
    for k in range(n + m - 1):  # anti-diagonal i + j = k depends only on k-1 and k-2
        i = np.arange(max(0, k - m + 1), min(n, k + 1))
        j = k - i
        c = cost[i, j] if cost is not None else np.linalg.norm(a[i] - b[j], axis=1)
        if k == 0:
            ca[0, 0] = c[0]
            continue
        prev = np.full(len(i), np.inf)
        up = i > 0  # (i-1, j)
        prev[up] = np.minimum(prev[up], ca[i[up] - 1, j[up]])
        left = j > 0  # (i, j-1)
        prev[left] = np.minimum(prev[left], ca[i[left], j[left] - 1])
        diag = up & left  # (i-1, j-1)
        prev[diag] = np.minimum(prev[diag], ca[i[diag] - 1, j[diag] - 1])
        ca[i, j] = np.maximum(c, prev)
    return float(ca[n - 1, m - 1])


def frechet(a: Trajectory, b: Trajectory, *, rate: float | None = SIMILARITY_RATE) -> float:
    """Discrete Fréchet distance (metres) between two trajectories, resampled to ``rate`` Hz."""
    return discrete_frechet(_points(a, rate, "first"), _points(b, rate, "second"))


def similarity(metric: str, a: Trajectory, b: Trajectory, *, rate: float | None = SIMILARITY_RATE) -> float:
    """The distance a ``similarity`` assertion compares: DTW per step or Fréchet, in metres."""
    if metric == "dtw":
        return dtw(a, b, rate=rate).per_step
    if metric == "frechet":
        return frechet(a, b, rate=rate)
    raise BadInput("unknown similarity metric", field="metric", value=metric, allowed="dtw, frechet")
