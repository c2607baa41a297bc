"""The commander's state machine (PX4 ``Commander``): readiness, arming, nav state, failsafes.

Fed once per 50 Hz tick (``update``) after the land detector; ``arm`` / ``disarm`` /
``set_mode`` / ``switch`` are what commands and failsafes call. It publishes
``vehicle_status`` (``status``) and talks to the rest of the vehicle through the vehicle it
belongs to (clock, outbox of MAVLink messages and status texts, navigator events).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from uavtest.px4.modes import (
    ARMING_STATE_ARMED,
    ARMING_STATE_DISARMED,
    MANUAL_NAV_STATES,
    NavState,
)
from uavtest.sitl import mav
from uavtest.sitl.commander.arming import Reason, arming_denied
from uavtest.sitl.commander.failsafe import (
    ACTION_NAV_STATE,
    BATTERY_CAUSE,
    DATA_LINK_LOST,
    GEOFENCE_TEXTS,
    GF_ACTION_NAV_STATE,
    GF_DELAYED_ACTIONS,
    MANUAL_CONTROL_LOST,
    NAV_STATE_NAME,
    OFFBOARD_LOSS_NAV_STATE,
    RC_IN_MODE_DISABLED,
    RCL_EXCEPT_HOLD,
    RCL_EXCEPT_MISSION,
    RCL_EXCEPT_OFFBOARD,
    Cause,
    Condition,
    FailsafeFramework,
    GeofenceAction,
    NavAction,
    OffboardLossAction,
    Selected,
    actuator_failure_action,
    battery_action,
    notify_texts,
)
from uavtest.sitl.commander.mode_requirements import MODE_NAMES, ModeFlags, can_run, prevents_arming
from uavtest.sitl.hysteresis import Hysteresis
from uavtest.sitl.land_detector import Transition
from uavtest.sitl.mav import MavResult, MavSeverity
from uavtest.sitl.mavlink_streams import STREAMS, home_position
from uavtest.sitl.mc_pos_control import IDLE
from uavtest.sitl.uorb import HomePosition, VehicleStatus

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["READY_US", "Commander"]

READY_US = 1_500_000  # estimator converged, home set

#: the failsafe framework's action → the nav state it flies (FailsafeBase::modeFromAction)
_FRAMEWORK_NAV_STATE: dict[int, NavState] = {
    NavAction.HOLD: NavState.AUTO_LOITER,
    NavAction.RETURN: NavState.AUTO_RTL,
    NavAction.LAND: NavState.AUTO_LAND,
}
#: nav states of failsafe actions worse than Hold (clearDelayIfNeeded: no delay on top of them)
_BEYOND_HOLD = frozenset({NavState.AUTO_RTL, NavState.AUTO_LAND, NavState.DESCEND})


def _framework_flies(selected: Selected) -> bool:
    """The framework's selection puts the vehicle in a mode of its own (Hold, Return, Land)."""
    return selected.action in _FRAMEWORK_NAV_STATE


#: The nav states the built-in vehicle flies: a mode change to any other is answered
#: UNSUPPORTED with a STATUSTEXT (``vehicle_command.unsupported``). Extend it with a new mode.
FLOWN_NAV_STATES: set[NavState] = {
    NavState.MANUAL,
    NavState.STAB,
    NavState.ACRO,
    NavState.ALTCTL,
    NavState.POSCTL,
    NavState.AUTO_MISSION,
    NavState.AUTO_LOITER,
    NavState.AUTO_RTL,
    NavState.AUTO_TAKEOFF,
    NavState.AUTO_LAND,
    NavState.OFFBOARD,  # sitl/offboard.py
}


