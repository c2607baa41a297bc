"""Failsafes as data (PX4 ``commander/failsafe/failsafe.cpp``): conditions, and what each action does.

NAV_DLL_ACT (data link lost) and NAV_RCL_ACT (manual control lost) choose an action
(``fromNavDllOrRclActParam``: 1 hold, 2 return, 3 land, 5 terminate, 6 disarm / lockdown);
COM_LOW_BAT_ACT chooses the battery action per warning level (``fromBatteryWarningActParam``);
COM_ACT_FAIL_ACT the motor-failure action (``fromActuatorFailureActParam``). The table
``ACTION_NAV_STATE`` says which nav state an action switches to; termination cuts the motors,
disarm disarms in the air.

``FailsafeFramework`` is the part of PX4's ``FailsafeBase`` (``failsafe/framework.cpp``) these
actions go through: the worst action wins, and with ``COM_FAIL_ACT_T`` > 0.1 s a new Hold,
Return or Land is preceded by that long in Hold (the vehicle reports Hold, the user's mode is
kept), unless a failsafe beyond Hold is already active; a mode change by the user during the
hold or after it takes over; the condition clearing removes a Hold or Land at once, a Return
only at the next mode change (``ClearCondition::OnModeChangeOrDisarm``). Disarm and
terminate act at once, outside it.

Texts: the condition's text ("Manual control lost", "Connection to ground station lost"), then
``notify_texts``: PX4's event text (``notifyUser``; the built-in vehicle has no MAVLink events, so
it goes out as a STATUSTEXT, as the battery warnings do) and PX4's STATUSTEXT, "Failsafe
activated: entering Hold for N seconds" before a delayed action, "Failsafe activated" when it acts.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from uavtest.px4.modes import NavState
from uavtest.sitl.mav import MavSeverity

__all__ = [
    "ACTION_NAV_STATE",
    "ACTION_TEXT",
    "BATTERY_CAUSE",
    "BATTERY_TEXT",
    "CAUSE_TEXT",
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
    "Cause",
    "Condition",
    "FailsafeFramework",
    "GeofenceAction",
    "NavAction",
    "OffboardLossAction",
    "Selected",
    "actuator_failure_action",
    "battery_action",
    "notify_texts",
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


class Cause(IntEnum):
    """Why a failsafe acts (framework.h ``Cause``, events ``failsafe_cause_t``)."""

    GENERIC = 0
    MANUAL_CONTROL_LOSS = 1
    GCS_CONNECTION_LOSS = 2
    BATTERY_LOW = 3
    BATTERY_CRITICAL = 4
    BATTERY_EMERGENCY = 5


#: failsafe_cause_t descriptions (src/lib/events/enums.json): the start of PX4's event texts
CAUSE_TEXT: dict[Cause, str] = {
    Cause.MANUAL_CONTROL_LOSS: "Manual control loss",
    Cause.GCS_CONNECTION_LOSS: "GCS connection loss",
    Cause.BATTERY_LOW: "Low battery level",
    Cause.BATTERY_CRITICAL: "Critical battery level",
    Cause.BATTERY_EMERGENCY: "Emergency battery level",
}
#: failsafe_action_t descriptions (enums.json): what PX4's event texts say the vehicle switches to
ACTION_TEXT: dict[int, str] = {
    NavAction.HOLD: "Hold",
    NavAction.RETURN: "RTL",
    NavAction.LAND: "Land",
    NavAction.DESCEND: "Descend",
    NavAction.DISARM: "disarm",
    NavAction.TERMINATE: "terminate",
}


@dataclass(frozen=True, slots=True)
class Condition:
    """A failsafe condition: the parameter choosing its action, the text PX4 reports, its cause."""

    action_param: str
    text: str
    cause: Cause = Cause.GENERIC


DATA_LINK_LOST = Condition("NAV_DLL_ACT", "Connection to ground station lost", Cause.GCS_CONNECTION_LOSS)
MANUAL_CONTROL_LOST = Condition("NAV_RCL_ACT", "Manual control lost", Cause.MANUAL_CONTROL_LOSS)


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

#: battery warning level → the severity name and text PX4 sends when it only warns
BATTERY_TEXT: dict[int, tuple[str, str]] = {
    1: ("WARNING", "Low battery level, return advised"),
    2: ("CRITICAL", "Critical battery level, land now"),
    3: ("EMERGENCY", "Emergency battery level, land immediately"),
}
#: battery warning level → the failsafe's cause (fromBatteryWarningActParam)
BATTERY_CAUSE: dict[int, Cause] = {
    1: Cause.BATTERY_LOW,
    2: Cause.BATTERY_CRITICAL,
    3: Cause.BATTERY_EMERGENCY,
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


# ---------------------------------------------------------------- the framework (framework.cpp)

#: framework.h ``Action`` order: a later action takes precedence over an earlier one
_RANK: dict[int, int] = {
    NavAction.DISABLED: 0,
    NavAction.WARN: 1,
    NavAction.HOLD: 5,
    NavAction.RETURN: 6,
    NavAction.LAND: 7,
    NavAction.DESCEND: 8,
    NavAction.DISARM: 9,
    NavAction.TERMINATE: 10,
}
#: ``actionAllowsUserTakeover``: the actions a mode change by the user ends
_TAKEOVER_ACTIONS = frozenset({NavAction.HOLD, NavAction.RETURN, NavAction.LAND, NavAction.DESCEND})


@dataclass(slots=True)
class _Action:
    """One of FailsafeBase's ``_actions``: what a condition asks for while it holds."""

    action: NavAction
    cause: Cause
    #: ``ClearCondition::OnModeChangeOrDisarm``: kept after the condition clears, until a mode
    #: change (else ``WhenConditionClears``: removed with the condition)
    sticky: bool
    #: ``UserTakeoverAllowed::Auto`` as ``addAction`` resolves it: ``Always`` (sticks may take
    #: over once the delay is over) with COM_FAIL_ACT_T > 0.1 s, else ``AlwaysModeSwitchOnly``
    sticks_allowed: bool = True
    failing: bool = True


