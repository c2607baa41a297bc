"""The pilot takes over with the sticks, as PX4 v1.15 lets them (COM_RC_OVERRIDE, COM_RC_STICK_OV).

ManualControl.cpp sets ``sticks_moving`` when a stick changes faster than COM_RC_STICK_OV percent
of its travel per second (a 0.1 s low-passed rate, ``MovingDiff``); Commander.cpp
``manualControlCheck`` then switches an auto mode (bit 0) or offboard (bit 1) to Position mode
and says "Pilot took over using sticks". In a failsafe the framework decides
(framework.cpp ``getSelectedAction``): not during the COM_FAIL_ACT_T Hold, not with
COM_FAIL_ACT_T <= 0.1 s, never out of a geofence Hold; after the Hold, yes.
"""

from __future__ import annotations

import math

from uavtest.px4.modes import NavState
from uavtest.sitl.manual_control import MovingDiff, StickMovement
from uavtest.sitl.mav import MavCmd, MavResult, Msg
from uavtest.sitl.mission import from_spec
from uavtest.spec.models import Home, MissionItem, MissionItemKind

from .test_battery_failures import GCS
from .test_failsafe_delay import Watched

TOOK_OVER = "Pilot took over using sticks"
HOME = Home()

# ------------------------------------------------------------------ ManualControl: sticks_moving


def test_moving_diff_is_the_low_passed_rate_of_change():
    d = MovingDiff()
    assert d.update(0.0, 0.05) == 0.0  # no previous sample yet
    # a step of 0.5 in 50 ms: 10 /s, through alpha = 0.05 / (0.1 + 0.05)
    assert math.isclose(d.update(0.5, 0.05), 10.0 / 3.0)
    assert math.isnan(d.update(0.5, 0.0))  # no time passed: PX4 returns NAN


def test_a_stick_step_moves_a_held_or_slowly_drifting_stick_does_not():
    s = StickMovement()
    t = 0
    assert not s.update(t, (0.0, 0.0, 0.0, 0.0), 30.0)
    for _ in range(20):  # held: 20 Hz samples of the same sticks
        t += 50_000
        assert not s.update(t, (0.0, 0.0, 0.0, 0.0), 30.0)
    t += 50_000
    assert s.update(t, (0.0, 0.4, 0.0, 0.0), 30.0)  # pitch forward at once
    drift = StickMovement()
    moved = []
    for k in range(100):  # throttle creeping at 0.2 of its travel per second: under 30 % / s
        moved.append(drift.update(k * 50_000, (0.0, 0.0, 0.0, -1.0 + 0.01 * k), 30.0))
    assert not any(moved)
    fast = StickMovement()
    assert any(fast.update(k * 50_000, (0.0, 0.0, 0.025 * k, 0.0), 30.0) for k in range(40))  # 0.5 / s


def test_a_stick_change_after_a_pause_still_counts_but_a_held_stick_decays():
    s = StickMovement()
    s.update(0, (0.0, 0.0, 0.0, 0.0), 30.0)
    assert s.update(1_000_000, (0.5, 0.0, 0.0, 0.0), 30.0)  # 1 s later, moved: the 200 ms runs between
    assert not s.update(2_000_000, (0.5, 0.0, 0.0, 0.0), 30.0)  # then held
    # a gap beyond COM_RC_LOSS_T: the input went invalid and its rates were reset
    assert not s.update(3_000_000, (-0.5, 0.0, 0.0, 0.0), 30.0, loss_timeout_s=0.5)
    assert s.update(3_050_000, (0.0, 0.0, 0.0, 0.0), 30.0, loss_timeout_s=0.5)


# ------------------------------------------------------------------ Commander: who takes over


