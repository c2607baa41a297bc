"""PositionSmoothing in three axes, as PX4 v1.15 flies the auto modes (``PositionSmoothing.cpp``,
``FlightTaskAuto::_updateTrajConstraints``): the velocity setpoint points straight at the 3-D
target and is scaled to the horizontal and vertical limits together, z has its own jerk-limited
profile (MPC_ACC_UP/DOWN_MAX, MPC_Z_V_AUTO_UP/DN, MPC_JERK_AUTO) synchronized with x and y, and a
takeoff climbs at MPC_TKO_SPEED only below MPC_LAND_ALT1. The trajectory is flown here with
perfect tracking (the vehicle sits on its reference), so only the trajectory is measured."""

from __future__ import annotations

import math

import pytest

from uavtest.sitl import velocity_smoothing
from uavtest.sitl.mc_pos_control import Controller, Goal, GoalKind, Limits, clamp_to_xy_norm, clamp_to_z_norm
from uavtest.sitl.params import ParamStore

DT = 0.02


def _fly(start: tuple[float, float, float], goal: Goal, seconds: float) -> list[tuple[float, ...]]:
    """(t, x, y, z, vx, vy, vz) of a vehicle that flies the reference's velocity exactly."""
    c = Controller(Limits.of(ParamStore()))
    c.reset(*start, 0.0, 0.0, 0.0, 0.0)
    x, y, z = start
    vx = vy = vz = 0.0
    out = []
    for k in range(int(seconds / DT)):
        c.dist_bottom = -z  # flat ground at z = 0 (SIH's range finder)
        c.update(DT, goal, x, y, z, vx, vy, vz, 0.0)
        vx, vy, vz = c.vx, c.vy, c.vz
        x, y, z = x + vx * DT, y + vy * DT, min(z + vz * DT, 0.0)  # the ground holds it up
        out.append(((k + 1) * DT, x, y, z, vx, vy, vz))
    return out


def _leg(target: tuple[float, float, float], prev: tuple[float, float, float]) -> Goal:
    g = Goal(GoalKind.POSITION, *target)
    g.prev = prev
    return g


def _within(track: list[tuple[float, ...]], z: float, tol: float) -> float:
    return next(s[0] for s in track if abs(s[3] - z) < tol)


def test_a_climbing_leg_is_flown_along_its_straight_line() -> None:
    # 100 m north, 20 m up: PX4 climbs at 1 m/s beside 5 m/s and arrives in position and altitude
    # together; separate axes climbed at 3 m/s and were at altitude 34 m into the leg
    track = _fly((0.0, 0.0, -10.0), _leg((100.0, 0.0, -30.0), (0.0, 0.0, -10.0)), 30.0)
    for _, x, _, z, *_ in track:
        assert z == pytest.approx(-10.0 - 0.2 * x, abs=0.3)
    assert track[-1][1] == pytest.approx(100.0, abs=0.05) and track[-1][3] == pytest.approx(-30.0, abs=0.05)


def test_an_altitude_change_follows_px4s_jerk_limited_profile() -> None:
    # _getMaxZSpeed: computeMaxSpeedFromDistance(MPC_JERK_AUTO 4, MPC_ACC_UP_MAX 4, |dz|, 0), the
    # z profile jerk-limited: PX4's PositionSmoothing is within NAV_MC_ALT_RAD (0.8 m) of a 2 m
    # climb after 2.24 s and of a 20 m climb after 9.70 s (1.18 and 7.64 s with the old approach)
    two = _fly((0.0, 0.0, -10.0), _leg((0.0, 0.0, -12.0), (0.0, 0.0, -10.0)), 8.0)
    assert 2.1 <= _within(two, -12.0, 0.8) <= 2.4
    twenty = _fly((0.0, 0.0, -10.0), _leg((0.0, 0.0, -30.0), (0.0, 0.0, -10.0)), 20.0)
    assert 9.5 <= _within(twenty, -30.0, 0.8) <= 9.9
    assert min(s[6] for s in twenty) == pytest.approx(-3.0, abs=0.01)  # MPC_Z_V_AUTO_UP
    down = _fly((0.0, 0.0, -30.0), _leg((0.0, 0.0, -10.0), (0.0, 0.0, -30.0)), 25.0)
    assert max(s[6] for s in down) == pytest.approx(1.5, abs=0.01)  # MPC_Z_V_AUTO_DN


