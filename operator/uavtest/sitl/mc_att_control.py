"""PX4's attitude controller, its yaw axis: the yaw rate setpoint from the yaw setpoint.

``AttitudeControl::update`` (PX4 v1.15, ``mc_att_control``) for a body whose tilt is on its
setpoint (the built-in vehicle's tilt follows its own response, ``simulator_sih``): the yaw error
enters the mixed attitude scaled by ``MC_YAW_WEIGHT``, its quaternion error angle ``2 sin(w e / 2)``
is multiplied by ``MC_YAW_P / w`` (the gain compensates the weight), the flight task's yawspeed
setpoint is fed forward, and the sum is limited to ``MC_YAWRATE_MAX``. The rate loop and SIH's yaw
torque that follow are in ``mc_rate_control`` and ``simulator_sih``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.sitl.params import ParamStore

__all__ = ["YawGains", "yaw_rate_setpoint"]


@dataclass(frozen=True, slots=True)
class YawGains:
    """``MC_YAW_P``, ``MC_YAW_WEIGHT`` and ``MC_YAWRATE_MAX`` (rad/s), read once per parameter change."""

    p: float
    weight: float
    rate_max: float

    @classmethod
    def of(cls, params: ParamStore) -> YawGains:
        return cls(
            p=params["MC_YAW_P"],
            weight=min(max(params["MC_YAW_WEIGHT"], 0.0), 1.0),
            rate_max=math.radians(params["MC_YAWRATE_MAX"]),
        )


def yaw_rate_setpoint(yaw_sp: float, yaw: float, feedforward: float, gains: YawGains) -> float:
    """The yaw rate setpoint (rad/s) for heading ``yaw`` towards ``yaw_sp`` (rad), with the flight
    task's yawspeed setpoint ``feedforward`` (rad/s; NaN: none)."""
    err = math.remainder(yaw_sp - yaw, math.tau)
    w = gains.weight
    rate = gains.p / w * 2.0 * math.sin(w * err / 2.0) if w > 1e-4 else 0.0
    if feedforward == feedforward:
        rate += feedforward
    return max(-gains.rate_max, min(gains.rate_max, rate))
