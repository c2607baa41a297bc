"""PositionSmoothing's per-axis jerk-limited velocity trajectory (PX4 v1.15 VelocitySmoothing)."""

from __future__ import annotations

import math

import pytest

from uavtest.sitl import velocity_smoothing as vs


def test_from_rest_to_cruise_at_the_jerk_and_acceleration_limits() -> None:
    # MPC_JERK_AUTO 4, MPC_ACC_HOR 3: jerk up for 0.75 s to 3 m/s^2, hold, jerk down 0.75 s
    p = vs.plan(0.0, 0.0, 0.0, 5.0, 4.0, 3.0, 12.0)
    assert (p.t1, p.t3) == pytest.approx((0.75, 0.75))
    assert p.total == pytest.approx(0.75 + 5.0 / 3.0)
    a, v, x = vs.advance(p, p.total)
    assert (a, v) == pytest.approx((0.0, 5.0), abs=1e-9)
    assert x == pytest.approx(5.0 * p.total / 2.0)  # symmetric profile: the mean speed is half
    # afterwards it cruises
    assert vs.advance(p, p.total + 1.0) == pytest.approx((0.0, 5.0, x + 5.0))


def test_a_small_change_never_reaches_the_acceleration_limit() -> None:
    p = vs.plan(0.0, 0.0, 0.0, 0.5, 4.0, 3.0, 12.0)
    assert p.t2 == 0.0
    assert p.t1 == pytest.approx(math.sqrt(0.5 / 4.0))
    assert vs.advance(p, p.total)[1] == pytest.approx(0.5)


def test_braking_while_accelerating_first_removes_the_acceleration() -> None:
    # accelerating at 2 m/s^2 at 3 m/s with a new setpoint of 3 m/s: cancelling the acceleration
    # at the jerk limit overshoots to 3.5 m/s, so the profile brakes (direction -1)
    p = vs.plan(2.0, 3.0, 0.0, 3.0, 4.0, 3.0, 12.0)
    assert p.direction == -1
    a, v, _ = vs.advance(p, p.total)
    assert (a, v) == pytest.approx((0.0, 3.0), abs=1e-6)


def test_the_velocity_limit_caps_the_setpoint() -> None:
    p = vs.plan(0.0, 0.0, 0.0, 20.0, 4.0, 3.0, 12.0)
    assert vs.advance(p, p.total)[1] == pytest.approx(12.0)


def test_x_and_y_are_synchronized_to_reach_their_setpoints_together() -> None:
    # VelocitySmoothing::timeSynchronization: the shorter profile is stretched to the longer's
    # duration, so a diagonal change does not finish one axis first
    px = vs.plan(0.0, 0.0, 0.0, 4.0, 4.0, 3.0, 12.0)
    py = vs.plan(0.0, 0.0, 0.0, 1.0, 4.0, 3.0, 12.0)
    assert px.total > py.total
    unsynchronized_end = py.total
    vs.synchronize(px, py, 4.0, 1.0, 3.0, 12.0)
    assert py.total == pytest.approx(px.total)
    assert vs.advance(py, unsynchronized_end)[1] < 0.95
    assert vs.advance(py, py.total)[:2] == pytest.approx((0.0, 1.0), abs=1e-6)
    assert vs.advance(px, px.total)[:2] == pytest.approx((0.0, 4.0), abs=1e-6)
