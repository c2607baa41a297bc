"""The failsafe action delay of PX4 v1.15's failsafe framework (commander/failsafe/framework.cpp).

Manual control loss, data link loss, the battery failsafes (and a motor failure) act after
COM_FAIL_ACT_T seconds in Hold (5 s): the vehicle reports Hold (HEARTBEAT, vehicle_status), the
user's mode is kept as the intention, and PX4 says "Failsafe activated: entering Hold for N
seconds" (its event: "<cause>: switching to <action> in N seconds"), then "Failsafe activated"
when the action comes. A mode change during the hold takes over; the condition clearing ends a
Hold or Land action (back to the user's mode) but not a Return. Terminate and disarm do not wait;
COM_FAIL_ACT_T <= 0.1 acts at once; a failsafe on top of one beyond Hold acts at once.
"""

from __future__ import annotations

import math

import pytest

from uavtest.px4.modes import NavState, nav_state_from_custom_mode, split_custom_mode
from uavtest.sitl.commander.failsafe import Cause, FailsafeFramework, NavAction, Selected, notify_texts
from uavtest.sitl.mav import MavCmd, MavFrame, MavResult, MavSeverity, Msg
from uavtest.sitl.mission import NavItem

from .test_battery_failures import GCS, Flight

TICK_S = 0.02


class Watched(Flight):
    """A Flight that records every change of (nav state, user's mode, failsafe flag) in time,
    and the nav state each HEARTBEAT reports."""

    def __init__(self, **params: float) -> None:
        super().__init__(**params)
        self.modes: list[tuple[float, NavState, NavState, bool]] = []
        self.heartbeats: list[tuple[float, NavState | None]] = []

    def _take(self, msgs) -> None:
        super()._take(msgs)
        v = self.v
        now = (v.nav_state, v.user_nav_state, v.failsafe)
        if not self.modes or self.modes[-1][1:] != now:
            self.modes.append((v.time_us / 1e6, *now))
        for m in msgs:
            if m.name == "HEARTBEAT":
                ns = nav_state_from_custom_mode(*split_custom_mode(m.fields["custom_mode"]))
                self.heartbeats.append((v.time_us / 1e6, ns))

    def since(self, t0: float) -> list[tuple[float, str]]:
        return [(round(t - t0, 2), text) for t, text in self.texts if t >= t0]

    def modes_since(self, t0: float) -> list[tuple[float, NavState, NavState, bool]]:
        return [(round(t - t0, 2), ns, user, fs) for t, ns, user, fs in self.modes if t >= t0]


def _rc_lost_in_position_mode(**params: float) -> tuple[Watched, float]:
    """Taken off, in Position mode with sticks, then the sticks stop: returns the flight and the
    moment the manual control loss is detected (COM_RC_LOSS_T after the last sticks)."""
    f = Watched(**params)
    f.takeoff()
    f.fly(1, each=f.sticks)
    assert f.command(MavCmd.DO_SET_MODE, 1, 3, 0) == 0  # POSCTL
    f.fly(1, each=f.sticks)
    f.fly(2, until=lambda v: v.commander.rc_lost)
    return f, f.v.time_us / 1e6


def test_rc_loss_holds_com_fail_act_t_then_returns():
    f, t0 = _rc_lost_in_position_mode()
    f.fly(7)
    P, H, R = NavState.POSCTL, NavState.AUTO_LOITER, NavState.AUTO_RTL
    # (seconds after the loss, nav state, the user's mode, vehicle_status.failsafe)
    assert f.modes_since(t0) == [(0.0, H, P, True), (5.0, R, P, True)]
    assert f.since(t0)[:6] == [
        (0.0, "Manual control lost"),
        (0.0, "Manual control loss: switching to RTL in 5 seconds"),
        (0.0, "Failsafe activated: entering Hold for 5 seconds"),
        (5.0, "Manual control loss: switching to RTL"),
        (5.0, "Failsafe activated"),
        (5.0, "RTL: start return at 498 m (10 m above destination)"),  # PX4: AMSL, ceilf
    ]
    # HEARTBEAT custom mode: Hold during the delay, then Return
    assert {ns for t, ns in f.heartbeats if t0 < t < t0 + 5.0} == {H}
    assert {ns for t, ns in f.heartbeats if t0 + 5.0 < t} == {R}
    assert f.last["HEARTBEAT"].fields["system_status"] == 5  # MAV_STATE_CRITICAL: in failsafe


