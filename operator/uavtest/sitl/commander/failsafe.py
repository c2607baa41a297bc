"""Failsafes as data (PX4 ``commander/failsafe/failsafe.cpp``): conditions, and what each action does.

NAV_DLL_ACT (data link lost) and NAV_RCL_ACT (manual control lost) choose an action
(``fromNavDllOrRclActParam``: 1 hold, 2 return, 3 land, 5 terminate, 6 disarm / lockdown);
COM_LOW_BAT_ACT chooses the battery action per warning level (``fromBatteryWarningActParam``);
COM_ACT_FAIL_ACT the motor-failure action (``fromActuatorFailureActParam``). The table
``ACTION_NAV_STATE`` says which nav state an action switches to; termination cuts the motors,
disarm disarms in the air.

Texts: the condition's STATUSTEXT, then "Failsafe activated: <mode>" (the existing bench
convention; PX4 sends the same as an event, ``failsafe/framework.cpp``). The battery warnings
that take no action are PX4's: "Low battery level, return advised", "Critical battery level,
land now", "Emergency battery level, land immediately".
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from uavtest.px4.modes import NavState

__all__ = [
    "ACTION_NAV_STATE",
    "BATTERY_TEXT",
    "DATA_LINK_LOST",
    "GEOFENCE_TEXTS",
    "GF_ACTION_NAV_STATE",
    "GF_DELAYED_ACTIONS",
    "MANUAL_CONTROL_LOST",
    "NAV_STATE_NAME",
    "OFFBOARD_LOSS_NAV_STATE",
    "POSITION_LOST",
    "RCL_EXCEPT_HOLD",
    "RCL_EXCEPT_MISSION",
    "RCL_EXCEPT_OFFBOARD",
    "RC_IN_MODE_DISABLED",
    "Condition",
    "GeofenceAction",
    "NavAction",
    "OffboardLossAction",
    "actuator_failure_action",
    "battery_action",
]


class NavAction(IntEnum):
    """Failsafe actions, numbered as NAV_DLL_ACT / NAV_RCL_ACT values."""

    DISABLED = 0
    HOLD = 1
    RETURN = 2
    LAND = 3
    TERMINATE = 5
    DISARM = 6
    WARN = 100  # not a NAV_*_ACT value: report only
    DESCEND = 101  # not a NAV_*_ACT value: land without a position (mode fallback)


#: action → the nav state the commander switches to
ACTION_NAV_STATE: dict[int, NavState] = {
    NavAction.HOLD: NavState.AUTO_LOITER,
    NavAction.RETURN: NavState.AUTO_RTL,
    NavAction.LAND: NavState.AUTO_LAND,
    NavAction.DESCEND: NavState.DESCEND,
}

#: COM_RC_IN_MODE: stick input disabled (no RC-loss failsafe)
RC_IN_MODE_DISABLED = 4
#: COM_RCL_EXCEPT bits (ManualControlLossExceptionBits)
RCL_EXCEPT_MISSION, RCL_EXCEPT_HOLD, RCL_EXCEPT_OFFBOARD = 1, 2, 4


@dataclass(frozen=True, slots=True)
class Condition:
    """A failsafe condition: the parameter choosing its action and the text PX4 reports."""

    action_param: str
    text: str


DATA_LINK_LOST = Condition("NAV_DLL_ACT", "Connection to ground station lost")
MANUAL_CONTROL_LOST = Condition("NAV_RCL_ACT", "Manual control lost")


class OffboardLossAction(IntEnum):
    """COM_OBL_RC_ACT values (failsafe.cpp ``fromOffboardLossActParam``)."""

    POSITION = 0
    ALTITUDE = 1
    MANUAL = 2
    RETURN = 3
    LAND = 4
    HOLD = 5
    TERMINATE = 6
    DISARM = 7


#: COM_OBL_RC_ACT → the nav state of the fallback (terminate / disarm are not nav states)
OFFBOARD_LOSS_NAV_STATE: dict[int, NavState] = {
    OffboardLossAction.POSITION: NavState.POSCTL,
    OffboardLossAction.ALTITUDE: NavState.ALTCTL,
    OffboardLossAction.MANUAL: NavState.STAB,
    OffboardLossAction.RETURN: NavState.AUTO_RTL,
    OffboardLossAction.LAND: NavState.AUTO_LAND,
    OffboardLossAction.HOLD: NavState.AUTO_LOITER,
}

#: failsafe_action_t names PX4's events use ("switching to Hold")
NAV_STATE_NAME: dict[NavState, str] = {
    NavState.POSCTL: "Position",
    NavState.ALTCTL: "Altitude",
    NavState.STAB: "Stabilized",
    NavState.AUTO_RTL: "Return",
    NavState.AUTO_LAND: "Land",
    NavState.AUTO_LOITER: "Hold",
}


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


POSITION_LOST = Condition("COM_POSCTL_NAVL", "Position estimate lost")

#: battery warning level → the STATUSTEXT severity name and text PX4 sends
BATTERY_TEXT: dict[int, tuple[str, str]] = {
    1: ("WARNING", "Low battery level, return advised"),
    2: ("CRITICAL", "Critical battery level, land now"),
    3: ("EMERGENCY", "Emergency battery level, land immediately"),
}


def battery_action(com_low_bat_act: int, warning: int) -> NavAction:
    """``Failsafe::fromBatteryWarningActParam``: low warns; critical / emergency per COM_LOW_BAT_ACT."""
    if warning == 2:
        return {1: NavAction.RETURN, 3: NavAction.RETURN, 2: NavAction.LAND}.get(
            com_low_bat_act, NavAction.WARN
        )
    if warning == 3:
        return {1: NavAction.RETURN, 3: NavAction.LAND, 2: NavAction.LAND}.get(
            com_low_bat_act, NavAction.WARN
        )
    return NavAction.WARN if warning == 1 else NavAction.DISABLED


def actuator_failure_action(com_act_fail_act: int) -> NavAction:
    """``Failsafe::fromActuatorFailureActParam``: 0 warn, 1 hold, 2 land, 3 return, 4 terminate."""
    return {1: NavAction.HOLD, 2: NavAction.LAND, 3: NavAction.RETURN, 4: NavAction.TERMINATE}.get(
        com_act_fail_act, NavAction.WARN
    )
