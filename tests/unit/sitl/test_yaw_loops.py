"""PX4 v1.15's yaw chain in the built-in vehicle: mc_att_control's yaw law, mc_rate_control's yaw
PI and SIH's yaw torque (``simulator_sih.Body``). Compared with PX4 SIH flights in
``test_sih_body_fixed.py`` (mission turns) and ``test_offboard.py`` (a yaw rate alone)."""

import itertools
import math

import numpy as np
import pytest

from uavtest.px4.modes import MainMode, NavState
from uavtest.sitl.mav import MavCmd, Msg
from uavtest.sitl.mc_att_control import YawGains, yaw_rate_setpoint
from uavtest.sitl.mc_rate_control import YawRateGains
from uavtest.sitl.params import ParamStore
from uavtest.sitl.simulator_sih import HOVER_THRUST, YAW_DAMPING, YAW_TORQUE_GAIN, Body

from .test_vehicle import GCS, command, ready_vehicle

GAINS = YawGains.of(ParamStore())


def test_a_small_yaw_error_asks_mc_yaw_p_times_it_plus_the_feedforward():
    assert yaw_rate_setpoint(0.05, 0.0, math.nan, GAINS) == pytest.approx(2.8 * 0.05, rel=1e-3)
    assert yaw_rate_setpoint(0.05, 0.0, 0.3, GAINS) == pytest.approx(2.8 * 0.05 + 0.3, rel=1e-3)


def test_a_large_yaw_error_is_limited_to_mc_yawrate_max_and_turns_the_short_way():
    assert yaw_rate_setpoint(math.radians(150), 0.0, math.nan, GAINS) == pytest.approx(math.radians(200))
    # 170 degrees to -170 degrees is 20 degrees clockwise, not 340 anticlockwise
    rate = yaw_rate_setpoint(math.radians(-170), math.radians(170), math.nan, GAINS)
    assert rate > 0.0
    assert rate == pytest.approx(2.8 / 0.4 * 2 * math.sin(0.4 * math.radians(20) / 2), rel=1e-3)


def test_mc_yaw_weight_compensates_its_own_scaling():
    """``setProportionalGain`` divides MC_YAW_P by the weight: small errors get MC_YAW_P whatever
    the weight; large ones less than linear."""
    for w in (0.2, 0.4, 1.0):
        g = YawGains.of(ParamStore({"MC_YAW_WEIGHT": w}))
        assert yaw_rate_setpoint(0.01, 0.0, math.nan, g) == pytest.approx(0.028, rel=1e-3)
    heavy = YawGains.of(ParamStore({"MC_YAW_WEIGHT": 1.0, "MC_YAWRATE_MAX": 1000}))
    assert yaw_rate_setpoint(2.0, 0.0, math.nan, heavy) < 2.8 * 2.0


def _hovering_body(gains: YawRateGains | None) -> Body:
    body = Body(yaw_rate_gains=gains)
    body.motors = True
    body.on_ground = False
    body.z = -5.0
    body.az = 0.0  # net of gravity: the thrust holds the weight (commanded 0 below)
    return body


def test_a_rate_step_saturates_the_yaw_torque_at_the_collectives_headroom():
    """PX4's sequential desaturation gives in on yaw first: hovering at SIH's 0.49 collective, the
    rotors' differential is at most 0.49, so a 200 degrees/s step accelerates at no more than
    4 x SIH_Q_MAX x 0.49 / SIH_IZZ (6.5 rad/s^2); the motors' 0.05 s lag softens the start."""
    body = _hovering_body(YawRateGains.of(ParamStore()))
    dt = 0.004
    rates = []
    for _ in range(100):  # 0.4 s
        body.step(dt, 0.0, 0.0, 0.0, math.radians(200), 0.0, 0.0, 0.0)
        rates.append(body.yawrate)
    accel = [(b - a) / dt for a, b in itertools.pairwise(rates)]
    limit = YAW_TORQUE_GAIN * HOVER_THRUST
    assert max(accel) <= limit * 1.001
    assert max(accel) > 0.8 * limit  # it does saturate
    assert accel[0] < 0.2 * limit  # SIH_T_TAU: not at once


def test_the_rate_loop_holds_a_rate_against_sihs_damping_with_its_integral():
    """P alone would settle at 0.2 x 13.3 / (0.2 x 13.3 + KDW / IZZ) of the rate asked (0.76);
    the integral (MC_YAWRATE_I) takes it to the rate."""
    body = _hovering_body(YawRateGains.of(ParamStore()))
    for _ in range(int(1.0 / 0.004)):
        body.step(0.004, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0)
    p_only = 0.2 * YAW_TORQUE_GAIN / (0.2 * YAW_TORQUE_GAIN + YAW_DAMPING)
    assert 0.5 * p_only * 0.95 < body.yawrate < 0.5 * 0.97
    for _ in range(int(20.0 / 0.004)):
        body.step(0.004, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0)
    assert body.yawrate == pytest.approx(0.5, abs=0.01)