def test_a_mode_change_during_the_hold_takes_over():
    f, t0 = _rc_lost_in_position_mode()
    f.fly(2)
    assert f.v.nav_state == NavState.AUTO_LOITER
    # Altitude mode needs manual control, which is lost: PX4 refuses it (can_run), the Hold goes on
    assert f.command(MavCmd.DO_SET_MODE, 1, 2, 0) == MavResult.TEMPORARILY_REJECTED
    assert f.v.nav_state == NavState.AUTO_LOITER
    assert f.command(MavCmd.DO_SET_MODE, 1, 4, 6) == 0  # Land: the user takes over
    f.fly(8)
    assert f.v.nav_state == NavState.AUTO_LAND and not f.v.failsafe
    texts = [s for _, s in f.since(t0)]
    assert "Failsafe activated: entering Hold for 5 seconds" in texts and "Failsafe activated" not in texts


def test_regained_during_the_hold_a_land_action_ends_a_return_does_not():
    # Land (WhenConditionClears): back to the user's mode
    f, t0 = _rc_lost_in_position_mode(NAV_RCL_ACT=3)
    f.fly(2)
    f.fly(1, each=f.sticks)
    assert f.v.nav_state == NavState.POSCTL and not f.v.failsafe
    f.fly(6, each=f.sticks)
    assert f.v.nav_state == NavState.POSCTL and "Manual control regained" in [s for _, s in f.since(t0)]
    # Return (OnModeChangeOrDisarm): it still comes after the delay, until the user changes mode
    g, t1 = _rc_lost_in_position_mode(NAV_RCL_ACT=2)
    g.fly(2)
    g.fly(1, each=g.sticks)
    assert g.v.nav_state == NavState.AUTO_LOITER
    g.fly(3, each=g.sticks)
    assert g.v.nav_state == NavState.AUTO_RTL
    assert [t for t, s in g.since(t1) if s == "Failsafe activated"] == [5.0]
    g.command(MavCmd.DO_SET_MODE, 1, 3, 0)
    g.fly(2, each=g.sticks)
    assert g.v.nav_state == NavState.POSCTL and not g.v.failsafe


def test_data_link_loss_lands_after_the_hold_and_the_link_back_returns_to_the_users_mode():
    f = Watched(NAV_DLL_ACT=3, COM_DL_LOSS_T=3)
    gcs = Msg("HEARTBEAT", {"type": 6, "autopilot": 8}, *GCS)
    f.v.receive(gcs)
    f.fly(5, until=lambda v: v.ready)
    f.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    f.command(MavCmd.NAV_TAKEOFF, 0, 0, 0, float("nan"), float("nan"), float("nan"), 488.0 + 8)
    f.fly(
        30,
        until=lambda v: v.nav_state == NavState.AUTO_LOITER and -v.body.z > 7.5,
        each=lambda: f.v.receive(gcs),
    )
    # the pilot's RC (manual control) stays: Position mode needs it; only the data link goes
    rc = Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS)
    f.v.receive(rc)
    assert f.command(MavCmd.DO_SET_MODE, 1, 3, 0) == 0  # POSCTL
    f.fly(10, until=lambda v: v.gcs_lost, each=lambda: f.v.receive(rc))
    t0 = f.v.time_us / 1e6
    f.fly(6, each=lambda: f.v.receive(rc))
    P, H, L = NavState.POSCTL, NavState.AUTO_LOITER, NavState.AUTO_LAND
    assert f.modes_since(t0) == [(0.0, H, P, True), (5.0, L, P, True)]
    assert f.since(t0)[:5] == [
        (0.0, "Connection to ground station lost"),
        (0.0, "GCS connection loss: switching to Land in 5 seconds"),
        (0.0, "Failsafe activated: entering Hold for 5 seconds"),
        (5.0, "GCS connection loss: switching to Land"),
        (5.0, "Failsafe activated"),
    ]
    f.v.receive(gcs)  # the link is back: Land (WhenConditionClears) goes, Position again
    f.fly(0.1)
    assert f.v.nav_state == P and not f.v.failsafe and f.said("Data link regained")


