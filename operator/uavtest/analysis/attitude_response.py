"""How fast the body's tilt follows the thrust setpoint: a delay and a first-order lag, fitted.

PX4's PositionControl publishes its thrust setpoint (``vehicle_local_position_setpoint.thrust``,
NED, normalised); the attitude and rate controllers, the control allocation and the motors turn
it into a tilt (``vehicle_attitude``). The direction of the thrust is the body's -z axis, so the
horizontal components of the desired body z axis, -thrust / |thrust|, are compared with those of
the attitude's. The response is modelled as a pure delay followed by a first-order lag and both
are found by a grid search for the least RMS of the difference (the tilt's sine: 0.01 is 0.6
degrees). In PX4 v1.15 SIH this is 0.09 s and 0.06 s (``bench/bench_fidelity.py`` prints it for
every PX4 log and built-in flight).

A flight is fitted from ``AFTER_LIFTOFF`` seconds into its window on: at lift-off the body kicks
with the rate integrators wound up against the ground (``simulator_sih.KICK_GAIN``), a tilt no
thrust setpoint asked for. PX4's own fits do not move with it (24 flights flown here: 0.08 + 0.09
from the window's start, 0.08 + 0.08 from 3 s in; the shared mission2 logs 0.10 + 0.06 and
0.09 + 0.06), the built-in vehicle's, whose kicks are larger than those logs', would (0.09 + 0.10).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from uavtest.errors import BadInput

__all__ = [
    "AFTER_LIFTOFF",
    "DELAYS",
    "TAUS",
    "AttitudeResponse",
    "body_z_from_quaternion",
    "body_z_from_thrust",
    "fit",
]

RATE = 100.0  # Hz: both signals are resampled onto this grid
DELAYS = tuple(round(0.01 * i, 2) for i in range(26))  # s
TAUS = (0.0, 0.02, 0.04, 0.06, 0.08, 0.10, 0.12, 0.14, 0.16, 0.20, 0.25)  # s
SETTLE = 2.0  # s at the start of the window the filter needs to forget its initial state
AFTER_LIFTOFF = 3.0  # s: a flight window's start left out (the lift-off's kick: module docstring)


@dataclass(frozen=True, slots=True)
class AttitudeResponse:
    delay: float  # s
    tau: float  # s
    rms: float  # of the tilt's horizontal components (unitless: the sine of the tilt)

    def __str__(self) -> str:
        return f"{self.delay:.2f} + {self.tau:.2f} s"


def body_z_from_thrust(thrust: np.ndarray) -> np.ndarray:
    """(N, 2): north and east components of the body z axis a thrust setpoint (N, 3) asks for."""
    norm = np.linalg.norm(thrust, axis=1)
    norm[norm < 1e-6] = np.nan
    return -thrust[:, :2] / norm[:, None]


def body_z_from_quaternion(q: np.ndarray) -> np.ndarray:
    """(N, 2): north and east components of the body z axis of Hamilton quaternions (N, 4: w, x, y, z)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.column_stack((2 * (x * z + w * y), 2 * (y * z - w * x)))


def _lag(signal: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """First-order lag (time constant ``tau``) of (N, 2) samples ``dt`` apart, starting at rest
    at the first sample."""
    if tau <= 0.0:
        return signal
    a = dt / (tau + dt)
    first = signal[0]
    return first + lfilter([0.0, a], [1.0, a - 1.0], signal - first, axis=0)


def fit(
    t_setpoint: np.ndarray,
    desired: np.ndarray,
    t_attitude: np.ndarray,
    actual: np.ndarray,
    window: tuple[float, float],
    delays: Sequence[float] = DELAYS,
    taus: Sequence[float] = TAUS,
) -> AttitudeResponse:
    """The delay and lag that best turn ``desired`` (body z components at ``t_setpoint``) into
    ``actual`` (at ``t_attitude``) over ``window`` (seconds, same clock; the first ``SETTLE``
    seconds are not scored). BadInput when the window is too short to tell."""
    start, end = window
    if end - start < SETTLE + 2.0 or len(t_setpoint) < 2 or len(t_attitude) < 2:
        raise BadInput(f"attitude response: a window of {end - start:.1f} s is too short to fit")
    dt = 1.0 / RATE
    grid = np.arange(start, end, dt)
    want = np.column_stack([np.interp(grid, t_setpoint, desired[:, i]) for i in range(2)])
    got = np.column_stack([np.interp(grid, t_attitude, actual[:, i]) for i in range(2)])
    ok = np.isfinite(want).all(axis=1)
    want[~ok] = 0.0
    scored = grid >= start + SETTLE
    best: AttitudeResponse | None = None
    for tau in taus:
        lagged = _lag(want, tau, dt)
        for delay in delays:
            k = round(delay / dt)
            shifted = lagged
            if k:
                shifted = np.vstack([np.repeat(lagged[:1], k, axis=0), lagged[: len(lagged) - k]])
            rms = float(np.sqrt(np.mean((shifted[scored] - got[scored]) ** 2)))
            if best is None or rms < best.rms:
                best = AttitudeResponse(delay, tau, rms)
    assert best is not None
    return best
