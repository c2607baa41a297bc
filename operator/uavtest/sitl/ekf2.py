"""Estimator and sensor noise: what the vehicle believes, as a seeded Gauss-Markov error.

PX4's EKF estimate wanders around the truth by decimetres (GPS noise, filter dynamics); the
controller flies the estimate, so replicas with different seeds take slightly different paths
and times. The error is a first-order Gauss-Markov process per axis (standard deviation
``SIGMA_*``, correlation time ``TAU``), plus small white noise on velocity and heading.
"""

from __future__ import annotations

import math
import random

__all__ = ["Estimator"]

TAU = 4.0  # s
SIGMA_XY = 0.12  # m
SIGMA_Z = 0.08  # m
SIGMA_V = 0.03  # m/s
SIGMA_HEADING = 0.005  # rad


class Estimator:
    """Position, velocity and heading error processes, advanced at the controller rate."""

    __slots__ = ("_rng", "eh", "evx", "evy", "evz", "ex", "ey", "ez")

    def __init__(self, rng: random.Random) -> None:
        self._rng = rng
        g = rng.gauss
        self.ex, self.ey, self.ez = g(0, SIGMA_XY), g(0, SIGMA_XY), g(0, SIGMA_Z)
        self.evx = self.evy = self.evz = 0.0
        self.eh = 0.0

    def update(self, dt: float) -> None:
        a = math.exp(-dt / TAU)
        b = math.sqrt(1 - a * a)
        g = self._rng.gauss
        self.ex = a * self.ex + b * SIGMA_XY * g(0.0, 1.0)
        self.ey = a * self.ey + b * SIGMA_XY * g(0.0, 1.0)
        self.ez = a * self.ez + b * SIGMA_Z * g(0.0, 1.0)
        self.evx = SIGMA_V * g(0.0, 1.0)
        self.evy = SIGMA_V * g(0.0, 1.0)
        self.evz = SIGMA_V * g(0.0, 1.0)
        self.eh = SIGMA_HEADING * g(0.0, 1.0)
