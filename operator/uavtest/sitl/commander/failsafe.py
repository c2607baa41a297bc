"""Failsafes as data (PX4 ``commander/failsafe``): conditions, and what each action does.

NAV_DLL_ACT (data link lost) and NAV_RCL_ACT (manual control lost) choose an action; the table
``ACTION_NAV_STATE`` says which nav state it switches to. Termination cuts the motors.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from uavtest.px4.modes import NavState

__all__ = [
    "ACTION_NAV_STATE",
    "DATA_LINK_LOST",
    "GEOFENCE_TEXTS",
    "GF_ACTION_NAV_STATE",
    "GF_DELAYED_ACTIONS",
    "MANUAL_CONTROL_LOST",
    "Condition",
    "GeofenceAction",
    "NavAction",
]


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


class GeofenceAction(IntEnum):
    """GF_ACTION values (msg/GeofenceResult.msg GF_ACTION_*)."""

    NONE = 0
    WARN = 1
    LOITER = 2
    RTL = 3
    TERMINATE = 4
    LAND = 5


#: GF_ACTION → the nav state (failsafe.cpp Failsafe::fromGfActParam: Hold_mode, Return_mode, Land_mode)
GF_ACTION_NAV_STATE: dict[int, NavState] = {
    GeofenceAction.LOITER: NavState.AUTO_LOITER,
    GeofenceAction.RTL: NavState.AUTO_RTL,
    GeofenceAction.LAND: NavState.AUTO_LAND,
}
#: actions whose user takeover is ``Auto`` in fromGfActParam: with COM_FAIL_ACT_T > 0.1 s the
#: framework (failsafe/framework.cpp) holds that long first ("entering Hold for N seconds");
#: Hold is AlwaysModeSwitchOnly and Terminate Never, so they act at once
GF_DELAYED_ACTIONS = frozenset({GeofenceAction.RTL, GeofenceAction.LAND})
#: geofence_result flag → the critical text PX4 sends (HealthAndArmingChecks/checks/geofenceCheck.cpp)
GEOFENCE_TEXTS = (
    ("max_dist", "Geofence violation: exceeding maximum distance to Home"),
    ("max_alt", "Geofence violation: exceeding maximum altitude above Home"),
    ("custom", "Geofence violation: approaching or outside geofence"),
)
