"""Position mode's default stick mapping in PX4 v1.15: ``MPC_POS_MODE`` 4, acceleration based
(``flight_mode_manager/tasks/Utility/StickAccelerationXY``, used by
``FlightTaskManualAcceleration``).

The (expo'd) pitch / roll stick, rotated into the heading, is an acceleration: up to twice
``MPC_ACC_HOR`` at full stick, less a drag proportional to the velocity setpoint that makes full
stick settle at ``MPC_VEL_MANUAL`` (half stick after expo at its share of it). With the sticks
centred the drag grows (a brake boost filtered over 0.8 s, up to max(2, sqrt(MPC_VEL_MANUAL))
and a square-root boost below 1 m/s) so the vehicle stops; the acceleration is slew-limited by
``MPC_JERK_MAX`` and integrated into the velocity setpoint. Stopped (a zero velocity setpoint),
the position is locked; moving, it is released and the velocity setpoint restarts from the
position controller's last one (``lockPosition``). ``MPC_VEL_MAN_SIDE`` / ``MPC_VEL_MAN_BACK``
(-1: as ``MPC_VEL_MANUAL``) scale the sideways and backwards stick.
"""

from __future__ import annotations

import math

from uavtest.sitl.sticks import limit_unit_length

__all__ = ["StickAccelerationXY"]

_FLT_EPSILON = 1.1920929e-07
_GRAVITY = 9.80665
_BRAKE_BOOST_TAU_S = 0.8


def _sign(v: float) -> int:
    """``matrix::sign``: -1, 0 or 1."""
    return (v > 0.0) - (v < 0.0)


def _sqrt_linear(v: float) -> float:
    """``math::sqrt_linear``: sqrt below 1, linear above."""
    if v < 0.0:
        return 0.0
    return math.sqrt(v) if v < 1.0 else v


def _slew(value: float, target: float, rate: float, dt: float) -> float:
    """``SlewRate::update``: towards ``target`` by at most ``rate`` per second."""
    step = rate * dt
    return value + max(-step, min(step, target - value))


class StickAccelerationXY:
    """One ``StickAccelerationXY``: built when position mode is entered (``activate``)."""

    def __init__(self, vx: float, vy: float, ax: float = 0.0, ay: float = 0.0) -> None:
        self.vx, self.vy = vx, vy  # _velocity_setpoint
        self.ax, self.ay = ax, ay  # _acceleration_setpoint (the slew rates' state)
        self._ax_prev, self._ay_prev = 0.0, 0.0  # _acceleration_setpoint_prev
        self.px = self.py = math.nan  # _position_setpoint: NaN while moving
        self._brake_boost = 1.0  # _brake_boost_filter.reset(1.f)

    @property
    def locked(self) -> bool:
        return self.px == self.px

    def update(
        self,
        stick_x: float,
        stick_y: float,
        heading: float,
        x: float,
        y: float,
        feedback: tuple[float, float],
        dt: float,
        *,
        vel_manual: float,
        acc_hor: float,
        jerk_max: float,
        tilt_max: float,
        vel_man_side: float = -1.0,
        vel_man_back: float = -1.0,
    ) -> None:
        """``generateSetpoints``: ``stick_x`` / ``stick_y`` the expo'd pitch and roll (forward,
        right), ``heading`` the yaw they are turned by (the locked yaw setpoint, else the yaw),
        ``feedback`` the position controller's last velocity setpoint (NED)."""
        velocity_sc = vel_manual  # fminf(MPC_VEL_MANUAL, _velocity_constraint): no constraint here
        acc_sc = acc_hor * (velocity_sc / vel_manual) * 2.0  # drag halves the average acceleration
        sx, sy = limit_unit_length(stick_x, stick_y)
        if vel_man_side >= 0.0:
            sy *= vel_man_side / vel_manual
        if vel_man_back >= 0.0 and sx < 0.0:
            sx *= vel_man_back / vel_manual
        c, s = math.cos(heading), math.sin(heading)
        sx, sy = c * sx - s * sy, s * sx + c * sy  # rotateIntoHeadingFrameXY
        ax, ay = sx * acc_sc, sy * acc_sc
        # calculateDrag
        alpha = dt / (_BRAKE_BOOST_TAU_S + dt)
        centred = sx * sx + sy * sy < _FLT_EPSILON
        boost_target = max(2.0, math.sqrt(vel_manual)) if centred else 1.0
        self._brake_boost += alpha * (boost_target - self._brake_boost)
        coef = acc_sc / velocity_sc * self._brake_boost
        speed = math.hypot(self.vx, self.vy)
        ux, uy = (self.vx / speed, self.vy / speed) if speed > 1e-9 else (0.0, 0.0)
        boosted = _sqrt_linear(speed)
        brake_scale = min(1.0, max(0.0, self._brake_boost - 1.0))  # interpolate(state, 1, 2, 0, 1)
        mx = brake_scale * ux * boosted + (1.0 - brake_scale) * self.vx
        my = brake_scale * uy * boosted + (1.0 - brake_scale) * self.vy
        dx, dy = coef * mx, coef * my
        # the drag must not turn the velocity round (oscillation around zero)
        if (
            ax * ax + ay * ay < _FLT_EPSILON
            or _sign(self._ax_prev) != _sign(ax)
            or _sign(self._ay_prev) != _sign(ay)
        ) and self.vx * self.vx + self.vy * self.vy < (dx * dx + dy * dy) * dt * dt:
            dx = dy = 0.0
            self.vx = self.vy = 0.0
        ax, ay = ax - dx, ay - dy
        # applyJerkLimit: per axis, the slew rate shared out along the change
        jx, jy = ax - self._ax_prev, ay - self._ay_prev
        n = math.hypot(jx, jy)
        rx, ry = (abs(jx) / n * jerk_max, abs(jy) / n * jerk_max) if n > 0.0 else (0.0, 0.0)
        self.ax = _slew(self.ax, ax, rx, dt)
        self.ay = _slew(self.ay, ay, ry, dt)
        # applyTiltLimit
        a = math.hypot(self.ax, self.ay)
        a_max = math.tan(tilt_max) * _GRAVITY
        if a > a_max:
            self.ax, self.ay = self.ax * a_max / a, self.ay * a_max / a
        self.vx += self.ax * dt
        self.vy += self.ay * dt
        # lockPosition
        moving = self.vx * self.vx + self.vy * self.vy > _FLT_EPSILON
        if not moving and not self.locked:
            self.px, self.py = x, y
        if moving and self.locked:
            self.px = self.py = math.nan
            if math.isfinite(feedback[0]) and math.isfinite(feedback[1]):
                self.vx, self.vy = feedback
        self._ax_prev, self._ay_prev = self.ax, self.ay
