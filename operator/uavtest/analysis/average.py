"""Averaging N flights of different lengths into one mean trajectory with a spread band.

Each flight is resampled on **normalized progress** — the fraction of its own flight time,
0 at takeoff and 1 at landing — then mean, standard deviation, min and max are taken across
flights at each grid point. Why progress rather than time since takeoff: replicas of one test
fly the same path at different paces (PX4 itself varies 41–47 s on the same mission from hover
and turn timing). On a time axis the shorter flights end first, so the tail of the "average" is
an average of fewer and fewer flights and its landing point is smeared across the map; on
progress every flight contributes at every grid point, takeoff aligns with takeoff and landing
with landing. The average's time axis is progress × the mean flight time, so it still reads in
seconds. Within a flight, pace differences still shift points along the path; the spread band
shows that honestly (DTW is the measure that ignores pace).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import BadInput

__all__ = ["AVERAGE_CSV_COLUMNS", "AverageTrajectory", "average_trajectories"]

AXES = ("x", "y", "z")
AVERAGE_CSV_COLUMNS = (
    "progress",
    "t",
    *AXES,
    *(f"{a}_std" for a in AXES),
    *(f"{a}_min" for a in AXES),
    *(f"{a}_max" for a in AXES),
)


@dataclass(frozen=True, eq=False, slots=True)
class AverageTrajectory:
    """Mean of N flights on a common progress grid, with the spread across flights.

    progress: (k,) 0..1; t: (k,) seconds since takeoff (progress × mean flight time);
    mean, std, min, max: (k, 3) x, y, z NED metres; count: flights averaged;
    durations: each flight's duration (s).
    """

    progress: np.ndarray
    t: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    min: np.ndarray
    max: np.ndarray
    count: int
    durations: np.ndarray

    def trajectory(self) -> Trajectory:
        """The mean as a Trajectory (t since takeoff; heading not averaged: zeros)."""
        return Trajectory(self.t, self.mean[:, 0], self.mean[:, 1], self.mean[:, 2], np.zeros(len(self.t)))

    def to_csv(self) -> str:
        """``aggregate/average.csv``: columns ``AVERAGE_CSV_COLUMNS``, one row per grid point."""
        data = np.column_stack((self.progress, self.t, self.mean, self.std, self.min, self.max))
        buf = io.StringIO()
        buf.write(",".join(AVERAGE_CSV_COLUMNS) + "\n")
        np.savetxt(buf, data, delimiter=",", fmt="%.4f")
        return buf.getvalue()

    @classmethod
    def from_csv(cls, text: str, *, source: str = "average.csv") -> AverageTrajectory:
        lines = text.strip().splitlines()
        header = ",".join(AVERAGE_CSV_COLUMNS)
        if not lines or lines[0].strip() != header:
            raise BadInput("not an average trajectory CSV", file=source, field="header", allowed=header)
        data = np.loadtxt(io.StringIO("\n".join(lines[1:])), delimiter=",", ndmin=2)
        return cls(
            progress=data[:, 0],
            t=data[:, 1],
            mean=data[:, 2:5],
            std=data[:, 5:8],
            min=data[:, 8:11],
            max=data[:, 11:14],
            count=0,
            durations=np.zeros(0),
        )


def average_trajectories(trajectories: Sequence[Trajectory], *, points: int = 500) -> AverageTrajectory:
    """Mean and spread of flights of different lengths, on ``points`` steps of normalized progress.

    Flights with fewer than two samples (never took off) are left out; BadInput when none is left.
    """
    flights = [tr for tr in trajectories if len(tr) >= 2 and tr.duration > 0]
    if not flights:
        raise BadInput("no flight to average: every trajectory is empty", value=len(trajectories))
    if points < 2:
        raise BadInput("an average needs at least 2 points", field="points", value=points)
    grid = np.linspace(0.0, 1.0, points)
    stacked = np.empty((len(flights), points, 3))
    durations = np.empty(len(flights))
    for k, tr in enumerate(flights):
        durations[k] = tr.duration
        progress = (tr.t - tr.t[0]) / tr.duration
        stacked[k, :, 0] = np.interp(grid, progress, tr.x)
        stacked[k, :, 1] = np.interp(grid, progress, tr.y)
        stacked[k, :, 2] = np.interp(grid, progress, tr.z)
    return AverageTrajectory(
        progress=grid,
        t=grid * durations.mean(),
        mean=stacked.mean(axis=0),
        std=stacked.std(axis=0),
        min=stacked.min(axis=0),
        max=stacked.max(axis=0),
        count=len(flights),
        durations=durations,
    )
