"""The commander's tables: failsafe actions, arming checks, command handlers."""

from uavtest.px4.modes import NavState
from uavtest.sitl.commander.arming import ARMING_CHECKS, arming_denied
from uavtest.sitl.commander.failsafe import ACTION_NAV_STATE, NavAction
from uavtest.sitl.commander.vehicle_command import HANDLERS
from uavtest.sitl.mav import MavCmd, MavResult
from uavtest.sitl.vehicle import SimConfig, Vehicle


def test_failsafe_actions_switch_to_px4s_nav_states():
    assert ACTION_NAV_STATE == {
        NavAction.HOLD: NavState.AUTO_LOITER,
        NavAction.RETURN: NavState.AUTO_RTL,
        NavAction.LAND: NavState.AUTO_LAND,
        NavAction.DESCEND: NavState.DESCEND,
    }
    assert NavAction.TERMINATE not in ACTION_NAV_STATE  # termination cuts the motors instead
    assert NavAction.DISARM not in ACTION_NAV_STATE  # NAV_RCL_ACT 6: disarm (lockdown)


def test_first_failing_arming_check_decides():
    v = Vehicle(SimConfig())
    assert arming_denied(v) is ARMING_CHECKS[0]
    assert ARMING_CHECKS[0].result == MavResult.TEMPORARILY_REJECTED
    v.fly_until(lambda v: v.ready, 5_000_000)
    assert arming_denied(v) is None


def test_every_handled_command_has_a_handler_and_others_are_unsupported():
    assert MavCmd.COMPONENT_ARM_DISARM in HANDLERS and MavCmd.NAV_TAKEOFF in HANDLERS
    assert 183 not in HANDLERS  # DO_SET_SERVO