def _mission_flight(**params: float) -> Watched:
    f = Watched(**params)
    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=10),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0006, lon=HOME.lon, alt=10),
        MissionItem(kind=MissionItemKind.LAND, lat=HOME.lat + 0.0006, lon=HOME.lon, alt=0),
    ]
    f.v.load_mission(from_spec(items))
    f.fly(5, until=lambda v: v.ready)
    f.fly(0.2, each=f.sticks)  # centred sticks: the manual control link is there
    assert f.command(MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED
    assert f.command(MavCmd.DO_SET_MODE, 1, 4, 4) == MavResult.ACCEPTED  # Mission
    f.fly(30, until=lambda v: v.nav.current == 1 and v.body.vx > 2.0, each=f.sticks)
    assert f.v.nav_state == NavState.AUTO_MISSION
    return f


def test_moving_the_sticks_in_a_mission_takes_over_in_position_mode():
    f = _mission_flight()
    t0 = f.v.time_us / 1e6
    f.fly(0.1, each=lambda: f.sticks(x=-500))  # pull back
    assert f.v.nav_state == NavState.POSCTL and f.v.user_nav_state == NavState.POSCTL
    assert [s for _, s in f.since(t0)] == [TOOK_OVER]
    f.fly(4, each=lambda: f.sticks(x=-500))  # the pilot flies: backwards (South), not on to the waypoint
    assert f.v.st.vx < -1.0 and f.v.nav_state == NavState.POSCTL
    assert not f.v.nav.finished


def test_held_sticks_and_com_rc_override_0_leave_the_mission_alone():
    f = _mission_flight()
    f.fly(20, until=lambda v: v.nav.current == 2, each=f.sticks)  # centred, sent every tick
    assert f.v.nav_state == NavState.AUTO_MISSION and not f.said(TOOK_OVER)
    g = _mission_flight(COM_RC_OVERRIDE=0)
    g.fly(1, each=lambda: g.sticks(x=-500))
    assert g.v.nav_state == NavState.AUTO_MISSION and not g.said(TOOK_OVER)
    h = _mission_flight(COM_RC_STICK_OV=80)  # a 0.3 step in 20 ms is still 5 / s: moving
    h.fly(0.1, each=lambda: h.sticks(y=300))
    assert h.v.nav_state == NavState.POSCTL


def test_offboard_is_taken_over_only_with_bit_1():
    from .test_offboard import airborne_offboard

    for bits, expect in ((1, NavState.OFFBOARD), (3, NavState.POSCTL)):
        s = airborne_offboard(COM_RC_OVERRIDE=bits)
        stick = Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS)
        s.v.receive(stick)
        s.stream(0.5, x=0.0, y=0.0, z=-5.0)
        s.v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 600, "z": 500, "r": 0}, *GCS))
        s.stream(0.5, x=0.0, y=0.0, z=-5.0)
        assert s.v.nav_state == expect, bits
        assert (TOOK_OVER in s.texts) == (expect == NavState.POSCTL)


def _gcs_lost_in_mission(**params: float) -> tuple[Watched, float]:
    """A mission with the GCS heartbeat and centred sticks, then the heartbeat stops."""
    f = Watched(NAV_DLL_ACT=2, COM_DL_LOSS_T=2, **params)
    gcs = Msg("HEARTBEAT", {"type": 6, "autopilot": 8}, *GCS)

    def alive() -> None:
        f.v.receive(gcs)
        f.sticks()

    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=10),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.001, lon=HOME.lon, alt=10),
    ]
    f.v.load_mission(from_spec(items))
    f.fly(5, until=lambda v: v.ready, each=alive)
    f.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    f.command(MavCmd.DO_SET_MODE, 1, 4, 4)
    f.fly(30, until=lambda v: v.nav.current == 1, each=alive)
    f.fly(10, until=lambda v: v.gcs_lost, each=f.sticks)
    return f, f.v.time_us / 1e6


def test_in_a_failsafe_the_sticks_take_over_only_after_the_hold():
    f, _t0 = _gcs_lost_in_mission()
    f.fly(2, each=f.sticks)
    assert f.v.nav_state == NavState.AUTO_LOITER  # the COM_FAIL_ACT_T Hold
    f.fly(0.1, each=lambda: f.sticks(x=500))  # moved during the Hold: mode switch only
    assert f.v.nav_state == NavState.AUTO_LOITER and not f.said(TOOK_OVER)
    f.fly(4, each=lambda: f.sticks(x=500))  # held there
    assert f.v.nav_state == NavState.AUTO_RTL and f.v.failsafe
    f.fly(0.1, each=f.sticks)  # centred again: moved, in the Return
    assert f.v.nav_state == NavState.POSCTL and f.v.user_nav_state == NavState.POSCTL
    assert not f.v.failsafe and f.said(TOOK_OVER)
    f.fly(5, each=f.sticks)
    assert f.v.nav_state == NavState.POSCTL  # the link is still lost: only a warning now


