"""Which modes can run and which can arm: PX4 v1.15's mode requirements.

``ModeUtil/mode_requirements.cpp`` lists what each nav state needs (an attitude, a local or global
position, manual control, a mission, an offboard signal, home, ...); the health and arming checks
(``HealthAndArmingChecks/checks/modeCheck.cpp``) clear a mode's *can run* and *can arm* bits when
something it needs is missing. Commander then:

- refuses a user's mode change while armed into a mode that cannot run
  (``UserModeIntention::change``: TEMPORARILY_REJECTED, "Switching to <mode> is currently not
  available"); while disarmed every change is allowed;
- refuses to arm in a mode that cannot arm ("Arming denied: Resolve system health failures
  first"), and in a mode that prevents arming (Return, Land, Descend, Orbit, ...: "Mode not
  suitable for arming").

Manual control ("No manual control input") clears can run and can arm of the stick modes but is
reported as a failure only with ``COM_RC_IN_MODE`` 4. A mission that is missing clears the can
arm bits of every mode with ``COM_ARM_MIS_REQ``, can run only of Mission.

What this vehicle's estimator never loses (angular velocity, attitude, altitude) and what it does
not model (wind and flight-time limits, external modes) is left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Flag, auto

from uavtest.px4.modes import NavState

__all__ = [
    "MODE_NAMES",
    "ModeFlags",
    "Need",
    "arm_blockers",
    "can_arm",
    "can_run",
    "missing",
    "prevents_arming",
]


class Need(Flag):
    """failsafe_flags.mode_req_*: what a nav state needs."""

    NONE = 0
    LOCAL_POSITION = auto()
    LOCAL_POSITION_RELAXED = auto()
    GLOBAL_POSITION = auto()
    MISSION = auto()
    OFFBOARD_SIGNAL = auto()
    HOME_POSITION = auto()
    MANUAL_CONTROL = auto()
    PREVENT_ARMING = auto()


_N = Need
#: mode_requirements.cpp getModeRequirements, multicopter (less the attitude, angular velocity,
#: altitude and wind/flight-time entries: see the module's docstring)
REQUIREMENTS: dict[NavState, Need] = {
    NavState.MANUAL: _N.MANUAL_CONTROL,
    NavState.ALTCTL: _N.MANUAL_CONTROL,
    NavState.POSCTL: _N.LOCAL_POSITION_RELAXED | _N.MANUAL_CONTROL,
    NavState.AUTO_MISSION: _N.LOCAL_POSITION | _N.GLOBAL_POSITION | _N.MISSION,
    NavState.AUTO_LOITER: _N.LOCAL_POSITION | _N.GLOBAL_POSITION,
    NavState.AUTO_RTL: _N.LOCAL_POSITION | _N.GLOBAL_POSITION | _N.HOME_POSITION | _N.PREVENT_ARMING,
    NavState.ACRO: _N.MANUAL_CONTROL,
    NavState.DESCEND: _N.PREVENT_ARMING,
    NavState.TERMINATION: _N.PREVENT_ARMING,
    NavState.OFFBOARD: _N.OFFBOARD_SIGNAL,
    NavState.STAB: _N.MANUAL_CONTROL,
    NavState.AUTO_TAKEOFF: _N.LOCAL_POSITION,
    NavState.AUTO_LAND: _N.LOCAL_POSITION | _N.PREVENT_ARMING,
    NavState.AUTO_FOLLOW_TARGET: _N.LOCAL_POSITION | _N.PREVENT_ARMING,
    NavState.AUTO_PRECLAND: _N.LOCAL_POSITION | _N.PREVENT_ARMING,
    NavState.ORBIT: _N.LOCAL_POSITION | _N.PREVENT_ARMING,
}

#: src/lib/modes/ui.hpp nav_state_names: the mode in "Switching to <mode> is currently not available"
MODE_NAMES: dict[NavState, str] = {
    NavState.MANUAL: "Manual",
    NavState.ALTCTL: "Altitude",
    NavState.POSCTL: "Position",
    NavState.AUTO_MISSION: "Mission",
    NavState.AUTO_LOITER: "Hold",
    NavState.AUTO_RTL: "Return",
    NavState.ACRO: "Acro",
    NavState.DESCEND: "Descend",
    NavState.TERMINATION: "Termination",
    NavState.OFFBOARD: "Offboard",
    NavState.STAB: "Stabilized",
    NavState.AUTO_TAKEOFF: "Takeoff",
    NavState.AUTO_LAND: "Land",
    NavState.AUTO_FOLLOW_TARGET: "Follow Target",
    NavState.AUTO_PRECLAND: "Precision Landing",
    NavState.ORBIT: "Orbit",
}


@dataclass(frozen=True, slots=True)
class ModeFlags:
    """The failsafe_flags the mode checks read: what is missing right now."""

    manual_control_lost: bool = False  # manual_control_signal_lost (also: never seen)
    position_invalid: bool = False  # local_position_invalid(_relaxed), global_position_invalid
    mission_missing: bool = False  # auto_mission_missing
    offboard_signal_lost: bool = False  # offboard_control_signal_lost
    home_invalid: bool = False  # home_position_invalid
    arm_needs_mission: bool = False  # COM_ARM_MIS_REQ: no arming in any mode without a mission

    def failing(self) -> Need:
        """The requirements that cannot be met."""
        out = Need.NONE
        if self.manual_control_lost:
            out |= Need.MANUAL_CONTROL
        if self.position_invalid:
            out |= Need.LOCAL_POSITION | Need.LOCAL_POSITION_RELAXED | Need.GLOBAL_POSITION
        if self.mission_missing:
            out |= Need.MISSION
        if self.offboard_signal_lost:
            out |= Need.OFFBOARD_SIGNAL
        if self.home_invalid:
            out |= Need.HOME_POSITION
        return out


def missing(ns: NavState, flags: ModeFlags) -> Need:
    """What ``ns`` needs and does not have (its can-run bit is clear when not NONE)."""
    return REQUIREMENTS.get(ns, Need.NONE) & flags.failing()


def can_run(ns: NavState, flags: ModeFlags) -> bool:
    """HealthAndArmingChecks::canRun: ``ns`` may be switched to while armed."""
    return missing(ns, flags) == Need.NONE


def prevents_arming(ns: NavState) -> bool:
    """modePreventsArming: Return, Land, Descend, Orbit, ... (ModeChecks::checkArmingRequirement)."""
    return bool(REQUIREMENTS.get(ns, Need.NONE) & Need.PREVENT_ARMING)


def arm_blockers(ns: NavState, flags: ModeFlags) -> Need:
    """What keeps ``ns`` from arming (its can-arm bit clear): a missing requirement, or any
    mission missing under ``COM_ARM_MIS_REQ`` (NONE: it may arm). The prevent-arming rule is
    separate (``prevents_arming``)."""
    out = missing(ns, flags)
    if flags.arm_needs_mission and flags.mission_missing:
        out |= Need.MISSION
    return out


def can_arm(ns: NavState, flags: ModeFlags) -> bool:
    """Report::canArm for the current nav state."""
    return not prevents_arming(ns) and arm_blockers(ns, flags) == Need.NONE