def test_a_small_altitude_error_does_not_slow_a_level_leg() -> None:
    # clampToZNorm / clampToXYNorm with PositionSmoothing's accuracy 0.5: under 0.5 m/s only the
    # one axis is scaled, so 10 cm below the leg's altitude the vehicle still cruises at 5 m/s
    track = _fly((0.0, 0.0, -9.9), _leg((100.0, 0.0, -10.0), (0.0, 0.0, -9.9)), 8.0)
    assert max(math.hypot(s[4], s[5]) for s in track) == pytest.approx(5.0, abs=0.01)


def test_a_takeoff_climbs_at_mpc_tko_speed_below_mpc_land_alt1_and_like_a_waypoint_above() -> None:
    track = _fly((0.0, 0.0, 0.0), Goal(GoalKind.TAKEOFF, 0.0, 0.0, -30.0), 30.0)
    low = [s[6] for s in track if -9.0 < s[3] < -1.0]
    high = [s[6] for s in track if -25.0 < s[3] < -12.0]
    assert min(low) == pytest.approx(-1.5, abs=0.01)  # MPC_TKO_SPEED
    assert min(high) == pytest.approx(-3.0, abs=0.01)  # MPC_Z_V_AUTO_UP
    # PX4's PositionSmoothing with its takeoff constraints: within NAV_MC_ALT_RAD after 18.8 s
    assert 18.4 <= _within(track, -30.0, 0.8) <= 19.2
    ten = _fly((0.0, 0.0, 0.0), Goal(GoalKind.TAKEOFF, 0.0, 0.0, -10.0), 15.0)
    assert 9.2 <= _within(ten, -10.0, 0.8) <= 9.7  # PX4: 9.46 s, all of it below MPC_LAND_ALT1


def test_the_three_axes_profiles_end_together() -> None:
    fx = velocity_smoothing.plan(0.0, 0.0, 0.0, 5.0, 4.0, 3.0, 12.0)
    fy = velocity_smoothing.plan(0.0, 0.0, 0.0, 1.0, 4.0, 3.0, 12.0)
    fz = velocity_smoothing.plan(0.0, 0.0, 0.0, -1.0, 4.0, 4.0, 3.0)
    velocity_smoothing.synchronize_axes(((fx, 5.0, 3.0, 12.0), (fy, 1.0, 3.0, 12.0), (fz, -1.0, 4.0, 3.0)))
    assert fy.total == pytest.approx(fx.total) and fz.total == pytest.approx(fx.total)
    for p, v in ((fx, 5.0), (fy, 1.0), (fz, -1.0)):
        assert velocity_smoothing.advance(p, p.total)[1] == pytest.approx(v, abs=1e-6)


def test_the_clamps_scale_the_whole_vector_unless_both_are_under_the_accuracy() -> None:
    # TrajectoryConstraints.hpp: a horizontal part of 5 against a limit of 2.5 halves all three
    assert clamp_to_xy_norm([3.0, 4.0, 1.0], 2.5, 0.5) == pytest.approx([1.5, 2.0, 0.5])
    assert clamp_to_z_norm([3.0, 4.0, -2.0], 1.0, 0.5) == pytest.approx([1.5, 2.0, -1.0])
    # within the limit: unchanged
    assert clamp_to_xy_norm([3.0, 4.0, 1.0], 5.0, 0.5) == [3.0, 4.0, 1.0]
    # both under the accuracy: only that axis (a nearly reached altitude leaves x and y alone)
    assert clamp_to_z_norm([3.0, 4.0, -0.4], 0.1, 0.5) == pytest.approx([3.0, 4.0, -0.1])
    assert clamp_to_xy_norm([0.3, 0.0, 2.0], 0.1, 0.5) == pytest.approx([0.1, 0.0, 2.0])
