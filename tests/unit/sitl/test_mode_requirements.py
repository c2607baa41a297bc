"""Which modes the built-in vehicle switches to and arms in: PX4 v1.15's mode requirements.

Every expectation here was seen on PX4 v1.15 SIH with pymavlink and no manual control ever sent
(2026-11-27): disarmed, every mode change is ACCEPTED and arming in a mode that cannot arm is
TEMPORARILY_REJECTED with "Arming denied: Resolve system health failures first" (SYS_STATUS's
pre-arm bit clears in that mode); hovering armed, Position / Altitude / Stabilized without
sticks, Mission without a mission and Offboard without setpoints are TEMPORARILY_REJECTED with
"Switching to <mode> is currently not available" (for a request from component 190 only) and the
vehicle stays in Hold; Return is ACCEPTED.
"""

from __future__ import annotations

import pytest

from uavtest.mavlink_numbers import FailureType, FailureUnit
from uavtest.px4.modes import NavState
from uavtest.sitl.commander.mode_requirements import ModeFlags, Need, can_arm, can_run, missing
from uavtest.sitl.mav import SYS_STATUS_PREARM_CHECK, MavCmd, MavResult, Msg

from .test_battery_failures import Flight

RESOLVE = "Arming denied: Resolve system health failures first"
POSCTL, ALTCTL, STAB, OFFBOARD = (3, 0), (2, 0), (7, 0), (6, 0)
MISSION, RTL, LAND, HOLD = (4, 4), (4, 5), (4, 6), (4, 3)


def _set_mode(f: Flight, mode: tuple[int, int]) -> int:
    return f.command(MavCmd.DO_SET_MODE, 1, *mode)


def _prearm(f: Flight) -> bool:
    f.fly(1.1)  # SYS_STATUS streams at 1 Hz
    return bool(f.last["SYS_STATUS"].fields["onboard_control_sensors_health"] & SYS_STATUS_PREARM_CHECK)


# ---------------------------------------------------------------- the table


def test_the_stick_modes_need_manual_control_and_the_auto_modes_a_position() -> None:
    no_sticks = ModeFlags(manual_control_lost=True)
    for ns in (NavState.POSCTL, NavState.ALTCTL, NavState.STAB, NavState.MANUAL, NavState.ACRO):
        assert missing(ns, no_sticks) == Need.MANUAL_CONTROL
    assert can_run(NavState.AUTO_LOITER, no_sticks) and can_run(NavState.AUTO_RTL, no_sticks)
    no_position = ModeFlags(position_invalid=True)
    for ns in (
        NavState.POSCTL,
        NavState.AUTO_MISSION,
        NavState.AUTO_LOITER,
        NavState.AUTO_RTL,
        NavState.ORBIT,
    ):
        assert not can_run(ns, no_position)
    assert can_run(NavState.ALTCTL, no_position) and can_run(NavState.DESCEND, no_position)
    assert not can_run(NavState.AUTO_RTL, ModeFlags(home_invalid=True))
    assert not can_run(NavState.AUTO_MISSION, ModeFlags(mission_missing=True))
    assert can_run(NavState.AUTO_LOITER, ModeFlags(mission_missing=True))


def test_return_land_and_orbit_cannot_arm_and_com_arm_mis_req_needs_a_mission_everywhere() -> None:
    ok = ModeFlags()
    for ns in (NavState.AUTO_RTL, NavState.AUTO_LAND, NavState.DESCEND, NavState.ORBIT):
        assert can_run(ns, ok) and not can_arm(ns, ok)
    assert can_arm(NavState.AUTO_LOITER, ok) and can_arm(NavState.AUTO_TAKEOFF, ok)
    assert can_arm(NavState.AUTO_LOITER, ModeFlags(mission_missing=True))
    assert not can_arm(NavState.AUTO_LOITER, ModeFlags(mission_missing=True, arm_needs_mission=True))


# ---------------------------------------------------------------- disarmed


