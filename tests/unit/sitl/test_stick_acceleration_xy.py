"""Position mode as PX4 v1.15 flies it by default (MPC_POS_MODE 4, StickAccelerationXY) and the
sticks as its manual tasks read them (Sticks: MPC_HOLD_DZ deadzone, MPC_*_EXPO curves)."""

from __future__ import annotations

import itertools
import math

import pytest

from uavtest.sitl.stick_acceleration_xy import StickAccelerationXY
from uavtest.sitl.sticks import deadzone, expo, expo_deadzone, limit_unit_length

LIMITS = {"vel_manual": 10.0, "acc_hor": 3.0, "jerk_max": 8.0, "tilt_max": math.radians(45.0)}
DT = 0.02


def test_the_deadzone_is_continuous_and_the_expo_keeps_full_stick():
    assert deadzone(0.1, 0.1) == 0.0 and deadzone(-0.05, 0.1) == 0.0
    assert deadzone(0.55, 0.1) == pytest.approx(0.5) and deadzone(-1.0, 0.1) == -1.0
    assert expo(1.0, 0.6) == 1.0 and expo(-1.0, 0.6) == -1.0 and expo(0.5, 0.0) == 0.5
    assert expo_deadzone(0.5, 0.6, 0.1) == pytest.approx(0.2305, abs=1e-4)  # half stick: 23 %
    assert limit_unit_length(1.0, 1.0) == pytest.approx((math.sqrt(0.5), math.sqrt(0.5)))


def _fly(sa: StickAccelerationXY, stick: tuple[float, float], seconds: float, x: float = 0.0) -> list[float]:
    speeds = []
    for _ in range(round(seconds / DT)):
        sa.update(stick[0], stick[1], 0.0, x, 0.0, (sa.vx, sa.vy), DT, **LIMITS)
        speeds.append(sa.vx)
    return speeds


def test_a_stick_settles_at_its_share_of_mpc_vel_manual_jerk_limited():
    sa = StickAccelerationXY(0.0, 0.0)
    v = _fly(sa, (1.0, 0.0), 15.0)
    assert v[-1] == pytest.approx(10.0, abs=0.05)  # full stick: MPC_VEL_MANUAL
    h = StickAccelerationXY(0.0, 0.0)
    w = _fly(h, (expo_deadzone(0.5, 0.6, 0.1), 0.0), 15.0)
    assert w[-1] == pytest.approx(2.305, abs=0.01)  # half stick after expo
    acc = [b - a for a, b in itertools.pairwise(v)]
    jerk = [(b - a) / DT / DT for a, b in itertools.pairwise(acc)]
    assert max(abs(j) for j in jerk) <= 8.0 + 1e-6  # MPC_JERK_MAX
    assert max(a / DT for a in acc) <= 6.0 + 1e-6  # twice MPC_ACC_HOR at most


def test_centred_it_brakes_to_a_stop_and_locks_the_position_moved_it_lets_go():
    sa = StickAccelerationXY(5.0, 0.0)
    assert not sa.locked
    v = _fly(sa, (0.0, 0.0), 6.0, x=12.0)
    assert v[-1] == 0.0 and sa.locked and sa.px == 12.0
    stop = next(i for i, s in enumerate(v) if s == 0.0) * DT
    assert 1.0 < stop < 4.0  # braked from 5 m/s with the brake boost
    assert all(b <= a + 1e-9 for a, b in itertools.pairwise(v))  # no overshoot backwards
    sa.update(0.5, 0.0, 0.0, 12.0, 0.0, (0.3, 0.0), DT, **LIMITS)
    assert not sa.locked and sa.vx > 0.3 - 1e-9  # moving: released, from the controller's setpoint


def test_the_stick_is_turned_by_the_heading():
    sa = StickAccelerationXY(0.0, 0.0)
    for _ in range(200):
        sa.update(1.0, 0.0, math.pi / 2, 0.0, 0.0, (sa.vx, sa.vy), DT, **LIMITS)
    assert abs(sa.vx) < 1e-6 and sa.vy > 5.0  # facing East: forward is East


def test_altitude_mode_takes_the_raw_stick_as_an_acceleration():
    """StickTiltXY: no deadzone, no expo; full stick is tan(MPC_MAN_TILT_MAX) g, half stick half of
    it (19.3 degrees of tilt at 35, where a tilt in proportion to the stick would be 17.5)."""
    from uavtest.sitl.mc_pos_control import Controller, Goal, GoalKind, Limits
    from uavtest.sitl.params import ParamStore

    ctrl = Controller(Limits.of(ParamStore()))
    ctrl.reset(0.0, 0.0, -10.0, 0.0, 0.0, 0.0, 0.0)
    full = math.tan(math.radians(35.0)) * 9.80665
    half, tiny = (Goal(GoalKind.ALTITUDE, sticks=(s, 0.0, 0.5, 0.0)) for s in (0.5, 0.05))
    ax, ay, _, _ = ctrl.update(DT, half, 0, 0, -10, 0, 0, 0, 0.0)
    assert ax == pytest.approx(0.5 * full, rel=1e-6) and ay == pytest.approx(0.0, abs=1e-9)
    ax, _, _, _ = ctrl.update(DT, tiny, 0, 0, -10, 0, 0, 0, 0.0)
    assert ax == pytest.approx(0.05 * full, rel=1e-6)  # inside MPC_HOLD_DZ, still tilts