class Commander:
    def __init__(self, v: Vehicle) -> None:
        self.v = v
        self.params = v.params
        self.nav = v.nav
        self.ctrl = v.ctrl
        self.body = v.body
        self.est = v.est
        self.st = v.st
        self.land = v.land
        self.recorder = v.recorder
        self.proj = v.proj
        self.home_alt = v.home_alt
        home = v.config.home
        self.armed = False
        self.armed_at_us = 0
        self.nav_state = NavState.AUTO_LOITER
        self.user_nav_state = NavState.AUTO_LOITER
        #: UserModeIntention's _nav_state_after_disarming: the last mode the user picked that
        #: does not prevent arming; the user's mode again on disarm (``disarm``)
        self.after_disarming = NavState.AUTO_LOITER
        self.ever_had_mode_change = False  # UserModeIntention::everHadModeChange
        self.nav_state_us = 0
        self.arming_reason = 0
        self.disarming_reason = 0
        self.crashed = False
        self.crash_obstacle: int | None = None
        self.failsafe = False
        self.gcs_lost = False
        self.ready = False
        self.home_set = False
        self.home = (0.0, 0.0, 0.0, home.lat, home.lon, home.alt, 0.0)
        self._home_count = 0
        self._last_gcs_us: int | None = None
        self.sticks = (0.0, 0.0, 0.5, 0.0)
        self._sticks_us: int | None = None
        self._offboard_lost = False  # the offboard-loss fallback is active
        self.rc_lost = False  # manual_control_signal_lost (after sticks were seen)
        self._mission_failing = False  # failsafe_flags.mission_failure while the user wants Mission
        self._rc_lost_at_arming = True
        self.battery_warning = 0  # failsafe_flags.battery_warning: only rises while armed
        self._pos_invalid_us: int | None = None
        self.position_fallback = False  # in a mode fallback for lack of position
        self._fd_bits = 0
        self.close_log = False  # the log closes after this tick (disarmed)
        self.status_dirty = True  # vehicle_status changed: log it now, not at the next 1 Hz slot
        self._gf_active = False  # a geofence breach has been acted on (until it clears)
        self._gf_pending: tuple[NavState, int] | None = None  # GF action after COM_FAIL_ACT_T hold
        #: the nav state the geofence action flies (until the user picks a mode), and whether
        #: sticks may take it over (fromGfActParam: only Return / Land after their delay)
        self._gf_flying: NavState | None = None
        self._gf_sticks = False
        #: data link, manual control, battery and motor failsafes (FailsafeBase: COM_FAIL_ACT_T)
        self._fw = FailsafeFramework(self.params["COM_FAIL_ACT_T"])
        self._taken_off = False  # _have_taken_off_since_arming
        self._auto_disarm_landed = Hysteresis(False)

    @property
    def home_count(self) -> int:
        return self._home_count

    def params_updated(self) -> None:
        """A parameter changed (Commander.cpp ``updateParameters``, FailsafeBase ``updateParams``)."""
        self._fw.params_updated(self.params["COM_FAIL_ACT_T"])

    def gcs_heartbeat(self, t: int) -> None:
        self._last_gcs_us = t
        if self.gcs_lost:
            self.gcs_lost = False
            self.v.text(MavSeverity.INFO, "Data link regained")
            self._fw.clear(DATA_LINK_LOST.action_param)

    def manual_control(self, t: int, sticks: tuple[float, float, float, float], moving: bool = False) -> None:
        """A MANUAL_CONTROL sample (x, y, z, r scaled to [-1, 1] / [0, 1]); ``moving``: the
        ManualControl module's ``sticks_moving`` (``manual_control.StickMovement``)."""
        if int(self.params["COM_RC_IN_MODE"]) in (0, RC_IN_MODE_DISABLED):
            return  # 0: RC transmitter only (MAVLink sticks unused); 4: stick input disabled
        self.sticks = sticks
        self._sticks_us = t
        self._rc_lost_at_arming = False  # sticks present: the RC-loss failsafe applies again
        if self.rc_lost:
            self.rc_lost = False
            self.v.text(MavSeverity.INFO, "Manual control regained")
            self._fw.clear(MANUAL_CONTROL_LOST.action_param)
        if moving:
            self._stick_override(t)
        if not self.armed and not self.ever_had_mode_change:
            # manualControlCheck, disarmed: "if there's never been a mode change force position
            # control as initial state" (MAVLink sticks)
            self.intend(NavState.POSCTL)
            self.switch(NavState.POSCTL, t)

    def _stick_override(self, t: int) -> None:
        """Commander.cpp ``manualControlCheck``: armed, sticks moving, in a mode the sticks do not
        fly (auto or offboard; not Orbit, whose control mode is neither), and ``COM_RC_OVERRIDE``
        enables it for that mode (bit 0 auto, bit 1 offboard) → the pilot takes over in Position
        mode ("Pilot took over using sticks"); with no position, in Altitude mode
        (``UserModeIntention::change`` with fallback). In a failsafe the request goes to the
        framework (``_failsafe_user_override_request``), which allows it only where PX4's
        ``UserTakeoverAllowed`` is ``Always``: a data link / manual control / battery / motor /
        mission failsafe once its COM_FAIL_ACT_T Hold is over (COM_FAIL_ACT_T > 0.1 s), a
        geofence Return or Land likewise, a position-loss Descend and an offboard-loss Hold,
        Return or Land; a geofence Hold never (mode switch only)."""
        ns = self.nav_state
        if not self.armed or self.crashed or ns in MANUAL_NAV_STATES or ns == NavState.ORBIT:
            return
        bit = 2 if ns == NavState.OFFBOARD else 1  # RcOverrideBits: OFFBOARD_MODE_BIT, AUTO_MODE_BIT
        if not int(self.params["COM_RC_OVERRIDE"]) & bit:
            return
        if not self.failsafe:  # _failsafe.selectedAction() <= Warn: change the user's mode
            valid = not self.v.sim.faulty or self.v.gps.position_valid(t, self.params["EKF2_NOAID_TOUT"])
            self.v.text(MavSeverity.INFO, "Pilot took over using sticks")
            self.set_mode(NavState.POSCTL if valid else NavState.ALTCTL, announce=False)
            return
        if self.position_fallback:  # Descend: the user's mode becomes Position, which falls back
            self.v.text(MavSeverity.INFO, "Pilot took over using sticks")
            self.user_mode_change()
            self.intend(NavState.POSCTL)
            navl = int(self.params["COM_POSCTL_NAVL"])
            self.switch(NavState.ALTCTL if navl == 0 else NavState.DESCEND, t)
            return
        if self._offboard_lost:
            allowed = True
        elif self._gf_flying is not None and ns == self._gf_flying:
            allowed = self._gf_sticks
        elif _framework_flies(self._fw.selected):
            allowed = self._fw.sticks_takeover()
        else:
            allowed = False
        if allowed:
            self.v.text(MavSeverity.INFO, "Pilot took over using sticks")
            self.set_mode(NavState.POSCTL, announce=False)

    def status(self, t: int) -> VehicleStatus:
        land = self.land
        return VehicleStatus(
            t,
            self.armed_at_us if self.armed else 0,
            land.takeoff_us if not land.landed else 0,
            self.nav_state_us,
            ARMING_STATE_ARMED if self.armed else ARMING_STATE_DISARMED,
            self.arming_reason,
            self.disarming_reason,
            int(self.user_nav_state),
            int(self.nav_state),
            (4 if self.crashed else 0) | self.v.failure_detector.status_bits,
            0,
            1,
            self.failsafe,
            self.gcs_lost,
            mav.MAV_TYPE_QUADROTOR,
            mav.SYSTEM_ID,
            mav.COMPONENT_ID,
            self.ready,
        )

    def update(self, t: int) -> None:
        if not self.ready and t >= READY_US:
            self.ready = True
            self.set_home(t)
            self.v.text(MavSeverity.INFO, "Ready for takeoff!")
        land = self.land
        transition = land.update(t, self.armed, self.body, self.v.goal.kind)
        if transition is not None:
            self.status_dirty = True
            if transition is Transition.TAKEOFF:
                self._taken_off = True
                self.v.text(MavSeverity.INFO, "Takeoff detected")
            elif transition is Transition.LANDED:
                self.v.text(MavSeverity.INFO, "Landing detected")
        if self.st.landed != land.landed:  # tell clients at once, not at the next 2 Hz slot
            self.st.landed = land.landed
            self.v._out.append(STREAMS["EXTENDED_SYS_STATE"](self.v, t))
        if not self.armed:
            self._manual_control_lost(t)
            return
        if self.crashed:
            if self.body.on_ground:
                self.disarm(t, Reason.FAILURE_DETECTOR, "Disarmed after crash")
            return
        if self.user_nav_state == NavState.OFFBOARD and self._offboard_loss(t):
            return
        self._auto_disarm(t)
        if not self.armed:
            return
        if not land.landed:
            self._check_failsafes(t)
        self._failsafe_update(t)

    def _auto_disarm(self, t: int) -> None:
        """Commander.cpp ``handleAutoDisarm``: after a takeoff, landed for COM_DISARM_LAND seconds
        (<= 0: never) → "Disarmed by landing"; never taken off, armed for COM_DISARM_PRFLT seconds
        → "Disarmed by auto preflight disarming". A landing in Mission mode counts only once the
        mission is finished (``landed_amid_mission``): its time starts then, not at the landing."""
        p = self.params
        land_s, preflight_s = p["COM_DISARM_LAND"], p["COM_DISARM_PRFLT"]
        if land_s <= 0 and preflight_s <= 0:
            return
        hyst = self._auto_disarm_landed
        landed_amid_mission = self.nav_state == NavState.AUTO_MISSION and not self.nav.finished
        if land_s > 0 and not landed_amid_mission and self._taken_off:
            hyst.set_hysteresis_time_from(False, round(land_s * 1e6))
            hyst.set_state_and_update(self.land.landed, t)
        elif preflight_s > 0 and not self._taken_off:
            hyst.set_hysteresis_time_from(False, round(preflight_s * 1e6))
            hyst.set_state_and_update(True, t)
        if hyst.state:
            if self._taken_off:
                self.disarm(t, Reason.AUTO_DISARM_LAND, "Disarmed by landing")
            else:
                self.disarm(t, Reason.AUTO_DISARM_PREFLIGHT, "Disarmed by auto preflight disarming")

    def mission_finished(self, t: int) -> None:
        """Commander.cpp ``checkForMissionUpdate``: a mission finished in the air while in
        Mission mode → the user's mode becomes Hold (the navigator loiters where it ended)."""
        if self.armed and not self.land.landed and self.nav_state == NavState.AUTO_MISSION:
            self._fw.mode_change()
            self.intend(NavState.AUTO_LOITER)
            self.switch(NavState.AUTO_LOITER, t)

    def _check_mission_failure(self, t: int) -> None:
        """failsafe.cpp ``checkStateAndMode``: while the user wants Mission and the navigator
        reports ``mission_result.failure`` (a forced heading not reached in MIS_YAW_TMT), Return,
        through the framework (COM_FAIL_ACT_T in Hold first); ``MissionChecks`` says "Mission
        cannot be completed". The condition clears with the failure (a new mission) or when the
        user picks another mode."""
        failing = self.nav.failure and self.user_nav_state == NavState.AUTO_MISSION
        if failing == self._mission_failing:
            return
        self._mission_failing = failing
        if failing:
            self.v.text(MavSeverity.CRITICAL, "Mission cannot be completed")
            self._framework_add("mission_failure", NavAction.RETURN, Cause.GENERIC, sticky=False)
        else:
            self._fw.clear("mission_failure")

    def _manual_control_lost(self, t: int) -> bool:
        """manual_control_signal_lost rises now: sticks seen, none for COM_RC_LOSS_T (tracked
        armed or not, as PX4's RC check does: arming then knows the sticks are gone)."""
        if self.rc_lost or self._sticks_us is None:
            return False
        if t - self._sticks_us <= max(self.params["COM_RC_LOSS_T"], 0.1) * 1e6:
            return False
        self.rc_lost = True
        return True

    def _check_failsafes(self, t: int) -> None:
        """Failsafes in the air (failsafe.cpp ``checkStateAndMode``): data link, manual control,
        position (battery and failure detector: ``monitor``)."""
        p = self.params
        if (
            int(p[DATA_LINK_LOST.action_param]) > 0
            and self._last_gcs_us is not None
            and not self.gcs_lost
            and t - self._last_gcs_us > p["COM_DL_LOSS_T"] * 1e6
            and self.user_nav_state != NavState.AUTO_LAND  # gcs_connection_loss_ignored
        ):
            self.gcs_lost = True
            self._failsafe(DATA_LINK_LOST, t)
        if self._manual_control_lost(t) and not self._rc_loss_ignored():
            self._failsafe(MANUAL_CONTROL_LOST, t)
        self._check_mission_failure(t)
        if self.v.sim.faulty:
            self._check_position(t)
        self._check_geofence(t)

    def _check_geofence(self, t: int) -> None:
        """GF_ACTION on a breach the navigator reported (failsafe.cpp checkStateAndMode
        ``geofence_breached`` with fromGfActParam; texts from geofenceCheck.cpp and
        framework.cpp notifyUser). Acts once per breach; Return / Land hold COM_FAIL_ACT_T first."""
        pending = self._gf_pending
        if pending is not None:
            if self.nav_state != NavState.AUTO_LOITER:
                self._gf_pending = None  # the user switched modes during the hold
            elif t >= pending[1]:
                self._gf_pending = None
                self.v.text(MavSeverity.CRITICAL, "Failsafe activated")
                self._gf_flying, self._gf_sticks = pending[0], True  # Auto → Always after the hold
                self.switch(pending[0], t)
        gf = self.nav.geofence
        if not (gf.max_dist or gf.max_alt or gf.custom):
            self._gf_active = False
            return
        action = int(self.params["GF_ACTION"])
        if self._gf_active or action == GeofenceAction.NONE:
            return
        self._gf_active = True
        for flag, text in GEOFENCE_TEXTS:
            if getattr(gf, flag):
                self.v.text(MavSeverity.CRITICAL, text)
        if action == GeofenceAction.TERMINATE:
            self.failsafe = True
            self.v.text(MavSeverity.CRITICAL, "Failsafe activated")
            self.body.motors = False
            self.crashed = True
            return
        target = GF_ACTION_NAV_STATE.get(action)
        if target is None:  # Warn (and values PX4 maps to Warn)
            self.v.text(MavSeverity.CRITICAL, "Failsafe activated")
            return
        self.failsafe = True
        delay = self.params["COM_FAIL_ACT_T"]
        if action in GF_DELAYED_ACTIONS and delay > 0.1:
            self.v.text(
                MavSeverity.CRITICAL, f"Failsafe activated: entering Hold for {int(delay + 0.5)} seconds"
            )
            self._gf_flying, self._gf_sticks = NavState.AUTO_LOITER, False
            self.switch(NavState.AUTO_LOITER, t)
            self._gf_pending = (target, t + round(delay * 1e6))
        else:
            self.v.text(MavSeverity.CRITICAL, "Failsafe activated")
            self._gf_flying, self._gf_sticks = target, False  # Hold, or no delay: mode switch only
            self.switch(target, t)

    def _offboard_loss(self, t: int) -> bool:
        """PX4 ``Failsafe::checkModeFallback``: offboard intended, signal lost → COM_OBL_RC_ACT.

        A mode fallback (failsafe.cpp ``fromOffboardLossActParam``), not latched: when setpoints
        come back the vehicle returns to OFFBOARD. Position / altitude / manual need manual
        control (MANUAL_CONTROL within COM_RC_LOSS_T), else PX4's fallback chain
        (framework.cpp ``getSelectedAction``) lands on Hold. PX4's STATUSTEXT is
        ``Failsafe activated`` (framework.cpp ``notifyUser``; the event text follows it).
        Returns True when the vehicle disarmed or terminated.
        """
        signal = self.v.offboard.signal(t)
        if signal:
            if self._offboard_lost:
                self._offboard_lost = False
                self.failsafe = False
                self.switch(NavState.OFFBOARD, t)
            return False
        if self._offboard_lost:
            return False
        self._offboard_lost = True
        act = int(self.params["COM_OBL_RC_ACT"])
        self.failsafe = True
        self.status_dirty = True
        self.v.text(MavSeverity.CRITICAL, "Failsafe activated")
        if act == OffboardLossAction.DISARM:
            self.v.text(MavSeverity.WARNING, "Autopilot disengaged, disarming")
            self.disarm(t, Reason.FAILSAFE, "Disarmed by failsafe")
            return True
        if act == OffboardLossAction.TERMINATE:
            self.v.text(MavSeverity.CRITICAL, "Failsafe: flight termination")
            self.body.motors = False
            self.crashed = True
            return True
        target = OFFBOARD_LOSS_NAV_STATE.get(act, NavState.POSCTL)
        if target in MANUAL_NAV_STATES and not (
            self._sticks_us is not None
            and t - self._sticks_us <= max(self.params["COM_RC_LOSS_T"], 0.1) * 1e6
        ):
            target = NavState.AUTO_LOITER  # no manual control: PX4's fallback chain ends in Hold
        self.v.text(MavSeverity.WARNING, f"Autopilot disengaged, switching to {NAV_STATE_NAME[target]}")
        self.switch(target, t)
        return False

    def monitor(self, t: int) -> None:
        """Battery and failure-detector failsafes, when those modules have run (5 Hz), in the air."""
        if not self.armed or self.crashed or self.land.landed:
            return
        battery = self.v.battery
        if battery.warning > self.battery_warning:  # armed: the warning only rises
            self.battery_warning = battery.warning
            self._battery_failsafe(t)
        bits = self.v.failure_detector.status_bits
        if bits != self._fd_bits:
            new, self._fd_bits = bits & ~self._fd_bits, bits
            if new & 1:
                self._attitude_failure(t)
            if new & 128:
                self.v.text(MavSeverity.CRITICAL, "Motor failure detected")
                action = actuator_failure_action(int(self.params["COM_ACT_FAIL_ACT"]))
                if action == NavAction.TERMINATE:
                    self._act(action, t)
                else:  # Warn, Hold, Return, Land: the framework (Return and Land clear on a mode change)
                    sticky = action in (NavAction.RETURN, NavAction.LAND)
                    self._framework_add("fd_motor_failure", action, Cause.GENERIC, sticky)

    def _rc_loss_ignored(self) -> bool:
        """COM_RC_IN_MODE 4, COM_RCL_EXCEPT for the user's mode, or no sticks when armed."""
        p = self.params
        if int(p["COM_RC_IN_MODE"]) == RC_IN_MODE_DISABLED or self._rc_lost_at_arming:
            return True
        exc = int(p["COM_RCL_EXCEPT"])
        mode = self.user_nav_state
        return bool(
            (mode == NavState.AUTO_MISSION and exc & RCL_EXCEPT_MISSION)
            or (mode in (NavState.AUTO_LOITER, NavState.AUTO_TAKEOFF) and exc & RCL_EXCEPT_HOLD)
            or (mode == NavState.OFFBOARD and exc & RCL_EXCEPT_OFFBOARD)
        )

    def _battery_failsafe(self, t: int) -> None:
        """failsafe.cpp: only the current warning level's check runs, so a lower level's action
        goes (not activated) as the new one comes (``fromBatteryWarningActParam``)."""
        level = self.battery_warning
        action = battery_action(int(self.params["COM_LOW_BAT_ACT"]), level)
        for lower in range(1, level):
            self._fw.clear(f"battery_warning_{lower}")
        self._framework_add(f"battery_warning_{level}", action, BATTERY_CAUSE[level], sticky=False)

    def _check_position(self, t: int) -> None:
        """Mode fallback without a position (failsafe.cpp ``checkModeFallback``): the auto modes
        cannot run → RTL → Land → Descend; position mode → altitude mode (COM_POSCTL_NAVL 0) or
        Land → Descend (1). Cleared (back to the user's mode) when the position is valid again."""
        v = self.v
        p = self.params
        if v.gps.position_valid(t, p["EKF2_NOAID_TOUT"]):
            self._pos_invalid_us = None
            if self.position_fallback:
                self.position_fallback = False
                self.failsafe = False
                self.v.text(MavSeverity.INFO, "Position estimate regained")
                self.switch(self.user_nav_state, t)
            return
        if self._pos_invalid_us is None:
            self._pos_invalid_us = t
        if self.position_fallback or t - self._pos_invalid_us < p["COM_POS_FS_DELAY"] * 1e6:
            return
        mode = self.user_nav_state
        if mode == NavState.POSCTL and int(p["COM_POSCTL_NAVL"]) == 0:
            target = NavState.ALTCTL
        elif mode in (
            NavState.POSCTL,
            *ACTION_NAV_STATE.values(),
            NavState.AUTO_MISSION,
            NavState.AUTO_TAKEOFF,
        ):
            target = NavState.DESCEND
        else:
            return
        if self.nav_state == target:
            return
        self.position_fallback = True
        self.failsafe = True
        v.text(MavSeverity.CRITICAL, "Position estimate lost")
        v.text(MavSeverity.WARNING, f"Failsafe activated: {target.name.lower()}")
        self.switch(target, t)

    def _attitude_failure(self, t: int) -> None:
        """fd_critical_failure: lockdown early after arming, termination if its breaker allows, else warn."""
        p = self.params
        self.v.text(MavSeverity.CRITICAL, "Attitude failure detected")
        if t < self.armed_at_us + (p["COM_LKDOWN_TKO"] + p["COM_SPOOLUP_TIME"]) * 1e6:
            self._act(NavAction.DISARM, t)
        elif int(p["CBRK_FLIGHTTERM"]) != 121212:
            self._act(NavAction.TERMINATE, t)

    def _failsafe(self, condition: Condition, t: int) -> None:
        """Report the condition, then the action its parameter chooses
        (``fromNavDllOrRclActParam``): terminate and disarm at once, Hold / Return / Land through
        the framework (Return stays until a mode change once the condition clears)."""
        self.v.text(MavSeverity.CRITICAL, condition.text)
        action = int(self.params[condition.action_param])
        if action in (NavAction.TERMINATE, NavAction.DISARM):
            self._act(action, t)
        elif action in (NavAction.HOLD, NavAction.RETURN, NavAction.LAND):
            sticky = action == NavAction.RETURN
            self._framework_add(condition.action_param, NavAction(action), condition.cause, sticky)

    def _framework_add(self, key: str, action: NavAction, cause: Cause, sticky: bool) -> None:
        self._fw.add(key, action, cause, sticky=sticky, fail_act_t=self.params["COM_FAIL_ACT_T"])

    def _failsafe_update(self, t: int) -> None:
        """Commander.cpp ``handleModeIntentionAndFailsafe`` for the framework's actions: what it
        selects is flown (``modeFromAction``: Hold, Return, Land; Warn and nothing leave the
        user's mode) and announced (``notifyUser``). When its action goes because the condition
        cleared, the vehicle goes back to the user's mode."""
        fw = self._fw
        before = fw.selected
        beyond_hold = self.failsafe and self.nav_state in _BEYOND_HOLD and not _framework_flies(before)
        if fw.update(t, self.params["COM_FAIL_ACT_T"], self.user_nav_state, beyond_hold):
            for severity, text in notify_texts(fw.selected, fw.delay_us):
                self.v.text(severity, text)
        after = fw.selected
        if after == before or self.position_fallback:
            return
        target = _FRAMEWORK_NAV_STATE.get(after.action)
        was = _FRAMEWORK_NAV_STATE.get(before.action)
        if target is not None:
            self.failsafe = True
            self.status_dirty = True
            self.switch(target, t)
        elif was is not None:  # the action went: the condition cleared, or the user took over
            self.failsafe = False
            self.status_dirty = True
            if self.nav_state == was:
                self.switch(self.user_nav_state, t)

    def _act(self, action: int, t: int) -> None:
        """The actions that do not wait: terminate (cut the motors) and disarm (lockdown)."""
        self.failsafe = True
        if action == NavAction.TERMINATE:
            self.v.text(MavSeverity.CRITICAL, "Failsafe: flight termination")
            self.body.motors = False
            self.crashed = True
        elif action == NavAction.DISARM:
            self.disarm(t, Reason.FAILSAFE, "Disarmed by failsafe")

    def user_mode_change(self) -> None:
        """The user asked for a mode (``UserModeIntention::change``): the failsafe framework lets
        them take over from its Hold, Return or Land."""
        self._fw.mode_change()

    def ground_impact(self, t: int) -> None:
        """The vehicle fell to the ground out of control (a motor failed): a crash."""
        self.crashed = True
        self.failsafe = True
        self.body.motors = False
        self.v._cmd = IDLE
        self.status_dirty = True
        self.v.text(MavSeverity.CRITICAL, "crash: ground impact")

    def set_home(self, t: int) -> None:
        st = self.st
        lat, lon = self.proj.reproject(st.x, st.y)
        self.home = (st.x, st.y, st.z, lat, lon, self.home_alt - st.z, st.yaw)
        self.nav.home = (st.x, st.y, st.z, st.yaw)  # home_position.yaw: the heading home was set with
        self.v.ctrl.home_xy = (st.x, st.y)  # FlightTaskAuto's home for MPC_YAW_MODE 1 and 2
        self.nav.check_mission_feasible()  # PX4 rechecks the mission when home changes
        self.home_set = True
        self._home_count += 1
        self.recorder.data(
            HomePosition(
                t, lat, lon, self.home_alt - st.z, st.x, st.y, st.z, st.yaw, True, True, True, False,
                self._home_count,
            )
        )  # fmt: skip
        self.v._out.append(home_position(self.v, t))

    def arm(self, t: int, reason: int) -> MavResult:
        if self.armed:
            return MavResult.ACCEPTED
        denied = arming_denied(self.v)
        if denied is not None:
            if denied.text is not None:
                self.v.text(MavSeverity.CRITICAL, denied.text)
            return denied.result
        if not self.recorder.active:
            self.recorder.start(t, self.params)
        self.armed = True
        self.armed_at_us = t
        self.arming_reason = reason
        self.failsafe = False
        self._gf_active = False
        self._gf_pending = None
        self._gf_flying = None
        self._fw.reset()
        self._mission_failing = False
        self._taken_off = False
        self._auto_disarm_landed.set_state_and_update(False, t)
        rtl_type = int(self.params["RTL_TYPE"])
        if rtl_type != 0:
            self.v.text(MavSeverity.WARNING, f"RTL_TYPE {rtl_type} not modelled: Return flies RTL_TYPE 0")
        self._rc_lost_at_arming = self._sticks_us is None or self.rc_lost
        self.set_home(t)
        if self.nav_state == NavState.AUTO_MISSION and self.nav.finished:
            self.nav.set_current(0)
        self.nav.enter(self.nav_state, self.st, t / 1e6)
        self.ctrl.reset(self.st.x, self.st.y, self.st.z, 0.0, 0.0, 0.0, self.st.yaw)
        self.status_dirty = True
        self.v.text(MavSeverity.INFO, "Armed by external command")
        return MavResult.ACCEPTED

    def disarm(self, t: int, reason: int, text: str) -> None:
        self.armed = False
        self._fw.reset()
        self._taken_off = False  # Commander::disarm: _have_taken_off_since_arming
        self._auto_disarm_landed.set_state_and_update(False, t)
        self.disarming_reason = reason
        self.body.motors = False
        self.status_dirty = True
        self.v.text(MavSeverity.INFO, text)
        self.close_log = True
        # UserModeIntention::onDisarm: back to the last mode that may arm (after Land, Return or
        # Orbit: the one before); disarmed, the failsafe framework selects no action, so the
        # vehicle is in the user's mode
        self.user_nav_state = self.after_disarming
        self.failsafe = False
        self._offboard_lost = False
        if not self.crashed:
            self.switch(self.user_nav_state, t)

    def crash(self, t: int, index: int) -> None:
        b = self.body
        self.crashed = True
        self.crash_obstacle = index
        self.failsafe = True
        b.vx = b.vy = 0.0
        b.ax = b.ay = 0.0
        b.motors = False
        self.v._cmd = IDLE
        self.status_dirty = True
        self.v.text(MavSeverity.CRITICAL, f"crash: collided with obstacle {index}")

    def mode_flags(self, t: int) -> ModeFlags:
        """What the mode checks see missing now (failsafe_flags): manual control (never seen, or
        lost for COM_RC_LOSS_T), the position (GNSS failed for EKF2_NOAID_TOUT), a valid mission,
        the offboard signal, home."""
        v, p = self.v, self.params
        return ModeFlags(
            manual_control_lost=self._sticks_us is None or self.rc_lost,
            position_invalid=v.sim.faulty and not v.gps.position_valid(t, p["EKF2_NOAID_TOUT"]),
            mission_missing=not self.nav.mission_valid,
            offboard_signal_lost=not v.offboard.signal(t),
            home_invalid=not self.home_set,
            arm_needs_mission=bool(int(p["COM_ARM_MIS_REQ"])),
        )

    def intend(self, ns: NavState) -> None:
        """The user's mode becomes ``ns`` (``UserModeIntention::change`` once allowed)."""
        self.user_nav_state = ns
        self.ever_had_mode_change = True
        if not prevents_arming(ns):
            self.after_disarming = ns

    def may_switch(self, ns: NavState, *, announce: bool = True) -> bool:
        """``UserModeIntention::change``'s check: disarmed, always; armed, when ``ns`` can run
        (else ``printRejectMode``'s text, when ``announce``)."""
        if not self.armed or can_run(ns, self.mode_flags(self.v.time_us)):
            return True
        if announce:
            self.v.text(MavSeverity.CRITICAL, f"Switching to {MODE_NAMES[ns]} is currently not available")
        return False

    def set_mode(self, ns: NavState | None, *, announce: bool = True) -> MavResult:
        """A user's mode change (``UserModeIntention::change``): always allowed while disarmed;
        armed, refused TEMPORARILY_REJECTED when the mode cannot run (``mode_requirements``), with
        ``printRejectMode``'s text when ``announce`` (PX4 prints it for DO_SET_MODE only when the
        request came from component 190, MAV_COMP_ID_MISSIONPLANNER, as the runner's does)."""
        if ns is None:
            return MavResult.DENIED
        if not self.may_switch(ns, announce=announce):
            return MavResult.TEMPORARILY_REJECTED
        if self.crashed:
            return MavResult.DENIED
        self.user_mode_change()
        self.intend(ns)
        self.failsafe = False
        self._offboard_lost = False
        self._gf_flying = None
        self.switch(ns, self.v.time_us)
        return MavResult.ACCEPTED

    def switch(
        self, ns: NavState, t: int, *, target_alt: float | None = None, hold_z: float | None = None
    ) -> None:
        if ns == self.nav_state and target_alt is None:
            return
        if ns == NavState.AUTO_MISSION and self.land.landed and self.nav.finished:
            self.nav.set_current(0)
        self.nav_state = ns
        self.nav_state_us = t
        self.nav.enter(ns, self.st, t / 1e6, target_alt=target_alt, hold_z=hold_z)
        if ns == NavState.OFFBOARD:
            self.v.offboard.enter()
        b, e, st = self.body, self.est, self.st
        self.ctrl.reset(st.x, st.y, st.z, b.vx + e.evx, b.vy + e.evy, b.vz + e.evz, st.yaw)
        self.status_dirty = True
