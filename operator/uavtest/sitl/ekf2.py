"""Estimator error: what the vehicle believes, as smooth, correlated, seeded processes.

PX4's EKF2 output (the output predictor: IMU-rate prediction corrected towards the delayed
filter state by a complementary filter) wanders around the truth by decimetres, smoothly: its
position is the integral of its velocity, so the derivative of the logged position does not jitter
(the SIH logs' hover speed from 10 Hz position differences is a few cm/s). The controller flies
the estimate, so replicas with different seeds take slightly different paths and times.

Modelled per axis as a velocity error that is a first-order Gauss-Markov process (standard
deviation ``SIGMA_V``, correlation time ``TAU_V``) and a position error that integrates it with a
leak (``TAU``: the GPS corrections pulling the estimate back), which keeps the position error
bounded (standard deviation about ``SIGMA_XY`` / ``SIGMA_Z``) and differentiable; the heading
error is a slow Gauss-Markov process. No white noise reaches the logged position or velocity.
"""

from __future__ import annotations

import math
import random

__all__ = ["Estimator"]

TAU = 4.0  # s: position error leak (GPS corrections)
TAU_V = 1.0  # s: velocity error correlation time
SIGMA_XY = 0.12  # m: standard deviation of the horizontal position error
SIGMA_Z = 0.08  # m
TAU_HEADING = 3.0  # s
SIGMA_HEADING = 0.005  # rad
#: stationary standard deviation of x for x' = -x / TAU + v, v Gauss-Markov(sigma_v, TAU_V):
#: sigma_x^2 = sigma_v^2 * TAU_V * TAU^2 / (TAU_V + TAU)
_GAIN = math.sqrt(TAU_V * TAU * TAU / (TAU_V + TAU))


class Estimator:
    """Position, velocity and heading error processes, advanced at the controller rate.

    ``ex, ey, ez`` (m) and ``evx, evy, evz`` (m/s) are the errors of the logged position and
    velocity (NED), ``eh`` (rad) of the heading.
    """

    __slots__ = ("_rng", "_sv", "eh", "evx", "evy", "evz", "ex", "ey", "ez")

    def __init__(self, rng: random.Random) -> None:
        self._rng = rng
        g = rng.gauss
        self._sv = (SIGMA_XY / _GAIN, SIGMA_XY / _GAIN, SIGMA_Z / _GAIN)
        sx, sy, sz = self._sv
        self.evx, self.evy, self.evz = g(0, sx), g(0, sy), g(0, sz)
        self.ex, self.ey, self.ez = g(0, SIGMA_XY), g(0, SIGMA_XY), g(0, SIGMA_Z)
        self.eh = g(0, SIGMA_HEADING)

    def update(self, dt: float) -> None:
        av = math.exp(-dt / TAU_V)
        bv = math.sqrt(1 - av * av)
        leak = 1.0 - dt / TAU
        g = self._rng.gauss
        sx, sy, sz = self._sv
        self.evx = av * self.evx + bv * sx * g(0.0, 1.0)
        self.evy = av * self.evy + bv * sy * g(0.0, 1.0)
        self.evz = av * self.evz + bv * sz * g(0.0, 1.0)
        self.ex = leak * self.ex + self.evx * dt
        self.ey = leak * self.ey + self.evy * dt
        self.ez = leak * self.ez + self.evz * dt
        ah = math.exp(-dt / TAU_HEADING)
        self.eh = ah * self.eh + math.sqrt(1 - ah * ah) * SIGMA_HEADING * g(0.0, 1.0)
