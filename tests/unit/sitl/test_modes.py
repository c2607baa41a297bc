from pymavlink.dialects.v20 import common as mavlink2

from uavtest.px4.modes import (
    AutoSubMode,
    MainMode,
    NavState,
    base_mode_flags,
    custom_mode,
    nav_state_from_custom_mode,
    split_custom_mode,
)
from uavtest.sitl import mav


def test_custom_mode_packs_main_in_bits_16_23_and_sub_in_24_31():
    assert custom_mode(NavState.AUTO_MISSION) == (4 << 16) | (4 << 24)
    assert custom_mode(NavState.POSCTL) == 3 << 16
    assert split_custom_mode(custom_mode(NavState.AUTO_RTL)) == (MainMode.AUTO, AutoSubMode.RTL)


def test_px4_numbers():
    assert (MainMode.AUTO, MainMode.OFFBOARD, MainMode.STABILIZED) == (4, 6, 7)
    assert (AutoSubMode.TAKEOFF, AutoSubMode.LOITER, AutoSubMode.LAND, AutoSubMode.PRECLAND) == (2, 3, 6, 9)
    assert (NavState.AUTO_MISSION, NavState.AUTO_LOITER, NavState.AUTO_TAKEOFF, NavState.AUTO_LAND) == (
        3,
        4,
        17,
        18,
    )


def test_every_flown_mode_round_trips_through_custom_mode():
    for ns in (
        NavState.MANUAL,
        NavState.ALTCTL,
        NavState.POSCTL,
        NavState.AUTO_MISSION,
        NavState.AUTO_LOITER,
        NavState.AUTO_RTL,
        NavState.AUTO_TAKEOFF,
        NavState.AUTO_LAND,
        NavState.STAB,
    ):
        assert nav_state_from_custom_mode(*split_custom_mode(custom_mode(ns))) == ns


def test_unknown_modes_are_refused():
    assert nav_state_from_custom_mode(MainMode.OFFBOARD, 0) == NavState.OFFBOARD
    assert nav_state_from_custom_mode(MainMode.AUTO, AutoSubMode.FOLLOW_TARGET) is None
    assert nav_state_from_custom_mode(42, 0) is None


def test_base_mode_flags_say_armed_and_custom():
    flags = base_mode_flags(NavState.AUTO_MISSION, armed=True)
    assert flags & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
    assert flags & mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert flags & mavlink2.MAV_MODE_FLAG_AUTO_ENABLED
    assert not base_mode_flags(NavState.POSCTL, armed=False) & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED


def test_mavlink_numbers_match_pymavlink():
    """Differential: our copies of MAVLink enum values against pymavlink's common dialect."""
    for enum, prefix in (
        (mav.MavResult, "MAV_RESULT_"),
        (mav.MavCmd, "MAV_CMD_"),
        (mav.MissionResult, "MAV_MISSION_"),
        (mav.MissionType, "MAV_MISSION_TYPE_"),
        (mav.MavFrame, "MAV_FRAME_"),
        (mav.ParamType, "MAV_PARAM_TYPE_"),
        (mav.LandedState, "MAV_LANDED_STATE_"),
        (mav.MavState, "MAV_STATE_"),
        (mav.MavSeverity, "MAV_SEVERITY_"),
    ):
        for member in enum:
            name = prefix + member.name
            if enum is mav.MissionResult and member.name not in ("ACCEPTED",):
                name = "MAV_MISSION_" + member.name
            assert getattr(mavlink2, name) == member.value, name
    assert mavlink2.MAV_AUTOPILOT_PX4 == mav.MAV_AUTOPILOT_PX4
    assert mavlink2.MAV_SYS_STATUS_PREARM_CHECK == mav.SYS_STATUS_PREARM_CHECK
    assert mavlink2.MAV_TYPE_QUADROTOR == mav.MAV_TYPE_QUADROTOR


def test_one_home_for_runner_and_simulator():
    from uavtest.px4.modes import encode_custom_mode, mode_name
    from uavtest.runner import px4 as runner_px4
    from uavtest.spec.models import FlightMode

    assert runner_px4.custom_mode(FlightMode.MISSION) == custom_mode(NavState.AUTO_MISSION)
    assert runner_px4.custom_mode(FlightMode.POSITION) == encode_custom_mode(MainMode.POSCTL)
    assert mode_name(4, 5) == "AUTO.RTL" and mode_name(3, 0) == "POSCTL" and mode_name(9, 0) == "9/0"
