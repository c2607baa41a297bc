"""A flight path: time on the vehicle clock and PX4 local NED position and heading.

``Trajectory.to_csv()`` is the ``trajectory.csv`` artifact (header ``t,x,y,z,heading``).
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field

import numpy as np

from uavtest.errors import BadInput

__all__ = ["CSV_HEADER", "Trajectory"]

CSV_HEADER = "t,x,y,z,heading"


def _as_float_array(values: object) -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64).reshape(-1)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False, slots=True)
class Trajectory:
    """Samples of one flight, in time order.

    t: seconds on the vehicle clock (time since boot); x, y, z: NED metres from home
    (x North, y East, z Down, so altitude is ``-z``); heading: radians, 0 = North, positive
    towards East. All arrays have the same length and are read-only.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    heading: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        t = _as_float_array(self.t)
        heading = self.heading
        if heading is None or np.size(heading) == 0:
            heading = np.zeros_like(t)
        arrays = {
            "t": t,
            "x": _as_float_array(self.x),
            "y": _as_float_array(self.y),
            "z": _as_float_array(self.z),
            "heading": _as_float_array(heading),
        }
        lengths = {k: len(v) for k, v in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise BadInput("trajectory arrays differ in length", value=lengths)
        if len(t) > 1 and np.any(np.diff(t) < 0):
            raise BadInput("trajectory times must not decrease", field="t")
        for name, arr in arrays.items():
            object.__setattr__(self, name, arr)

    # ------------------------------------------------------------------ views

    def __len__(self) -> int:
        return len(self.t)

    @property
    def empty(self) -> bool:
        return len(self.t) == 0

    @property
    def duration(self) -> float:
        """Seconds from the first to the last sample (0 for fewer than two samples)."""
        return float(self.t[-1] - self.t[0]) if len(self.t) > 1 else 0.0

    @property
    def altitude(self) -> np.ndarray:
        """Metres above home: ``-z``."""
        return -self.z

    def positions(self) -> np.ndarray:
        """(n, 3) array of x, y, z."""
        return np.column_stack((self.x, self.y, self.z))

    def between(self, start: float, end: float) -> Trajectory:
        """The samples with ``start <= t <= end``."""
        keep = (self.t >= start) & (self.t <= end)
        return Trajectory(self.t[keep], self.x[keep], self.y[keep], self.z[keep], self.heading[keep])

    def resample(self, rate: float) -> Trajectory:
        """Linear interpolation on a uniform grid of ``rate`` Hz from the first sample.

        Heading is interpolated unwrapped, then wrapped back to (-pi, pi].
        """
        if rate <= 0:
            raise BadInput("resample rate must be positive", field="rate", value=rate)
        if len(self.t) < 2:
            return self
        grid = self.t[0] + np.arange(0.0, self.duration + 1e-9, 1.0 / rate)
        unwrapped = np.unwrap(self.heading)
        heading = np.interp(grid, self.t, unwrapped)
        heading = np.angle(np.exp(1j * heading))
        return Trajectory(
            grid,
            np.interp(grid, self.t, self.x),
            np.interp(grid, self.t, self.y),
            np.interp(grid, self.t, self.z),
            heading,
        )

    # ------------------------------------------------------------------ CSV

    def to_csv(self) -> str:
        """``trajectory.csv``: header ``t,x,y,z,heading``, one row per sample."""
        buf = io.StringIO()
        data = np.column_stack((self.t, self.x, self.y, self.z, self.heading))
        buf.write(CSV_HEADER + "\n")
        if len(data):
            np.savetxt(buf, data, delimiter=",", fmt=["%.6f", "%.4f", "%.4f", "%.4f", "%.5f"])
        return buf.getvalue()

    @classmethod
    def from_csv(cls, text: str, *, source: str = "trajectory.csv") -> Trajectory:
        """Parse ``to_csv()`` output; raises BadInput naming ``source`` when it is not one."""
        lines = text.strip().splitlines()
        if not lines or lines[0].strip().replace(" ", "") != CSV_HEADER:
            got = lines[0][:60] if lines else ""
            raise BadInput("not a trajectory CSV", file=source, field="header", value=got, allowed=CSV_HEADER)
        if len(lines) == 1:
            return cls(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0))
        try:
            data = np.loadtxt(io.StringIO("\n".join(lines[1:])), delimiter=",", ndmin=2)
        except ValueError as e:
            raise BadInput(f"unreadable trajectory rows: {e}", file=source) from e
        if data.shape[1] != 5:
            raise BadInput("each row needs 5 columns", file=source, value=data.shape[1], allowed=CSV_HEADER)
        return cls(data[:, 0], data[:, 1], data[:, 2], data[:, 3], data[:, 4])
