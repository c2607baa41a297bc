"""PX4's hover thrust estimator (``mc_hover_thrust_estimator``, PX4 v1.15): a one-state EKF.

``ZeroOrderHoverThrustEkf``: the state is the hover thrust (the collective thrust that holds the
vehicle up, 0..1); the measurement is the vertical acceleration (up) against the collective thrust
(up), predicted as ``g * thrust / hover - g``. The state is constant (process noise
``HTE_HT_NOISE``), the measurement noise is learnt from the residuals (bounded to 1..400 m^2/s^4),
a measurement is fused only inside the innovation gate (``HTE_ACC_GATE``), and a persistent
offset bumps the state's variance. ``MulticopterHoverThrustEstimator`` runs it while armed and in
the air (the distance to the ground above 1 m since the last landing), desensitised above
``HTE_VZ_THR`` / ``HTE_VXY_THR``, and calls the estimate valid once its variance is below 0.001
(the first time with the innovation test passing). ``MPC_USE_HTE``: PositionControl then uses it.

Why it matters for a SIH flight: SIH's drag acts on the vertical velocity too (``SIH_KDV``), so
during the takeoff climb the estimate rises from ``MPC_THR_HOVER`` 0.5 to about 0.56 (the true
hover thrust is ``SIH_MASS * g / (4 * SIH_T_MAX)`` = 0.49) and only comes back over the next
tens of seconds (the 16 PX4 v1.15 SIH flights flown here log it, ``hover_thrust_estimate``).
Meanwhile PositionControl holds the altitude with a positive (downward) vertical acceleration
setpoint, and its horizontal tracking anti-windup, which judges the horizontal acceleration the
thrust gives with that estimate, bleeds the velocity integrator: the vehicle gathers speed on a
leg more slowly than its trajectory (``mc_pos_control``).
"""

from __future__ import annotations

from uavtest.sitl.params import ParamStore
from uavtest.sitl.simulator_sih import GRAVITY

__all__ = ["HoverThrustEstimator"]

VALID_VARIANCE = 0.001  # thrust^2: MulticopterHoverThrustEstimator's validity threshold
IN_AIR_HEIGHT = 1.0  # m: the distance to the ground that starts the estimation after takeoff
LPF_TIME_CONSTANT = 1.0  # s: ZeroOrderHoverThrustEkf::_lpf_time_constant
NOISE_LEARNING_TIME_CONSTANT = 2.0  # s: ZeroOrderHoverThrustEkf::_noise_learning_time_constant
ACC_VAR_INIT = 5.0  # m^2/s^4: resetAccelNoise


class HoverThrustEstimator:
    """The hover thrust estimate (``hover``) and the one PositionControl flies with (``used``)."""

    __slots__ = (
        "_acc_var",
        "_gate",
        "_in_air",
        "_lpf_ratio",
        "_lpf_residual",
        "_process_var",
        "_var",
        "_vxy_thr",
        "_vz_thr",
        "hover",
        "init",
        "init_err",
        "innov",
        "innov_var",
        "ratio",
        "used",
        "valid",
    )

    def __init__(self, params: ParamStore) -> None:
        self.init = params["MPC_THR_HOVER"]
        self.init_err = params["HTE_HT_ERR_INIT"]
        self._process_var = params["HTE_HT_NOISE"] ** 2
        self._gate = params["HTE_ACC_GATE"]
        self._vxy_thr = params["HTE_VXY_THR"]
        self._vz_thr = params["HTE_VZ_THR"]
        self.reset()

    def reset(self) -> None:
        """Disarmed: back to ``MPC_THR_HOVER`` with ``HTE_HT_ERR_INIT`` of uncertainty."""
        self.hover = self.used = self.init
        self._var = self.init_err * self.init_err
        self._acc_var = ACC_VAR_INIT
        self._lpf_residual = self._lpf_ratio = 0.0
        self._in_air = False
        self.valid = False
        self.innov = self.innov_var = self.ratio = 0.0

    @property
    def variance(self) -> float:
        return self._var

    @property
    def accel_noise_var(self) -> float:
        return self._acc_var

    def update(
        self,
        dt: float,
        acc_up: float,
        thrust_up: float,
        vz: float,
        vxy: float,
        dist_bottom: float,
        landed: bool,
    ) -> bool:
        """One estimator step; True when PositionControl should take the new estimate (valid)."""
        if landed:
            self._in_air = False
        elif dist_bottom > IN_AIR_HEIGHT:
            self._in_air = True
        if not self._in_air or dt <= 0.001:
            self.valid = False
            return False
        self._var += self._process_var * dt * dt  # predict: the state is constant
        scale = max(abs(vz) - self._vz_thr + 1.0, vxy - self._vxy_thr + 1.0, 1.0)
        h = self.hover
        big_h = -GRAVITY * thrust_up / (h * h)
        r = self._acc_var * scale * scale
        innov_var = max(big_h * self._var * big_h + r, r)
        innov = acc_up - (GRAVITY * thrust_up / h - GRAVITY)
        ratio = innov * innov / (self._gate * self._gate * innov_var)
        self.innov, self.innov_var, self.ratio = innov, innov_var, ratio
        residual = innov
        if ratio < 1.0:
            k = self._var * big_h / innov_var
            self.hover = min(max(h + k * innov, 0.1), 0.9)
            self._var = min(max((1.0 - k * big_h) * self._var, 1e-10), 1.0)
            residual = acc_up - (GRAVITY * thrust_up / self.hover - GRAVITY)
        elif abs(self._lpf_ratio) > 0.2:  # a persistent offset: let the state move again
            self._var += 1e3 * self._process_var * dt * dt
        a = dt / (LPF_TIME_CONSTANT + dt)
        self._lpf_residual = (1.0 - a) * self._lpf_residual + a * residual
        signed = ratio if innov >= 0.0 else -ratio
        self._lpf_ratio = (1.0 - a) * self._lpf_ratio + a * max(-1.0, min(1.0, signed))
        b = dt / (NOISE_LEARNING_TIME_CONSTANT + dt)
        res = residual - self._lpf_residual
        self._acc_var = min(
            max((1.0 - b) * self._acc_var + b * (res * res + big_h * self._var * big_h), 1.0), 400.0
        )
        valid = self._var < VALID_VARIANCE and (self.valid or ratio < 1.0)
        self.valid = valid
        return valid
