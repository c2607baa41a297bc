"""PX4's rate controller, its yaw axis: the gains ``simulator_sih.Body`` runs it with.

``RateControl::update`` (PX4 v1.15, ``lib/rate_control``): normalised torque = ``MC_YAWRATE_K`` ×
(``MC_YAWRATE_P`` × error + integral), the integral growing at ``MC_YAWRATE_I`` × error × a factor
that shrinks with large errors (1 − (error / 400 °/s)²), bounded by ``MC_YR_INT_LIM`` and held
while landed; ``MC_YAWRATE_D`` and ``_FF`` are 0 in the SIH airframe and not modelled. The body
integrates it at the physics rate (``Body.step``), where SIH turns the torque into yaw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.sitl.params import ParamStore

__all__ = ["I_FACTOR_RATE", "YawRateGains"]

#: RateControl::updateIntegral's I-term factor: the error at which the integration stops (rad/s)
I_FACTOR_RATE = math.radians(400.0)


@dataclass(frozen=True, slots=True)
class YawRateGains:
    """``MC_YAWRATE_P`` and ``_I`` scaled by ``MC_YAWRATE_K``, and ``MC_YR_INT_LIM``."""

    p: float
    i: float
    int_lim: float

    @classmethod
    def of(cls, params: ParamStore) -> YawRateGains:
        k = params["MC_YAWRATE_K"]
        # MulticopterRateControl: setPidGains(rate_k x P, rate_k x I, rate_k x D)
        p, i = params["MC_YAWRATE_P"], params["MC_YAWRATE_I"]
        return cls(p=k * p, i=k * i, int_lim=params["MC_YR_INT_LIM"])