def test_a_disarmed_body_has_no_yaw_rate_loop():
    """Motors off (disarmed, falling): no rate controller runs and no yaw torque acts, whatever rate
    is asked; a spin left over only decays with SIH's damping."""
    body = _hovering_body(YawRateGains.of(ParamStore()))
    for _ in range(100):
        body.step(0.004, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    spinning = body.yawrate
    assert spinning > 0.3
    body.z = -100.0  # high enough to fall for the whole second
    body.motors = False
    body.step(0.004, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    assert body.yaw_int == 0.0 and body.yaw_torque == 0.0
    for _ in range(250):  # 1 s
        body.step(0.004, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    assert body.yawrate == pytest.approx(spinning * math.exp(-YAW_DAMPING * 1.004), rel=0.02)


def test_the_local_planners_system_keeps_its_first_order_yaw():
    body = _hovering_body(None)
    for _ in range(int(0.08 / 0.004)):
        body.step(0.004, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    assert body.yawrate == pytest.approx(1.0 - math.exp(-1.0), abs=0.03)


def _posctl_vehicle():
    """A vehicle taken off to 5 m and in position mode, and a function holding the sticks."""
    v = ready_vehicle()
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 5)
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_LOITER, 30_000_000)
    v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS))  # needed
    command(v, MavCmd.DO_SET_MODE, 1, MainMode.POSCTL, 0)

    def sticks(r: int, seconds: float) -> list[float]:
        headings = []
        for _ in range(round(seconds * 10)):
            v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": r}, *GCS))
            v.advance(v.time_us + 100_000)
            headings.append(v.st.yaw)
        return headings

    return v, sticks


def test_a_yaw_stick_turns_and_the_released_heading_is_locked_and_held():
    """Position mode (PX4's StickYaw): the stick's rate, low-passed at MPC_MAN_Y_TAU, is fed
    forward with no yaw setpoint; once it has decayed, the heading is locked where it is and
    MC_YAW_P holds it (the rate loop's overshoot is pulled back)."""
    v, sticks = _posctl_vehicle()
    # 60 % yaw stick: 0.325 after MPC_HOLD_DZ and MPC_YAW_EXPO, of MPC_MAN_Y_MAX 150 deg/s = 49 deg/s
    turned = np.unwrap(sticks(600, 2.0))
    assert math.degrees(turned[-1] - turned[0]) > 45.0
    sticks(0, 3.0)  # released: the filtered rate decays, then the heading locks
    held = np.unwrap(sticks(0, 5.0))
    assert v.ctrl.yaw_lock == v.ctrl.yaw_lock  # locked
    # held on average where it locked; EKF2's heading error wanders the estimate by a degree or two
    off = np.degrees(np.remainder(held - v.ctrl.yaw_lock + math.pi, math.tau) - math.pi)
    assert abs(off.mean()) < 1.0, off
    assert np.abs(off).max() < 4.0, off


def test_entering_position_mode_mid_turn_starts_the_yaw_stick_at_rest():
    """PX4's FlightModeManager constructs a fresh flight task at a mode switch: switched to position
    mode in the middle of an auto turn, with the yaw stick centred, the turn's feed-forward is not
    carried on (StickYaw's filter starts at 0) and the heading is locked where it is."""
    from uavtest.sitl.mc_pos_control import Controller, Goal, GoalKind, Limits

    ctrl = Controller(Limits.of(ParamStore()))
    ctrl.reset(0.0, 0.0, -5.0, 0.0, 0.0, 0.0, 0.0)
    turn = Goal(GoalKind.POSITION, x=0.0, y=0.0, z=-5.0, yaw=math.pi)
    yaw = 0.0
    for _ in range(50):  # 1 s into a 180 degree turn, the vehicle following the setpoint
        ctrl.update(0.02, turn, 0.0, 0.0, -5.0, 0.0, 0.0, 0.0, yaw)
        yaw = ctrl.yaw_sp
    assert ctrl.yawrate_sp > math.radians(30.0)  # the auto turn's feed-forward
    sticks = Goal(GoalKind.VELOCITY, sticks=(0.0, 0.0, 0.5, 0.0))
    rate = ctrl.update(0.02, sticks, 0.0, 0.0, -5.0, 0.0, 0.0, 0.0, yaw)[3]
    assert ctrl.yawrate_sp == 0.0
    assert ctrl.yaw_lock == pytest.approx(yaw)
    assert abs(rate) < 1e-9  # on the locked heading: no rate asked