def test_com_fail_act_t_0_acts_at_once_and_the_delay_is_said_rounded():
    f, t0 = _rc_lost_in_position_mode(COM_FAIL_ACT_T=0)
    assert f.modes_since(t0)[0][:2] == (0.0, NavState.AUTO_RTL)
    assert [s for _, s in f.since(t0)][:3] == [
        "Manual control lost",
        "Manual control loss: switching to RTL",
        "Failsafe activated",
    ]
    g, t1 = _rc_lost_in_position_mode(COM_FAIL_ACT_T=2.6)
    g.fly(3)
    assert "Failsafe activated: entering Hold for 3 seconds" in [s for _, s in g.since(t1)]
    assert [(t, ns) for t, ns, _, _ in g.modes_since(t1)] == [
        (0.0, NavState.AUTO_LOITER),
        (2.6, NavState.AUTO_RTL),
    ]


def test_rc_loss_disarm_and_terminate_do_not_wait():
    f, t0 = _rc_lost_in_position_mode(NAV_RCL_ACT=6)  # disarm (lockdown)
    assert not f.v.armed and (0.0, "Disarmed by failsafe") in f.since(t0)
    g, t1 = _rc_lost_in_position_mode(NAV_RCL_ACT=5)  # terminate
    assert g.v.crashed and (0.0, "Failsafe: flight termination") in g.since(t1)


def test_critical_battery_holds_then_returns_and_emergency_lands_at_once():
    f = Watched(
        SIM_BAT_DRAIN=40, SIM_BAT_MIN_PCT=0, BAT_LOW_THR=0.6, BAT_CRIT_THR=0.4, BAT_EMERGEN_THR=0.25,
        COM_LOW_BAT_ACT=3, RTL_RETURN_ALT=15,
    )  # fmt: skip
    f.takeoff()
    f.fly(60, until=lambda v: v.battery.warning >= 2)
    f.fly(0.3)
    t0 = next(t for t, s in f.texts if s.startswith("Critical battery level"))
    assert f.since(t0)[:2] == [
        (0.0, "Critical battery level: switching to RTL in 5 seconds"),
        (0.0, "Failsafe activated: entering Hold for 5 seconds"),
    ]
    f.fly(60, until=lambda v: v.battery.warning >= 3)
    f.fly(0.3)
    texts = [s for _, s in f.since(t0)]
    assert texts[2:4] == ["Critical battery level: switching to RTL", "Failsafe activated"]
    assert "Emergency battery level: switching to Land" in texts  # no second hold: already returning
    ns = [(t, n) for t, n, _, _ in f.modes_since(t0)]
    assert (
        ns[:2] == [(0.0, NavState.AUTO_LOITER), (5.0, NavState.AUTO_RTL)] and ns[2][1] == NavState.AUTO_LAND
    )
    assert not any("entering Hold" in s for s in texts[2:])


def test_low_battery_warns_with_px4s_failsafe_text():
    f = Flight(SIM_BAT_DRAIN=20, SIM_BAT_MIN_PCT=0, BAT_LOW_THR=0.6, BAT_CRIT_THR=0.1, BAT_EMERGEN_THR=0.05)
    f.takeoff()
    f.fly(60, until=lambda v: v.battery.warning >= 1)
    f.fly(0.3)
    i = next(i for i, (_, s) in enumerate(f.texts) if s == "Low battery level, return advised")
    assert f.texts[i + 1][1] == "Failsafe activated" and f.v.nav_state == NavState.AUTO_LOITER


# ---------------------------------------------------------------- the framework alone


