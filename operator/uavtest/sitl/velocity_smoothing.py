"""PX4's jerk-limited velocity trajectory of one axis (``lib/motion_planning/VelocitySmoothing``).

PositionSmoothing (the auto modes' trajectory) keeps one such trajectory per axis. Every tick it
advances each axis along its current profile, then plans a new time-optimal profile from the
axis' state (acceleration, velocity, position) to the new velocity setpoint: jerk at +-``j_max``
for T1, acceleration held (at most ``a_max``) for T2, jerk back for T3, then constant velocity.
The x and y profiles are then synchronized: the shorter one is re-planned to take as long as the
longer, so the horizontal velocity changes along a straight line in velocity space.

Facts carried over from PX4 v1.15 ``VelocitySmoothing.cpp`` (the formulas for T1, T2, T3 and the
direction); written from them, not translated line by line.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Profile", "advance", "plan", "plan_given_time", "synchronize", "synchronize_axes"]


@dataclass(slots=True)
class Profile:
    """One axis' plan from its state: the three phase durations and the jerk's sign."""

    a0: float
    v0: float
    x0: float
    jerk: float  # j_max
    direction: int
    t1: float = 0.0
    t2: float = 0.0
    t3: float = 0.0

    @property
    def total(self) -> float:
        return self.t1 + self.t2 + self.t3


def _sign(x: float) -> int:
    return (x > 0.0) - (x < 0.0)


def _saturate_t1(a0: float, j: float, t1: float, a_max: float) -> float:
    a = a0 + j * t1
    if a > a_max:
        return (a_max - a0) / j
    if a < -a_max:
        return (-a_max - a0) / j
    return t1


def _t1(a0: float, dv: float, j: float, a_max: float) -> float:
    delta = 2.0 * a0 * a0 + 4.0 * j * dv
    if delta < 0.0:
        return 0.0
    r = math.sqrt(delta)
    t_plus, t_minus = (-a0 + 0.5 * r) / j, (-a0 - 0.5 * r) / j
    t1 = 0.0
    if t_plus >= 0.0 and a0 / j + t_plus >= 0.0:
        t1 = t_plus
    elif t_minus >= 0.0 and a0 / j + t_minus >= 0.0:
        t1 = t_minus
    return max(_saturate_t1(a0, j, t1, a_max), 0.0)


def _t1_given_time(total: float, a0: float, dv: float, j: float, a_max: float) -> float:
    b = j * total - a0
    delta = total * total * j * j + 2.0 * total * a0 * j - a0 * a0 - 4.0 * j * dv
    if delta < 0.0:
        return 0.0
    r = math.sqrt(delta)
    inv = 1.0 / (-2.0 * j)
    t_plus, t_minus = max((-b + r) * inv, 0.0), max((-b - r) * inv, 0.0)
    t1 = 0.0
    t3_plus, t3_minus = a0 / j + t_plus, a0 / j + t_minus
    if t3_plus >= 0.0 and t_plus + t3_plus <= total:
        t1 = t_plus
    elif t3_minus >= 0.0 and t_minus + t3_minus <= total:
        t1 = t_minus
    return _saturate_t1(a0, j, t1, a_max)


def _direction(a0: float, v0: float, v_sp: float, j_max: float) -> int:
    # the velocity reached if the acceleration is brought to zero at once
    v_zero_acc = v0
    if abs(a0) > 1e-12:
        jz = -_sign(a0) * j_max
        tz = -a0 / jz
        v_zero_acc = v0 + a0 * tz + 0.5 * jz * tz * tz
    d = _sign(v_sp - v_zero_acc)
    return d if d else _sign(a0)


def plan(a0: float, v0: float, x0: float, v_sp: float, j_max: float, a_max: float, v_max: float) -> Profile:
    """The time-optimal profile from (a0, v0, x0) to ``v_sp`` (limited to +-``v_max``)."""
    v_sp = max(-v_max, min(v_max, v_sp))
    d = _direction(a0, v0, v_sp, j_max)
    p = Profile(a0, v0, x0, j_max, d)
    if d == 0 or j_max <= 0.0:
        return p
    j = d * j_max
    dv = v_sp - v0
    p.t1 = _t1(a0, dv, j, a_max)
    p.t3 = max(a0 / j + p.t1, 0.0)
    den = a0 + j * p.t1
    if abs(den) > 1e-12:
        t1, t3 = p.t1, p.t3
        p.t2 = max((-0.5 * t1 * t1 * j - t1 * t3 * j - t1 * a0 + 0.5 * t3 * t3 * j - t3 * a0 + dv) / den, 0.0)
    return p


def plan_given_time(p: Profile, v_sp: float, total: float, a_max: float, v_max: float) -> None:
    """Re-plan ``p`` (its state and direction kept) to reach ``v_sp`` in ``total`` seconds."""
    v_sp = max(-v_max, min(v_max, v_sp))
    if p.direction == 0 or p.jerk <= 0.0:
        p.t1 = p.t2 = p.t3 = 0.0
        return
    j = p.direction * p.jerk
    p.t1 = _t1_given_time(total, p.a0, v_sp - p.v0, j, a_max)
    p.t3 = max(p.a0 / j + p.t1, 0.0)
    p.t2 = max(total - p.t1 - p.t3, 0.0)


def synchronize(px: Profile, py: Profile, vx_sp: float, vy_sp: float, a_max: float, v_max: float) -> None:
    """``VelocitySmoothing::timeSynchronization`` of x and y: the shorter takes the longer's time."""
    synchronize_axes(((px, vx_sp, a_max, v_max), (py, vy_sp, a_max, v_max)))


def synchronize_axes(axes: Sequence[tuple[Profile, float, float, float]]) -> None:
    """``VelocitySmoothing::timeSynchronization`` of any number of axes, each given as (profile,
    velocity setpoint, its a_max, its v_max): every axis but the longest takes the longest's time
    (PositionSmoothing synchronizes x, y and z: the vehicle moves along a straight line)."""
    longest = max(range(len(axes)), key=lambda i: axes[i][0].total)
    total = axes[longest][0].total
    if total <= 1e-6:
        return
    for i, (p, v_sp, a_max, v_max) in enumerate(axes):
        if i != longest:
            plan_given_time(p, v_sp, total, a_max, v_max)


def advance(p: Profile, t: float) -> tuple[float, float, float]:
    """(acceleration, velocity, position) ``t`` seconds along the profile."""
    a, v, x = p.a0, p.v0, p.x0
    j = p.direction * p.jerk
    s = p.t1 if t > p.t1 else t
    if s > 0.0:  # jerk towards the acceleration
        x += v * s + 0.5 * a * s * s + j * s * s * s / 6.0
        v += a * s + 0.5 * j * s * s
        a += j * s
        t -= s
    if t > 0.0:  # the acceleration held
        s = p.t2 if t > p.t2 else t
        x += v * s + 0.5 * a * s * s
        v += a * s
        t -= s
    if t > 0.0:  # jerk back to zero acceleration
        s = p.t3 if t > p.t3 else t
        x += v * s + 0.5 * a * s * s - j * s * s * s / 6.0
        v += a * s - 0.5 * j * s * s
        a -= j * s
        t -= s
    if t > 0.0:  # constant velocity after the profile
        x += v * t
        a = 0.0
    return a, v, x