@dataclass(frozen=True, slots=True)
class Selected:
    """``SelectedActionState``: what the vehicle does, the action a Hold delays, and why."""

    action: NavAction = NavAction.DISABLED  # DISABLED: nothing (PX4's Action::None)
    delayed: NavAction = NavAction.DISABLED
    cause: Cause = Cause.GENERIC


NOTHING = Selected()


class FailsafeFramework:
    """PX4's ``FailsafeBase`` (failsafe/framework.cpp) for the actions whose user takeover is
    ``Auto``: data link and manual control loss (Hold, Return, Land), the battery warnings and a
    motor failure (Hold, Return, Land, Warn).

    Conditions are reported as they change (``add`` / ``clear``); ``update`` runs once per
    commander tick and says what is selected now. With ``COM_FAIL_ACT_T`` > 0.1 s the first such
    action starts the delay (``_current_delay``) from ``start_delay_us`` (``_current_start_delay``,
    which runs down while a delay holds and recovers at a quarter of the time otherwise, so a
    toggling condition still acts); while it runs the selected action is Hold and the action
    waits (``getSelectedAction``). It is cleared when a failsafe beyond Hold is already active or
    the user took over (``clearDelayIfNeeded``).
    """

    def __init__(self, fail_act_t: float) -> None:
        self.actions: dict[str, _Action] = {}
        self.delay_us = 0
        self.start_delay_us = round(fail_act_t * 1e6)
        self.selected = NOTHING
        self.takeover = False  # _user_takeover_active
        self._warn_added = False  # _notification_required
        self._delay_requested = False  # an action was added: start the delay in the next update
        self._last_us: int | None = None

    def params_updated(self, fail_act_t: float) -> None:
        """``updateParams`` (any parameter change): the start delay is COM_FAIL_ACT_T again."""
        self.start_delay_us = round(fail_act_t * 1e6)

    def add(self, key: str, action: NavAction, cause: Cause, *, sticky: bool, fail_act_t: float) -> None:
        """``checkFailsafe`` as the condition ``key`` starts to hold: add its action (an action
        already there only takes the new value, as PX4 keeps the rest)."""
        entry = self.actions.get(key)
        if entry is not None:
            entry.action, entry.failing = action, True
            return
        self.actions[key] = _Action(action, cause, sticky, sticks_allowed=fail_act_t > 0.1)
        if fail_act_t > 0.1 and action != NavAction.WARN:
            self._delay_requested = True  # UserTakeoverAllowed::Auto with a delay
        if action == NavAction.WARN:
            self._warn_added = True
        if _RANK[action] >= _RANK[NavAction.HOLD]:
            self.takeover = False

    def clear(self, key: str) -> None:
        """``checkFailsafe`` as the condition stops holding (``removeAction``)."""
        entry = self.actions.get(key)
        if entry is None:
            return
        if entry.sticky:
            entry.failing = False
        else:
            del self.actions[key]

    def mode_change(self) -> None:
        """The user asked for a mode (``user_intended_mode_updated``): actions whose condition
        cleared and that wait for a mode change go (``removeActions``); a selected Hold, Return,
        Land or Descend (the delay's Hold too) gives way to the user's mode (user takeover)."""
        for key in [k for k, a in self.actions.items() if a.sticky and not a.failing]:
            del self.actions[key]
        if self.actions and self.selected.action in _TAKEOVER_ACTIONS:
            self.takeover = True

    def sticks_takeover(self) -> bool:
        """``rc_sticks_takeover_request`` (the commander saw the sticks move in a failsafe):
        ``getSelectedAction`` lets the user take over a Hold, Return, Land or Descend when every
        active action allows it by sticks (``UserTakeoverAllowed::Always``) and the delay's Hold
        is not running (that Hold is ``AlwaysModeSwitchOnly``). The actions are those left after
        this sample's conditions cleared (manual control regained), as the request is handled in
        the next framework update. True when taken over; the user's mode becomes Position (the
        commander changes it)."""
        worst = max(self.actions.values(), key=lambda a: _RANK[a.action], default=None)
        if worst is None or worst.action not in _TAKEOVER_ACTIONS or self.delay_us > 0:
            return False
        if not all(a.sticks_allowed for a in self.actions.values()):
            return False
        self.takeover = True
        return True

    def reset(self) -> None:
        """Arming or disarming: no action carries over (the built-in vehicle reports conditions
        as they change in the air, and checks them afresh after arming)."""
        self.actions.clear()
        self.selected = NOTHING
        self.takeover = False
        self._warn_added = self._delay_requested = False

    def update(self, now_us: int, fail_act_t: float, user_mode: NavState, beyond_hold: bool) -> bool:
        """``FailsafeBase::update``: select the action for now (``selected``); True when PX4
        notifies the user (a worse action, or a new warning). ``beyond_hold``: a failsafe worse
        than Hold is active outside the framework (geofence, position loss)."""
        dt = 0 if self._last_us is None else now_us - self._last_us
        self._last_us = now_us
        configured_us = round(fail_act_t * 1e6)
        if (
            not self.actions
            and self.selected is NOTHING
            and self.delay_us == 0
            and self.start_delay_us == configured_us
        ):
            return False  # nothing to select, nothing to count down
        self.delay_us = max(0, self.delay_us - dt)  # updateDelay
        if self._delay_requested:
            self._delay_requested = False
            if self.delay_us == 0:
                self.delay_us = self.start_delay_us
        previous = self.selected
        if _RANK[previous.action] > _RANK[NavAction.HOLD] or beyond_hold or self.takeover:
            self.delay_us = 0  # clearDelayIfNeeded
        selected = self._select(user_mode)
        # updateStartDelay
        if selected.delayed != NavAction.DISABLED:
            self.start_delay_us = max(0, self.start_delay_us - dt)
        else:
            self.start_delay_us = min(configured_us, self.start_delay_us + dt // 4)
        notify = _RANK[selected.action] > _RANK[previous.action] or (
            selected.action != NavAction.DISABLED and self._warn_added
        )
        self._warn_added = False
        self.selected = selected
        return notify

    def _select(self, user_mode: NavState) -> Selected:
        """``getSelectedAction``: the worst action; Hold while the delay runs; Warn once the user
        took over; Return while the user lands is only a warning."""
        worst: _Action | None = None
        for a in self.actions.values():
            if worst is None or _RANK[a.action] > _RANK[worst.action]:
                worst = a
        if worst is None:
            self.takeover = False
            return NOTHING
        action, delayed = worst.action, NavAction.DISABLED
        if self.delay_us > 0 and not self.takeover and action not in (NavAction.DISARM, NavAction.TERMINATE):
            action, delayed = NavAction.HOLD, action
        if self.takeover and action in _TAKEOVER_ACTIONS:
            action, delayed = NavAction.WARN, NavAction.DISABLED
        else:
            self.takeover = False
        if user_mode == NavState.AUTO_LAND and NavAction.RETURN in (action, delayed):
            action, delayed = NavAction.WARN, NavAction.DISABLED  # already landing: no Return
        return Selected(action, delayed, worst.cause)


def notify_texts(selected: Selected, delay_us: int) -> list[tuple[MavSeverity, str]]:
    """``FailsafeBase::notifyUser``: the event's text, then the STATUSTEXT PX4 sends.

    The delay is said in whole seconds, rounded (``(_current_delay + 500 ms) / 1 s``).
    """
    cause = CAUSE_TEXT.get(selected.cause)
    crit = MavSeverity.CRITICAL
    if selected.action == NavAction.HOLD and selected.delayed != NavAction.DISABLED:
        seconds = (delay_us + 500_000) // 1_000_000
        name = ACTION_TEXT[selected.delayed]
        start = cause if cause is not None else "Failsafe activated"
        return [
            (crit, f"{start}: switching to {name} in {seconds} seconds"),
            (crit, f"Failsafe activated: entering Hold for {seconds} seconds"),
        ]
    texts: list[tuple[MavSeverity, str]] = []
    if selected.action == NavAction.WARN:
        level = {c: lvl for lvl, c in BATTERY_CAUSE.items()}.get(selected.cause)
        if level is not None:
            severity, text = BATTERY_TEXT[level]
            texts.append((MavSeverity[severity], text))
        elif cause is not None:
            texts.append((MavSeverity.WARNING, f"Failsafe warning: {cause}"))
        # generic: "Failsafe warning:" followed by the health report, not modelled
    elif cause is None:
        texts.append(
            (crit, f"Failsafe activated: Autopilot disengaged, switching to {ACTION_TEXT[selected.action]}")
        )
    else:
        texts.append((crit, f"{cause}: switching to {ACTION_TEXT[selected.action]}"))
    texts.append((crit, "Failsafe activated"))
    return texts
