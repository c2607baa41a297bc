"""The simulated GPS and what the estimator does without it.

Failure injection of the GPS follows PX4's ``simulator_mavlink`` (``SimulatorMavlink.cpp``,
``handle_message``/failure commands): SENSOR_GPS OFF blocks the GPS, OK unblocks it (both
ACCEPTED, any instance); other failure types of the GPS are handled but UNSUPPORTED. (PX4 v1.15's
SIH ``sensor_gps_sim`` does not take the command at all: no module answers it.)

Without GPS, PX4's EKF2 dead-reckons on its inertial sensors (``EKF2_NOAID_TOUT``, 5 s): the
horizontal estimate drifts away from the truth and, after the timeout, the local horizontal
position and the global position become invalid (the vertical estimate stays valid on the
barometer). The drift is modelled as a constant velocity error (``DRIFT_SPEED`` in a seeded
direction) integrated from the loss. GPS back: the estimate snaps to the GPS again.
"""

from __future__ import annotations

import math
import random

from uavtest.mavlink_numbers import FailureType
from uavtest.sitl.mav import MavResult

__all__ = ["DRIFT_SPEED", "GpsSimulator"]

DRIFT_SPEED = 0.3  # m/s: inertial dead-reckoning drift of the horizontal estimate


class GpsSimulator:
    __slots__ = ("_rng", "blocked", "drift_vx", "drift_vy", "drift_x", "drift_y", "lost_us")

    def __init__(self, rng: random.Random) -> None:
        self._rng = rng
        self.blocked = False
        self.lost_us = 0
        self.drift_x = self.drift_y = 0.0
        self.drift_vx = self.drift_vy = 0.0

    def inject(self, failure_type: int, instance: int, t: int) -> MavResult:
        if failure_type == FailureType.OFF:
            if not self.blocked:
                self.blocked = True
                self.lost_us = t
                heading = self._rng.uniform(-math.pi, math.pi)
                self.drift_vx, self.drift_vy = (
                    DRIFT_SPEED * math.cos(heading),
                    DRIFT_SPEED * math.sin(heading),
                )
            return MavResult.ACCEPTED
        if failure_type == FailureType.OK:
            self.blocked = False
            self.drift_x = self.drift_y = 0.0
            return MavResult.ACCEPTED
        return MavResult.UNSUPPORTED

    def dead_reckon(self, dt: float) -> None:
        """One estimator step without GPS (called only while blocked)."""
        self.drift_x += self.drift_vx * dt
        self.drift_y += self.drift_vy * dt

    def position_valid(self, t: int, noaid_timeout_us: float) -> bool:
        """EKF2's horizontal (and so global) position validity at ``t``."""
        return not self.blocked or t - self.lost_us < noaid_timeout_us