def test_sticks_back_after_a_manual_control_loss_are_not_a_takeover():
    f = _mission_flight(NAV_RCL_ACT=3)  # Land
    f.fly(10, until=lambda v: v.commander.rc_lost)  # no sticks: lost after COM_RC_LOSS_T
    f.fly(6)
    assert f.v.nav_state == NavState.AUTO_LAND and f.v.user_nav_state == NavState.AUTO_MISSION
    f.fly(0.2, each=lambda: f.sticks(x=500))  # back, pushed forward: Land goes, the mission goes on
    assert f.v.nav_state == NavState.AUTO_MISSION and not f.said(TOOK_OVER)
    assert f.said("Manual control regained")


def test_without_the_failsafe_delay_the_sticks_never_take_over():
    f, _t0 = _gcs_lost_in_mission(COM_FAIL_ACT_T=0)
    assert f.v.nav_state == NavState.AUTO_RTL
    f.fly(0.1, each=lambda: f.sticks(x=500))
    f.fly(2, each=lambda: f.sticks(x=500))
    assert f.v.nav_state == NavState.AUTO_RTL and not f.said(TOOK_OVER)


def test_a_geofence_hold_is_not_taken_over_by_sticks_a_return_after_its_hold_is():
    from .test_geofence import ready, take_off_then_sticks

    v = ready(GF_MAX_HOR_DIST=30, GF_ACTION=2)  # Hold
    take_off_then_sticks(v, lambda v: v.nav_state != NavState.POSCTL)
    assert v.nav_state == NavState.AUTO_LOITER
    for x in (0, 600, 0, -600, 0):
        v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": x, "y": 0, "z": 500, "r": 0}, *GCS))
        v.advance(v.time_us + 100_000)
    assert v.nav_state == NavState.AUTO_LOITER
    w = ready(GF_MAX_HOR_DIST=30, GF_ACTION=3)  # Return, after the COM_FAIL_ACT_T Hold
    take_off_then_sticks(w, lambda v: v.nav_state != NavState.POSCTL)
    for _ in range(100):  # the stick still held forward through the Hold
        if w.nav_state == NavState.AUTO_RTL:
            break
        w.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 600, "y": 0, "z": 500, "r": 0}, *GCS))
        w.advance(w.time_us + 100_000)
    assert w.nav_state == NavState.AUTO_RTL
    w.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS))
    w.advance(w.time_us + 100_000)
    assert w.nav_state == NavState.POSCTL and w.user_nav_state == NavState.POSCTL


def test_the_log_says_when_the_sticks_moved():
    import io

    from pyulog import ULog

    from .test_offboard import airborne_offboard

    s = airborne_offboard(COM_RC_OVERRIDE=3)
    for y in (0, 0, 600, 600, 600, 600, 600):  # 10 Hz
        s.v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": y, "z": 500, "r": 0}, *GCS))
        s.stream(0.1, x=0.0, y=0.0, z=-5.0)
    assert s.cmd(MavCmd.COMPONENT_ARM_DISARM, 0, 21196) == MavResult.ACCEPTED  # forced: the log closes
    s.fly(0.1)
    log = ULog(io.BytesIO(s.sink.logs[0]))
    moving = list(log.get_dataset("manual_control_setpoint").data["sticks_moving"])
    # the step's rate, 6 /s, low-passed (alpha 0.5 at 10 Hz): 3, 1.5, 0.75, 0.375, then under 0.3 /s
    assert moving == [0, 0, 1, 1, 1, 1, 0]


def test_in_a_position_loss_descend_the_sticks_take_over_in_altitude_mode():
    from uavtest.mavlink_numbers import FailureType, FailureUnit

    f = Watched()
    f.takeoff()
    f.fly(0.5, each=f.sticks)
    assert f.inject(FailureUnit.SENSOR_GPS, FailureType.OFF) == MavResult.ACCEPTED
    f.fly(10, until=lambda v: v.nav_state == NavState.DESCEND, each=f.sticks)
    assert f.v.nav_state == NavState.DESCEND  # EKF2_NOAID_TOUT, then COM_POS_FS_DELAY
    f.fly(0.1, each=lambda: f.sticks(z=700))  # throttle up: the user's mode becomes Position,
    v = f.v  # which without a position falls back to Altitude (COM_POSCTL_NAVL 0)
    assert v.nav_state == NavState.ALTCTL and v.user_nav_state == NavState.POSCTL and f.said(TOOK_OVER)
    z0 = v.body.z
    f.fly(2, each=lambda: f.sticks(z=700))
    assert v.body.z < z0 - 0.5 and v.nav_state == NavState.ALTCTL  # climbing on the pilot's throttle
