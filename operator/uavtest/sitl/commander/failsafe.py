"""Failsafes as data (PX4 ``commander/failsafe``): conditions, and what each action does.

NAV_DLL_ACT (data link lost) and NAV_RCL_ACT (manual control lost) choose an action; the table
``ACTION_NAV_STATE`` says which nav state it switches to. Termination cuts the motors.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from uavtest.px4.modes import NavState

__all__ = ["ACTION_NAV_STATE", "DATA_LINK_LOST", "MANUAL_CONTROL_LOST", "Condition", "NavAction"]


class NavAction(IntEnum):
    """NAV_DLL_ACT / NAV_RCL_ACT values."""

    DISABLED = 0
    HOLD = 1
    RETURN = 2
    LAND = 3
    TERMINATE = 5


#: action → the nav state the commander switches to
ACTION_NAV_STATE: dict[int, NavState] = {
    NavAction.HOLD: NavState.AUTO_LOITER,
    NavAction.RETURN: NavState.AUTO_RTL,
    NavAction.LAND: NavState.AUTO_LAND,
}


@dataclass(frozen=True, slots=True)
class Condition:
    """A failsafe condition: the parameter choosing its action and the text PX4 reports."""

    action_param: str
    text: str


DATA_LINK_LOST = Condition("NAV_DLL_ACT", "Connection to ground station lost")
MANUAL_CONTROL_LOST = Condition("NAV_RCL_ACT", "Manual control lost")