@pytest.mark.parametrize("mode", [POSCTL, ALTCTL, RTL, LAND, MISSION, OFFBOARD])
def test_disarmed_every_mode_change_is_taken_and_arming_in_one_that_cannot_arm_is_refused(
    mode: tuple[int, int],
) -> None:
    f = Flight()
    f.fly(5, until=lambda v: v.ready)
    assert _prearm(f)
    assert _set_mode(f, mode) == MavResult.ACCEPTED
    assert not _prearm(f)  # pre_flight_checks_pass is canArm in the current mode
    assert f.command(MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.TEMPORARILY_REJECTED
    assert not f.v.armed and f.said(RESOLVE)
    assert _set_mode(f, HOLD) == MavResult.ACCEPTED and _prearm(f)
    assert f.command(MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED


def test_with_sticks_position_mode_arms() -> None:
    f = Flight()
    f.fly(5, until=lambda v: v.ready, each=f.sticks)
    assert _set_mode(f, POSCTL) == MavResult.ACCEPTED
    f.sticks()
    assert f.command(MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED


def test_com_arm_mis_req_refuses_arming_without_a_mission() -> None:
    f = Flight(COM_ARM_MIS_REQ=1)
    f.fly(5, until=lambda v: v.ready)
    assert f.command(MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.TEMPORARILY_REJECTED
    assert f.said(RESOLVE)


# ---------------------------------------------------------------- armed, in the air


def test_in_flight_a_mode_that_cannot_run_is_refused_and_the_hold_goes_on() -> None:
    f = Flight()
    f.takeoff()
    for mode, name in ((POSCTL, "Position"), (ALTCTL, "Altitude"), (STAB, "Stabilized")):
        assert _set_mode(f, mode) == MavResult.TEMPORARILY_REJECTED
        assert f.said(f"Switching to {name} is currently not available")
    assert _set_mode(f, MISSION) == MavResult.TEMPORARILY_REJECTED  # no mission uploaded
    assert _set_mode(f, OFFBOARD) == MavResult.TEMPORARILY_REJECTED  # no setpoints
    f.fly(2)
    assert f.v.armed and f.v.nav_state == NavState.AUTO_LOITER and not f.v.failsafe
    assert f.said("Switching to Mission is currently not available")
    assert f.said("Switching to Offboard is currently not available")
    f.fly(0.5, each=f.sticks)  # manual control now: Position mode runs
    assert _set_mode(f, POSCTL) == MavResult.ACCEPTED and f.v.nav_state == NavState.POSCTL


def test_the_refusal_is_said_only_to_the_mission_planner_component() -> None:
    f = Flight()
    f.takeoff()
    fields = {"command": int(MavCmd.DO_SET_MODE), "target_system": 1, "target_component": 1}
    fields.update({"param1": 1, "param2": 3, "param3": 0})
    ack, *rest = f.v.receive(Msg("COMMAND_LONG", fields, 255, 1))  # a companion, not a GCS
    f._take(rest)
    f.fly(0.5)
    assert ack.fields["result"] == MavResult.TEMPORARILY_REJECTED
    assert not f.said("currently not available")


def test_return_and_land_are_taken_and_said_and_disarmed_the_vehicle_is_back_in_hold() -> None:
    f = Flight()
    f.takeoff()
    assert f.command(MavCmd.NAV_RETURN_TO_LAUNCH) == MavResult.ACCEPTED and f.said("Returning to launch")
    assert f.command(MavCmd.NAV_LAND) == MavResult.ACCEPTED and f.said("Landing at current position")
    f.fly(60, until=lambda v: not v.armed)
    # UserModeIntention::onDisarm (PX4 SIH: AUTO/LOITER after a Return landed): it may arm again
    assert not f.v.armed and f.v.nav_state == NavState.AUTO_LOITER == f.v.user_nav_state
    assert f.command(MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED


def test_without_a_position_the_auto_modes_are_refused_and_altitude_mode_is_not() -> None:
    f = Flight(COM_POSCTL_NAVL=0)
    f.takeoff()
    f.fly(0.5, each=f.sticks)
    assert f.inject(FailureUnit.SENSOR_GPS, FailureType.OFF) == MavResult.ACCEPTED
    f.fly(10, until=lambda v: v.commander.position_fallback, each=f.sticks)
    assert f.v.commander.position_fallback
    for mode in (HOLD, RTL, MISSION, POSCTL):
        assert _set_mode(f, mode) == MavResult.TEMPORARILY_REJECTED
    assert _set_mode(f, ALTCTL) == MavResult.ACCEPTED


def test_mission_start_without_a_valid_mission_is_denied() -> None:
    f = Flight()
    f.fly(5, until=lambda v: v.ready)
    assert f.command(MavCmd.MISSION_START, 0, 0) == MavResult.DENIED
    assert f.said("Mission start denied! No valid mission") and not f.v.armed