def test_the_start_delay_runs_down_in_a_hold_and_recovers_at_a_quarter():
    """updateStartDelay: a condition that comes and goes still ends in its action."""
    fw = FailsafeFramework(5.0)
    t = 0
    fw.update(t, 5.0, NavState.POSCTL, False)
    fw.add("rc", NavAction.LAND, Cause.MANUAL_CONTROL_LOSS, sticky=False, fail_act_t=5.0)
    for _ in range(150):  # 3 s in the hold
        t += 20_000
        fw.update(t, 5.0, NavState.POSCTL, False)
    assert fw.selected == Selected(NavAction.HOLD, NavAction.LAND, Cause.MANUAL_CONTROL_LOSS)
    assert fw.start_delay_us == 2_000_000
    fw.clear("rc")  # Land goes with its condition; the delay runs on (2 s left)
    for _ in range(150):  # 3 s without: 0.75 s back
        t += 20_000
        fw.update(t, 5.0, NavState.POSCTL, False)
    assert fw.selected.action == NavAction.DISABLED and fw.delay_us == 0
    assert fw.start_delay_us == 2_750_000
    fw.add("rc", NavAction.LAND, Cause.MANUAL_CONTROL_LOSS, sticky=False, fail_act_t=5.0)
    t += 20_000
    assert fw.update(t, 5.0, NavState.POSCTL, False) and fw.selected.action == NavAction.HOLD
    start = t
    while fw.selected.action == NavAction.HOLD:
        t += 20_000
        fw.update(t, 5.0, NavState.POSCTL, False)
    assert fw.selected.action == NavAction.LAND and t - start == 2_760_000  # 2.75 s, at a tick


def test_already_landing_a_return_is_only_a_warning():
    fw = FailsafeFramework(5.0)
    fw.add("battery", NavAction.RETURN, Cause.BATTERY_CRITICAL, sticky=False, fail_act_t=5.0)
    assert fw.update(0, 5.0, NavState.AUTO_LAND, False)
    assert fw.selected.action == NavAction.WARN


def test_notify_texts_are_px4s():
    crit = MavSeverity.CRITICAL
    generic = Selected(NavAction.HOLD, NavAction.LAND, Cause.GENERIC)
    assert notify_texts(generic, 4_600_000) == [
        (crit, "Failsafe activated: switching to Land in 5 seconds"),
        (crit, "Failsafe activated: entering Hold for 5 seconds"),
    ]
    assert notify_texts(Selected(NavAction.RETURN, cause=Cause.GENERIC), 0) == [
        (crit, "Failsafe activated: Autopilot disengaged, switching to RTL"),
        (crit, "Failsafe activated"),
    ]
    assert notify_texts(Selected(NavAction.WARN, cause=Cause.BATTERY_EMERGENCY), 0) == [
        (MavSeverity.EMERGENCY, "Emergency battery level, land immediately"),
        (crit, "Failsafe activated"),
    ]


def test_a_mission_failure_holds_com_fail_act_t_then_returns():
    """failsafe.cpp: while the user wants Mission and mission_result.failure is set (here a
    LOITER_TIME that requires a heading, param2 1, not reached within MIS_YAW_TMT), PX4 says
    "Mission cannot be completed" and returns, after COM_FAIL_ACT_T in Hold like any failsafe."""
    f = Watched(MIS_YAW_TMT=0.5)
    f.takeoff()
    f.fly(20, until=lambda v: v.nav_state == NavState.AUTO_LOITER)
    f.fly(3)  # settled in Hold
    v = f.v
    lat, lon = v.proj.reproject(v.st.x, v.st.y)
    heading = (math.degrees(v.st.yaw) + 180.0) % 360.0  # behind it: a 4 s turn at 45 degrees/s
    here = NavItem(0, MavCmd.NAV_LOITER_TIME, MavFrame.GLOBAL_RELATIVE_ALT_INT, param2=1.0,
                   param4=heading, x=round(lat * 1e7), y=round(lon * 1e7), z=-v.st.z)  # fmt: skip
    v.load_mission([here])
    t0 = v.time_us / 1e6
    f.command(MavCmd.DO_SET_MODE, 1, 4, 4)
    f.fly(12, until=lambda v: v.nav_state == NavState.AUTO_RTL)
    said = f.since(t0)
    texts = [text for _, text in said]
    assert "unable to reach heading within timeout" in texts
    assert "Mission cannot be completed" in texts
    failed = next(t for t, text in said if text == "Mission cannot be completed")
    assert 0.4 <= failed <= 1.0  # MIS_YAW_TMT after the arrival (on the item at once)
    modes = f.modes_since(t0)
    hold = next(m for m in modes if m[1] == NavState.AUTO_LOITER and m[3])
    rtl = next(m for m in modes if m[1] == NavState.AUTO_RTL)
    assert hold[2] == NavState.AUTO_MISSION  # the user's mode is kept during the hold
    assert rtl[0] - hold[0] == pytest.approx(5.0, abs=0.1)  # COM_FAIL_ACT_T
    assert v.nav.failure and v.armed
