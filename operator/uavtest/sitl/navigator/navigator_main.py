"""What the vehicle should do now: PX4's navigator for mission, hold, takeoff, land and return.

Pure logic: fed the estimated state and the clock, it returns the controller's ``Goal`` and
queues events (mission item reached, mission finished, status texts). PX4 behaviour kept:

- takeoff to the item's altitude (``MIS_TAKEOFF_ALT`` is Takeoff mode's default, not a minimum, in
  PX4 v1.15), done within ``NAV_MC_ALT_RAD``;
- a mission climbs first where the vehicle is when its first position item is above it
  (``checkClimbRequired`` on activation, ``Mission::handleTakeoff``: a TAKEOFF setpoint from the
  ground, "Climb to N meters above home"); a TAKEOFF item is then flown to as a waypoint (its
  lat/lon, its yaw ignored) and reached there;
- a waypoint is reached within its acceptance radius (``NAV_ACC_RAD`` unless the item sets one)
  and ``NAV_MC_ALT_RAD`` (``_time_wp_reached``); an item with a heading (param4, degrees) is flown
  to facing it and waits until the heading error is below ``MIS_YAW_ERR``: ``MIS_YAW_TMT`` set
  accepts an unforced heading at once, and fails the mission ("unable to reach heading within
  timeout") when a forced one (LOITER_TIME param2) is not reached within it; one without (NaN, as
  QGC and the runner send) is reached at once (``get_yaw_to_be_accepted``); the hold, ``param1``
  seconds, counts from the arrival;
- Hold while flying holds where the vehicle can stop (``calculate_breaking_stop``: MPC_ACC_HOR,
  MPC_JERK_AUTO), or on the loiter setpoint it is already on (``Loiter::set_loiter_position``);
  a geofence breach with GF_ACTION 2 holds where the breach was seen (its reposition);
- a waypoint is flown along the track from the previous one (``Goal.prev``, PX4's
  position_setpoint_triplet.previous): the controller's FlightTaskAuto states (offtrack, ...);
  a loiter item (LOITER_TIME, LOITER_UNLIM) is braked onto, never turned through;
- a land item first flies to its position at the current altitude (reached then, as PX4
  reports it), then descends; the mission is finished once landed;
- DO_CHANGE_SPEED sets the cruise speed; camera items are skipped;
- a mission RTL item is issued as vehicle_command NAV_RETURN_TO_LAUNCH (commander → Return);
- DO_REPOSITION moves the hold point (``reposition``); ORBIT runs ``FlightTaskOrbit``;
- a new mission or MISSION_SET_CURRENT only changes what is flown in mission mode;
- return (``rtl_direct.cpp``): climb where Return started, facing the heading it had, to the
  return altitude (``rtl.py``: ``RTL_RETURN_ALT``, lowered near the destination by the
  ``RTL_CONE_ANG`` cone within ``RTL_MIN_DIST``; "RTL: start return at N m (M m above
  destination)"), fly to the destination (facing it, or already home's heading when the return
  starts within ``RTL_MIN_DIST``), descend to ``RTL_DESCEND_ALT`` turning to home's heading (the
  heading home was set with), wait ``RTL_LAND_DELAY`` (negative: forever, "RTL: completed,
  loitering"), land facing home's heading ("RTL: land at destination"); every item with a heading
  waits for it within ``MIS_YAW_ERR``;
- return destination (``RTL_TYPE`` 0, ``rtl.cpp`` findRtlDestination): home or the closest rally
  point (``geofence.rally_destination``); RTL_TYPE 1-3 are not modelled (said at arming) and
  fly as 0;
- geofence (``geofence.py``): the breach check every 0.2 s (``geofence_breach_check``) and the
  mission feasibility check against it (``mission_feasibility_checker.cpp``
  checkMissionAgainstGeofence: a waypoint outside → "Geofence violation for waypoint N", the
  mission is not valid), rerun when the mission, the fence or home change, as PX4 does.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from enum import Enum

from uavtest.px4.modes import NavState
from uavtest.sitl.flight_task_orbit import FlightTaskOrbit
from uavtest.sitl.geo import Projection
from uavtest.sitl.mav import MavCmd, MavSeverity
from uavtest.sitl.mc_pos_control import NO_NEXT, NO_TRACK, Goal, GoalKind, wrap_pi
from uavtest.sitl.mission import NavItem, has_position
from uavtest.sitl.navigator.geofence import NAV_RALLY_POINT, Geofence, rally_destination
from uavtest.sitl.navigator.mission_feasibility import feasibility_failures
from uavtest.sitl.navigator.rtl import (
    FLT_EPSILON,
    f32,
    rtl_heading_accepted,
    rtl_loiters_forever,
    rtl_return_altitude,
    rtl_start_text,
)
from uavtest.sitl.params import ParamStore
from uavtest.sitl.uorb import GeofenceResult

__all__ = ["Event", "EventKind", "Navigator", "State", "braking_distance"]

#: items whose successor becomes the triplet's next unless they hold (param1) or stop. Not the
#: loiter items: their setpoint is SETPOINT_TYPE_LOITER and FlightTaskAuto::_evaluateTriplets
#: makes a loiter's next its own target, so the vehicle stops there even with no hold time
_PASS_THROUGH = frozenset({MavCmd.NAV_WAYPOINT, MavCmd.NAV_TAKEOFF})
#: items with a heading (param4) that the vehicle turns to and, on arrival, waits for
_HEADING_ITEMS = frozenset({MavCmd.NAV_WAYPOINT, MavCmd.NAV_LOITER_TIME, MavCmd.NAV_LOITER_UNLIM})
#: items whose setpoint is SETPOINT_TYPE_LOITER (MissionBlock::mission_item_to_position_setpoint)
_LOITER_ITEMS = frozenset({MavCmd.NAV_LOITER_TIME, MavCmd.NAV_LOITER_UNLIM})


class EventKind(Enum):
    REACHED = "reached"  # value: seq
    CURRENT = "current"  # value: seq
    FINISHED = "finished"
    TEXT = "text"  # value: (severity, text)
    HOLD = "hold"  # the navigator asks the commander to switch to hold (after takeoff)
    RTL = "rtl"  # a mission RTL item: vehicle_command NAV_RETURN_TO_LAUNCH (commander → Return)
    FAILURE = "failure"  # mission_result.failure set (Navigator::set_mission_failure_heading_timeout)


@dataclass(frozen=True, slots=True)
class Event:
    kind: EventKind
    value: object = None


@dataclass(slots=True)
class State:
    """The estimated state the navigator decides on."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = 0.0
    landed: bool = True
    vx: float = 0.0  # the estimated horizontal velocity (Navigator::calculate_breaking_stop)
    vy: float = 0.0


class Phase(Enum):
    START = "start"
    TAKEOFF = "takeoff"
    FLY = "fly"
    YAW = "yaw"
    HOLD = "hold"
    DESCEND = "descend"
    DONE = "done"


@dataclass(slots=True)
class _Rtl:
    """RtlDirect's state: climb (CLIMBING), return (MOVE_TO_LOITER), descend (LOITER_DOWN), loiter
    (LOITER_HOLD), approach (MOVE_TO_LAND_HOVER), land (LAND), done (IDLE)."""

    phase: str = "climb"
    alt: float = 0.0  # the return altitude, m up (local frame, -z)
    since: float = 0.0
    x: float = 0.0  # destination: home or a rally point
    y: float = 0.0
    land_alt: float = 0.0  # the loiter altitude: RTL_DESCEND_ALT above the destination, m up
    yaw: float = math.nan  # the current item's heading (nan: FlightTaskAuto's MPC_YAW_MODE)
    cx: float = 0.0  # the climb's position: where Return started
    cy: float = 0.0


@dataclass(slots=True)
class _Step:
    """Where the current item is: its target, its phase, and when the phase began."""

    phase: Phase = Phase.START
    since: float = 0.0
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = math.nan
    speed: float = math.nan  # a reposition's ground speed (nan: the navigator's cruise speed)
    rtl: _Rtl | None = None
    #: position_setpoint_triplet.next for the item, looked up once (None: not yet)
    next: tuple[float, float, float] | None = None
    #: MissionBlock's _time_wp_reached: when the item's position was reached (its hold counts
    #: from then, the heading's wait too)
    reached_at: float = math.nan
    #: mission_item.force_heading (a LOITER_TIME's param2 > 0): the heading must be reached
    force_heading: bool = False
    extra: dict[str, float] = field(default_factory=dict)


def braking_distance(velocity: float, jerk: float, accel: float) -> float:
    """The distance to brake from ``velocity`` as Navigator::calculate_breaking_stop computes it:
    math::trajectory::computeBrakingDistanceFromVelocity(v, MPC_JERK_AUTO, MPC_ACC_HOR, 0.6
    MPC_JERK_AUTO), v (v / 2a + a_delay / j): the delay term is 0.6 s of the velocity."""
    accel_delay_max = 0.6 * jerk
    return velocity * (velocity / (2.0 * accel) + accel_delay_max / jerk)


class Navigator:
    def __init__(
        self, params: ParamStore, projection: Projection, home_alt: float, rng: random.Random | None = None
    ) -> None:
        self.rng = rng or random.Random(0)
        self.params = params
        self.proj = projection
        self.home_alt = home_alt
        self.mission: list[NavItem] = []
        self.current = 0
        self.reached = -1
        self.finished = False
        self.speed = math.nan  # DO_CHANGE_SPEED override
        self.events: list[Event] = []
        self.nav_state = NavState.AUTO_LOITER
        self.home = (0.0, 0.0, 0.0)
        self._step = _Step()
        self._goal = Goal()
        self.geofence = Geofence(projection)
        self.rally: list[tuple[float, float]] = []  # rally points, local x, y
        self.mission_feasible = True  # the mission passes FeasibilityChecker and the geofence
        #: the vehicle's state at the latest update (landed, x, y): what PX4's FeasibilityChecker
        #: reads when it checks a mission; None before the first (landed at the origin)
        self._latest: State | None = None
        #: the estimate's horizontal position as the navigator last sampled it: PX4's navigator
        #: polls vehicle_local_position at 20 Hz, behind the flight task's sample, so a point it
        #: takes (the takeoff's) is a little behind where FlightTaskAuto sees the vehicle. Set by
        #: the vehicle each control tick to the previous tick's estimate; NaN: the current one
        self.sample_x = self.sample_y = math.nan
        self.failure = False  # mission_result.failure: a forced heading not reached in MIS_YAW_TMT
        #: MissionBase::_mission_init_climb_altitude_amsl as a local z: the climb owed before the
        #: first position item (checkClimbRequired on activation), None when none is
        self._climb_z: float | None = None
        #: the geofence's reposition triplet (x, y, z, time) for Hold, and _geofence_reposition_sent
        self._gf_reposition: tuple[float, float, float, float] | None = None
        self._gf_reposition_sent = False
        # PX4's ObstacleAvoidance publishes yaw_acceptance NaN: with avoidance on, a waypoint is
        # accepted from any heading (Navigator::get_yaw_to_be_accepted), no MIS_YAW_ERR wait
        self.yaw_acceptance = True
        # PX4 runs Orbit as a flight task; here the navigator hands its goal to the controller
        self.orbit = FlightTaskOrbit(params["MC_ORBIT_RAD_MAX"])

    @property
    def mission_valid(self) -> bool:
        """mission_result.valid: a mission is loaded and passes the feasibility check."""
        return bool(self.mission) and self.mission_feasible

    # ------------------------------------------------------------------ configuration

    def set_mission(self, items: list[NavItem], now: float = 0.0) -> None:
        """A new mission. Only a vehicle flying the mission starts it over (PX4
        ``MissionBase::onMissionUpdate``: ``set_mission_items`` only ``if (isActive())``); in hold,
        return or takeoff the vehicle keeps doing what it does."""
        self.mission = list(items)
        self.current = 0
        self.reached = -1
        self.finished = False
        if self.nav_state == NavState.AUTO_MISSION:
            self._step = _Step(since=now)
        self.events.append(Event(EventKind.CURRENT, 0))
        self.check_mission_feasible()

    def set_fence(self, items: list[NavItem], flying_at: tuple[float, float] | None) -> None:
        """Take a fence plan (``flying_at``: the vehicle's x, y when airborne with GF_ACTION set)."""
        hx, hy, _ = self.home
        here = None if flying_at is None else self.proj.reproject(*flying_at)
        for text in self.geofence.set_areas(items, self.proj.reproject(hx, hy), here):
            self.events.append(Event(EventKind.TEXT, (MavSeverity.CRITICAL, text)))
        self.check_mission_feasible()

    def set_rally(self, items: list[NavItem]) -> None:
        self.rally = [self.proj.project(it.lat, it.lon) for it in items if it.command == NAV_RALLY_POINT]

    def check_mission_feasible(self) -> None:
        """MissionFeasibilityChecker::checkMissionFeasible: FeasibilityChecker's item checks
        (``mission_feasibility.py``), then checkMissionAgainstGeofence (every waypoint inside the
        fence), each failure said. A check also clears mission_result.failure
        (MissionBase::check_mission_valid)."""
        self.failure = False
        p = self.params
        gf = self.geofence
        max_hor, max_ver = p["GF_MAX_HOR_DIST"], p["GF_MAX_VER_DIST"]
        st = self._latest
        vx, vy = (st.x, st.y) if st is not None else (0.0, 0.0)
        texts = feasibility_failures(
            self.mission,
            landed=st.landed if st is not None else True,
            home_amsl=self.home_alt - self.home[2],
            distance_to=lambda item: math.dist(self.proj.project(item.lat, item.lon), (vx, vy)),
            dist_1wp=p["MIS_DIST_1WP"],
            takeoff_land_req=int(p["MIS_TKO_LAND_REQ"]),
        )
        for text in texts:
            self.events.append(Event(EventKind.TEXT, (MavSeverity.CRITICAL, text)))
        ok = not texts
        if self.mission and (max_hor > 0 or max_ver > 0 or gf.areas):
            hx, hy, hz = self.home
            home_amsl = self.home_alt - hz
            for i, item in enumerate(self.mission):
                if not has_position(item):
                    continue
                x, y = self.proj.project(item.lat, item.lon)
                if not gf.allows(x, y, item.alt_rel(home_amsl), (hx, hy, 0.0), max_hor, max_ver):
                    ok = False
                    text = f"Geofence violation for waypoint {i + 1}"
                    self.events.append(Event(EventKind.TEXT, (MavSeverity.CRITICAL, text)))
                    break
        self.mission_feasible = ok

    def geofence_allows_position(self, x: float, y: float, alt: float) -> bool:
        """Navigator::geofence_allows_position for a local point ``alt`` m above home: PX4 refuses
        a DO_REPOSITION outside the fence ("Reposition is outside geofence") unless GF_ACTION is
        0 or 1 (for the reposition / goto handler)."""
        p = self.params
        if int(p["GF_ACTION"]) in (0, 1):
            return True
        hx, hy, _ = self.home
        return self.geofence.allows(x, y, alt, (hx, hy, 0.0), p["GF_MAX_HOR_DIST"], p["GF_MAX_VER_DIST"])

    def geofence_breach_check(self, st: State, t_us: int, armed: bool = True) -> GeofenceResult | None:
        """Navigator::geofence_breach_check (every 0.2 s): the result, or None when GF_ACTION is 0
        (PX4 does not check then) or nothing is fenced (no limit, no area: nothing to log)."""
        p = self.params
        gf = self.geofence
        action = int(p["GF_ACTION"])
        max_hor, max_ver = p["GF_MAX_HOR_DIST"], p["GF_MAX_VER_DIST"]
        if action == 0 or (max_hor <= 0 and max_ver <= 0 and not gf.areas):
            gf.max_dist = gf.max_alt = gf.custom = False
            return None
        hx, hy, hz = self.home
        gf.check(st.x, st.y, -st.z, (hx, hy, -hz), max_hor, max_ver)
        if gf.max_dist or gf.max_alt or gf.custom:
            # GF_ACTION 2 (Hold): a reposition to where the vehicle is (GF_PREDICT 0), once per
            # breach, that Loiter flies instead of its braking stop
            if not self._gf_reposition_sent and armed and action == 2:
                self._gf_reposition = (st.x, st.y, st.z, t_us / 1e6)
                self._gf_reposition_sent = True
        else:
            self._gf_reposition_sent = False
        return GeofenceResult(t_us, gf.max_dist, gf.max_alt, gf.custom, action)

    def set_current(self, seq: int, now: float = 0.0) -> bool:
        """MISSION_SET_CURRENT / MISSION_START param1: jump to ``seq`` (flown at once in mission
        mode, else when the mission starts); False when there is no such item."""
        if not 0 <= seq < len(self.mission):
            return False
        self.current = seq
        self.finished = False
        if self.nav_state == NavState.AUTO_MISSION:
            self._step = _Step(since=now)
        self.events.append(Event(EventKind.CURRENT, self.current))
        return True

    def land_start_index(self) -> int | None:
        """The mission's DO_LAND_START item (PX4 ``MissionBase::get_land_start_index``)."""
        for item in self.mission:
            if item.command == MavCmd.DO_LAND_START:
                return item.seq
        return None

    def reposition(
        self, st: State, x: float | None, y: float | None, z: float | None, yaw: float, speed: float
    ) -> None:
        """DO_REPOSITION in hold (PX4 ``Navigator::run`` VEHICLE_CMD_DO_REPOSITION): fly to x, y
        (None: keep the hold point) at z (None: the current altitude), facing ``yaw`` (radians,
        nan: along the way), at ``speed`` (nan: cruise). All None and nan: stop where it is."""
        s = self._step
        if x is None or y is None:
            if z is None and math.isnan(yaw):
                # all NaN pauses the vehicle where it can stop (navigator_main.cpp: not from a
                # takeoff setpoint, there the current position)
                s.x, s.y = (st.x, st.y) if self._goal.kind is GoalKind.TAKEOFF else self.breaking_stop(st)
        else:
            s.x, s.y = x, y
        s.z = st.z if z is None else z
        s.yaw = yaw
        s.speed = speed

    def enter(
        self,
        nav_state: NavState,
        st: State,
        now: float,
        *,
        target_alt: float | None = None,
        hold_z: float | None = None,
    ) -> None:
        """Start flying a mode from the current state (a hold keeps ``hold_z`` when given: the
        takeoff's setpoint, ``Takeoff::on_active`` setLoiterItemFromCurrentPositionSetpoint).

        Hold after a mission that finished in the air keeps the mission's end-of-mission loiter
        point (Navigator::run does not reset a valid loiter setpoint when switching to Loiter, and
        Loiter::set_loiter_position, within the loiter radius of it, keeps it); Hold from any
        other flight holds where the vehicle can stop (``_loiter_position``)."""
        old = self._step
        ended = (
            nav_state == NavState.AUTO_LOITER
            and self.nav_state == NavState.AUTO_MISSION
            and self.finished
            and old.phase == Phase.DONE
            and not st.landed
            and hold_z is None
        )
        hold_at = None
        if nav_state == NavState.AUTO_LOITER and hold_z is None and not st.landed and not ended:
            hold_at = self._loiter_position(st)
        self.nav_state = nav_state
        self._step = _Step(since=now, x=st.x, y=st.y, z=st.z if hold_z is None else hold_z, yaw=st.yaw)
        if ended:
            self._step.x, self._step.y, self._step.z, self._step.yaw = old.x, old.y, old.z, old.yaw
        elif hold_at is not None:
            self._step.x, self._step.y, self._step.z = hold_at
        # every navigator mode resets the cruise speed on activation (reset_cruising_speed in
        # Loiter, Land, Takeoff, RtlDirect and MissionBase::on_activation)
        self.speed = math.nan
        if nav_state == NavState.AUTO_TAKEOFF:
            # Takeoff::set_takeoff_position: the command's altitude, else MIS_TAKEOFF_ALT (a
            # default, not a minimum); never below where the vehicle already is
            alt = target_alt if target_alt is not None else self.params["MIS_TAKEOFF_ALT"]
            if -alt > st.z:
                alt = -st.z
                text = (MavSeverity.CRITICAL, "Already higher than takeoff altitude")
                self.events.append(Event(EventKind.TEXT, text))
            self._step.z = -alt
        elif nav_state == NavState.AUTO_RTL:
            self._step.rtl = self._rtl_start(st, now)
        elif nav_state == NavState.AUTO_MISSION and self.finished:
            self._step.phase = Phase.DONE
        elif nav_state == NavState.AUTO_MISSION:
            self._climb_z = self._climb_required(st)
        elif nav_state == NavState.ORBIT:
            self.orbit.activate(st.x, st.y, st.z, st.yaw)
        if math.isnan(self.home_yaw):
            # home came without its heading: the commander sets home and then starts the mode in
            # the same step (arming), so the state seen here is the one home was set from
            self.home_yaw = st.yaw

    def breaking_stop(self, st: State) -> tuple[float, float]:
        """Navigator::calculate_breaking_stop: where a multicopter flying at its current
        horizontal velocity stops, ``braking_distance`` ahead along its course."""
        v = math.hypot(st.vx, st.vy)
        if v <= 0.0:
            return st.x, st.y
        d = braking_distance(v, self.params["MPC_JERK_AUTO"], self.params["MPC_ACC_HOR"])
        return st.x + st.vx / v * d, st.y + st.vy / v * d

    def _loiter_position(self, st: State) -> tuple[float, float, float]:
        """Loiter::set_loiter_position for a flying multicopter: the current setpoint when it is
        a loiter the vehicle is already within NAV_ACC_RAD + NAV_LOITER_RAD of
        (setLoiterItemFromCurrentPositionSetpoint), else the braking stop at the current altitude
        (setLoiterItemFromCurrentPositionWithBreaking)."""
        g = self._goal
        if self._setpoint_is_loiter():
            p = self.params
            if math.hypot(g.x - st.x, g.y - st.y) <= p["NAV_ACC_RAD"] + p["NAV_LOITER_RAD"]:
                return g.x, g.y, g.z
        x, y = self.breaking_stop(st)
        return x, y, st.z

    def _setpoint_is_loiter(self) -> bool:
        """position_setpoint_triplet.current.type is SETPOINT_TYPE_LOITER: a hold, a mission's
        loiter item, the climb of a flying vehicle (LOITER_TO_ALT), or the loiter at its end."""
        ns, s = self.nav_state, self._step
        if ns == NavState.AUTO_LOITER:
            return self._goal.kind is GoalKind.POSITION
        if ns != NavState.AUTO_MISSION or self._goal.kind is not GoalKind.POSITION:
            return False
        if s.phase == Phase.DONE or (s.phase == Phase.TAKEOFF and "ground" not in s.extra):
            return True
        item = self.mission[self.current] if self.current < len(self.mission) else None
        return item is not None and item.command in _LOITER_ITEMS and s.phase != Phase.START

    def _climb_required(self, st: State) -> float | None:
        """MissionBase::checkClimbRequired on activation: the first position item from the
        current one, when it is more than NAV_MC_ALT_RAD above the vehicle, is climbed to first."""
        for item in self.mission[self.current :]:
            if has_position(item):
                alt = item.alt_rel(self.home_alt)
                return -alt if alt - -st.z > self.params["NAV_MC_ALT_RAD"] else None
        return None

    # ------------------------------------------------------------------ the tick

    def update(self, st: State, now: float) -> Goal:
        self._latest = st
        ns = self.nav_state
        if ns == NavState.AUTO_MISSION:
            return self._mission(st, now)
        s = self._step
        if ns == NavState.AUTO_TAKEOFF:
            if st.landed or abs(st.z - s.z) > self.params["NAV_MC_ALT_RAD"]:
                return self._goal_set(GoalKind.TAKEOFF, s.x, s.y, s.z, s.yaw)
            self.events.append(Event(EventKind.HOLD, s.z))
            return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
        if ns == NavState.AUTO_LAND:
            if st.landed:  # Land::on_active: landed → the idle setpoint (motors at idle, armed)
                return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
            g = self._goal_set(GoalKind.LAND, s.x, s.y, st.z, s.yaw)
            g.alt_amsl = 0.0  # MissionBlock::set_land_item: altitude 0, not relative
            return g
        if ns == NavState.AUTO_RTL:
            if s.rtl is None:
                s.rtl = self._rtl_start(st, now)
            return self._rtl(s.rtl, st, now)
        if st.landed:
            return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
        if ns == NavState.ORBIT:
            return self.orbit.update(st.x, st.y, st.z, st.yaw, self.params["NAV_MC_ALT_RAD"], self._goal)
        rep, self._gf_reposition = self._gf_reposition, None
        if rep is not None and ns == NavState.AUTO_LOITER and now - rep[3] < 0.5:
            # Loiter::on_activation / on_active: a reposition triplet under 500 ms old is flown
            # (the geofence's: back to where the breach was seen)
            s.x, s.y, s.z, s.yaw = rep[0], rep[1], rep[2], math.nan
        g = self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)  # hold
        if s.speed == s.speed:
            g.speed = s.speed
        return g

    def _goal_set(self, kind: GoalKind, x: float, y: float, z: float, yaw: float = math.nan) -> Goal:
        g = self._goal
        g.kind, g.x, g.y, g.z, g.yaw, g.speed = kind, x, y, z, yaw, self.speed
        g.prev = NO_TRACK
        g.acc_rad = math.nan
        g.next = NO_NEXT
        g.alt_amsl = math.nan
        return g

    # ------------------------------------------------------------------ mission

    def _local(self, item: NavItem, st: State) -> tuple[float, float, float]:
        if item.x == 0 and item.y == 0:
            x, y = st.x, st.y
        else:
            x, y = self.proj.project(item.lat, item.lon)
        return x, y, -item.alt_rel(self.home_alt)

    def _next_setpoint(self, after: int, st: State) -> tuple[float, float, float] | None:
        """position_setpoint_triplet.next: the first item with a position after ``after``
        (Mission::getNextPositionItems); None at a Return item or the mission's end."""
        for item in self.mission[after + 1 :]:
            if item.command == MavCmd.NAV_RETURN_TO_LAUNCH:
                return None
            if has_position(item):
                return self._local(item, st)
        return None

    def _advance(self, st: State, now: float, *, report: bool = True, announce: bool = True) -> None:
        if report:
            self.reached = self.current
            self.events.append(Event(EventKind.REACHED, self.current))
        if self.current + 1 < len(self.mission):
            old = self._step
            was_position = old.phase in (Phase.TAKEOFF, Phase.FLY, Phase.YAW, Phase.HOLD)
            self.current += 1
            self.events.append(Event(EventKind.CURRENT, self.current))
            self._step = _Step(since=now)
            if was_position and not math.isnan(old.x):
                # position_setpoint_triplet.previous: the item just reached
                self._step.extra.update(prev_x=old.x, prev_y=old.y, prev_z=old.z)
        else:
            self._finish(st, announce=announce)

    def _finish(self, st: State, *, announce: bool = True) -> None:
        """The mission ended (MissionBase ``advance_mission``: "Mission finished, landed" or
        ", loitering"; ``setEndOfMissionItems``: landed, idle; in the air, a loiter at the current
        position setpoint when it is a loiter item's, else at the current position, heading free).
        ``announce`` False: the mission hands over to Return (an RTL item) and says nothing."""
        s = self._step
        if not self.finished:
            self.finished = True
            if announce:
                text = "Mission finished, landed" if st.landed else "Mission finished, loitering"
                self.events.append(Event(EventKind.TEXT, (MavSeverity.INFO, text)))
            self.events.append(Event(EventKind.FINISHED))
            if not st.landed:
                loiter = self._last_position_item()
                if loiter is not None and loiter.command in (MavCmd.NAV_LOITER_TIME, MavCmd.NAV_LOITER_UNLIM):
                    s.x, s.y, s.z = self._local(loiter, st)
                else:
                    s.x, s.y, s.z, s.yaw = st.x, st.y, st.z, math.nan
        s.phase = Phase.DONE

    def _last_position_item(self) -> NavItem | None:
        """The item that set the position setpoint last: the last one with a position up to the
        current item (PX4's triplet keeps it through the items without a position after it)."""
        for item in reversed(self.mission[: self.current + 1]):
            if has_position(item):
                return item
        return None

    def _mission(self, st: State, now: float) -> Goal:
        s = self._step
        if not self.mission or s.phase == Phase.DONE or self.current >= len(self.mission):
            if self.mission and not self.finished:
                self._finish(st)
            if st.landed:
                return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
            if s.phase != Phase.DONE or math.isnan(s.z) or s.z == 0.0:
                s.phase, s.x, s.y, s.z = Phase.DONE, st.x, st.y, st.z
            return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
        item = self.mission[self.current]
        cmd = item.command
        p = self.params
        if s.phase == Phase.START:
            s.since = now
            if cmd == MavCmd.DO_CHANGE_SPEED:
                # issued as a vehicle command: param2 > 0 sets the cruise speed, else resets it
                self.speed = item.param2 if item.param2 > 0 else math.nan
                self._advance(st, now)
                return self._mission(st, now)
            if cmd == MavCmd.NAV_RETURN_TO_LAUNCH:
                # PX4 MissionBlock::issue_command: the item becomes vehicle_command
                # NAV_RETURN_TO_LAUNCH, so commander switches to Return (mission_block.cpp)
                self.events.append(Event(EventKind.RTL, self.current))
                self._advance(st, now, announce=False)
                return self._mission(st, now)
            if cmd not in (
                MavCmd.NAV_WAYPOINT,
                MavCmd.NAV_LOITER_TIME,
                MavCmd.NAV_LOITER_UNLIM,
                MavCmd.NAV_LAND,
                MavCmd.NAV_TAKEOFF,
            ):
                self._advance(st, now)  # camera and other no-op items
                return self._mission(st, now)
            else:
                s.x, s.y, s.z = self._local(item, st)
                self._start_position_item(item, st)
        if s.phase == Phase.TAKEOFF:
            # Mission::handleTakeoff's climb work item: straight up from where the mission started
            # (a TAKEOFF setpoint from the ground, LOITER_TO_ALT in the air), yaw left to
            # FlightTaskAuto; not reported as reached; then the item is flown to as a waypoint
            tx, ty, cz = s.extra["tx"], s.extra["ty"], s.extra["cz"]
            if "ground" in s.extra:
                if st.landed or not self._takeoff_reached(st, cz):
                    return self._goal_set(GoalKind.TAKEOFF, tx, ty, cz)
            elif abs(st.z - cz) > p["NAV_MC_ALT_RAD"]:
                return self._goal_set(GoalKind.POSITION, tx, ty, cz)
            s.phase = Phase.FLY
            # position_setpoint_triplet.previous: the climb's setpoint (setActiveMissionItems)
            s.extra.update(prev_x=tx, prev_y=ty, prev_z=cz)
        if s.phase == Phase.FLY:
            radius = p["NAV_ACC_RAD"]
            if cmd == MavCmd.NAV_WAYPOINT and item.param2 > 0:
                radius = item.param2
            dxy = math.hypot(s.x - st.x, s.y - st.y)
            dz = abs(s.z - st.z)
            # is_mission_item_reached_or_completed: a land item is flown to at altitude first (and
            # done once landed); any other position is reached only in the air ("Update the
            # 'waypoint position reached' status" only while not landed): a waypoint on the ground
            # where the vehicle stands is never reached, and PX4 does not take off towards it
            in_air = not st.landed
            if dxy <= radius and (cmd == MavCmd.NAV_LAND or (in_air and dz <= p["NAV_MC_ALT_RAD"])):
                if cmd == MavCmd.NAV_LAND:
                    self.reached = self.current
                    self.events.append(Event(EventKind.REACHED, self.current))
                    s.phase = Phase.DESCEND
                else:
                    s.phase = Phase.YAW
                    s.reached_at = now  # MissionBlock's _time_wp_reached
            else:
                # the item's heading (NaN: FlightTaskAuto's MPC_YAW_MODE) is the setpoint's yaw
                # all the way there (FlightTaskAuto::_evaluateTriplets: current.yaw when finite)
                g = self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
                if "prev_x" in s.extra:
                    g.prev = (s.extra["prev_x"], s.extra["prev_y"], s.extra["prev_z"])
                g.acc_rad = radius
                # Mission::setActiveMissionItems: a waypoint without a hold time hands its
                # successor to the triplet's next, so the trajectory turns through the corner
                # instead of stopping (a hold time or autocontinue 0 brakes: next invalid)
                if cmd in _PASS_THROUGH and self._time_inside(item) <= 0 and item.autocontinue:
                    if s.next is None:  # once per item
                        s.next = self._next_setpoint(self.current, st) or NO_NEXT
                    g.next = s.next
                return g
        if s.phase == Phase.YAW:
            if not self._heading_reached(st, now):
                return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
            if not math.isfinite(s.yaw):
                # FlightTaskAuto::_set_heading_from_mode: inside the acceptance radius the heading
                # locks where it is, and stays so while the item's hold time runs
                s.yaw = st.yaw
            s.phase = Phase.HOLD
        if s.phase == Phase.HOLD:
            if cmd == MavCmd.NAV_LOITER_UNLIM:
                return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
            # the hold time counts from the arrival (_time_wp_reached), the heading's wait included
            if now - s.reached_at < self._time_inside(item):
                return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
            self._advance(st, now)
            return self._mission(st, now)
        if s.phase == Phase.DESCEND:
            if st.landed:
                self._finish(st)
                return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
            g = self._goal_set(GoalKind.LAND, s.x, s.y, st.z, s.yaw)
            g.alt_amsl = self.home_alt + item.alt_rel(self.home_alt)  # the land item's altitude
            return g
        return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)

    def _start_position_item(self, item: NavItem, st: State) -> None:
        """Mission::setActiveMissionItems for a position item (its target already in the step):
        the climb owed before it (handleTakeoff), the move to a land item at altitude
        (MissionBase::handleLanding), the item's heading (param4) and force_heading."""
        s = self._step
        cmd = item.command
        if cmd == MavCmd.NAV_LAND:
            # MOVE_TO_LAND: at the current position setpoint's altitude (the previous item's),
            # else the current altitude; the heading ignored. handleLanding resets the triplet's
            # previous, but setActiveMissionItems then sets it to the last setpoint again (the
            # work item was still DEFAULT): the track runs from the last waypoint, as PX4 logs it
            prev = self._goal
            held = prev.kind in (GoalKind.POSITION, GoalKind.TAKEOFF) and not st.landed
            s.z = prev.z if held else st.z
            s.phase = Phase.FLY
            return
        climb, self._climb_z = self._climb_z, None
        if climb is None and st.landed and st.z - s.z > self.params["NAV_MC_ALT_RAD"]:
            # on the ground in mission mode without an activation: take off to it, when it is
            # above (checkClimbRequired's rule: not a waypoint on the ground, such as the home
            # item 0 of an ArduPilot-style QGC WPL file)
            climb = s.z
        if climb is not None and climb < st.z:
            # Mission::handleTakeoff climbs from the navigator's global position
            sampled = self.sample_x == self.sample_x
            tx, ty = (self.sample_x, self.sample_y) if sampled else (st.x, st.y)
            s.extra.update(tx=tx, ty=ty, cz=climb)
            if st.landed:
                s.extra["ground"] = 1.0
            s.phase = Phase.TAKEOFF
            text = f"Climb to {-climb:.1f} meters above home"
            self.events.append(Event(EventKind.TEXT, (MavSeverity.INFO, text)))
        else:
            s.phase = Phase.FLY
        # MAVLink's param4 in degrees (mavlink_mission.cpp); a TAKEOFF is flown as a waypoint
        # with its yaw ignored (handleTakeoff: "otherwise it might yaw before ...")
        yaw = item.param4 if cmd in _HEADING_ITEMS else math.nan
        s.yaw = wrap_pi(math.radians(yaw)) if math.isfinite(yaw) else math.nan
        s.force_heading = cmd == MavCmd.NAV_LOITER_TIME and item.param2 > 0

    def _takeoff_reached(self, st: State, z: float) -> bool:
        """is_mission_item_reached_or_completed for a multicopter's TAKEOFF: altitude only, above
        the target less NAV_MC_ALT_RAD (half the takeoff altitude when that is smaller)."""
        rad = self.params["NAV_MC_ALT_RAD"]
        alt = -z
        if 0.0 < alt < rad:
            rad = alt / 2.0
        return -st.z > alt - rad

    @staticmethod
    def _time_inside(item: NavItem) -> float:
        """MissionBlock::get_time_inside: a waypoint's or LOITER_TIME's param1, never negative."""
        if item.command in (MavCmd.NAV_WAYPOINT, MavCmd.NAV_LOITER_TIME):
            return max(item.param1, 0.0)
        return 0.0

    def _heading_reached(self, st: State, now: float) -> bool:
        """is_mission_item_reached_or_completed's heading for a multicopter
        (``rtl_heading_accepted``, the item's ``force_heading``); a forced heading not reached
        MIS_YAW_TMT after the arrival fails the mission."""
        s, p = self._step, self.params
        timeout = p["MIS_YAW_TMT"]
        if rtl_heading_accepted(
            s.yaw, st.yaw, p["MIS_YAW_ERR"], timeout, self.yaw_acceptance, forced=s.force_heading
        ):
            return True
        if s.force_heading and timeout >= FLT_EPSILON and now - s.reached_at >= timeout:
            self._mission_failure_heading_timeout()
        return False

    def _mission_failure_heading_timeout(self) -> None:
        """Navigator::set_mission_failure_heading_timeout: mission_result.failure, said once."""
        if not self.failure:
            self.failure = True
            text = (MavSeverity.CRITICAL, "unable to reach heading within timeout")
            self.events.append(Event(EventKind.TEXT, text))
            self.events.append(Event(EventKind.FAILURE))

    # ------------------------------------------------------------------ return to launch

    @property
    def home(self) -> tuple[float, float, float]:
        """home_position's local x, y, z."""
        return self._home

    @home.setter
    def home(self, value: tuple[float, ...]) -> None:
        """Set home: x, y, z and optionally its heading (home_position.yaw: the heading when home
        was set, ``HomePosition::fillLocalHomePos``); without one it is taken from the state the
        next mode starts with (``enter``)."""
        self._home = (value[0], value[1], value[2])
        self.home_yaw = value[3] if len(value) > 3 else math.nan

    def _rtl_start(self, st: State, now: float) -> _Rtl:
        """RTL::on_activation (RTL_TYPE 0): the destination, the return altitude and its text, and
        RtlDirect::getActivationLandState: climb when below the return altitude, else return."""
        p = self.params
        hx, hy, hz = self.home
        if self.rally:  # RTL_TYPE 0: the closest of home and the rally points
            dest = rally_destination(self.rally, (st.x, st.y), (hx, hy))
            if dest is not None:
                hx, hy = dest[0], dest[1]
        # PX4 keeps the altitudes AMSL in float32 (home_position.alt, vehicle_global_position.alt)
        dest_amsl = f32(self.home_alt - hz)
        alt_amsl = f32(self.home_alt - st.z)
        rtl_amsl = f32(
            rtl_return_altitude(
                math.hypot(st.x - hx, st.y - hy),
                dest_amsl,
                alt_amsl,
                return_alt=p["RTL_RETURN_ALT"],
                cone_half_angle_deg=int(p["RTL_CONE_ANG"]),
                min_dist=p["RTL_MIN_DIST"],
                acc_rad=p["NAV_ACC_RAD"],
            )
        )
        self.events.append(Event(EventKind.TEXT, (MavSeverity.INFO, rtl_start_text(rtl_amsl, dest_amsl))))
        alt = rtl_amsl - self.home_alt
        # RtlDirect::sanitizeLandApproach: RTL_DESCEND_ALT above the destination, not above the
        # return altitude (set_rtl_item's loiter_altitude)
        land_alt = min(dest_amsl - self.home_alt + p["RTL_DESCEND_ALT"], alt)
        # CLIMBING: a loiter-to-altitude where Return started, facing the heading it had then
        r = _Rtl("climb", alt, now, hx, hy, land_alt=land_alt, yaw=st.yaw, cx=st.x, cy=st.y)
        if st.landed:
            r.phase = "done"  # for safety, no Return from the ground (IDLE)
        elif not alt_amsl < rtl_amsl:
            self._rtl_return(r, st)
        return r

    def _rtl_return(self, r: _Rtl, st: State) -> None:
        """RtlDirect::set_rtl_item MOVE_TO_LOITER: to the destination at the return altitude; the
        heading is left to FlightTaskAuto (MPC_YAW_MODE: facing the destination), or is already
        the destination's (home's) when the return starts within RTL_MIN_DIST of it."""
        close = math.hypot(st.x - r.x, st.y - r.y) < self.params["RTL_MIN_DIST"]
        r.phase = "return"
        r.yaw = self.home_yaw if close else math.nan

    def _rtl_heading(self, r: _Rtl, st: State) -> bool:
        """The current RTL item's heading is reached (rtl.py ``rtl_heading_accepted``)."""
        p = self.params
        return rtl_heading_accepted(r.yaw, st.yaw, p["MIS_YAW_ERR"], p["MIS_YAW_TMT"], self.yaw_acceptance)

    def _rtl(self, r: _Rtl, st: State, now: float) -> Goal:
        """RtlDirect::on_active: each item flown until is_mission_item_reached_or_completed, then
        set_rtl_item's next one."""
        p = self.params
        hx, hy = r.x, r.y
        alt_rad = p["NAV_MC_ALT_RAD"]
        if r.phase == "climb":
            if st.landed:
                r.phase = "done"
            elif -st.z < r.alt - alt_rad or not self._rtl_heading(r, st):
                return self._goal_set(GoalKind.POSITION, r.cx, r.cy, -r.alt, r.yaw)
            else:
                self._rtl_return(r, st)
        if r.phase == "return":
            far = math.hypot(st.x - hx, st.y - hy) > p["NAV_ACC_RAD"]
            if far or abs(-st.z - r.alt) > alt_rad or not self._rtl_heading(r, st):
                return self._goal_set(GoalKind.POSITION, hx, hy, -r.alt, r.yaw)
            # LOITER_DOWN: down to the loiter altitude, turning to the destination's heading
            r.phase, r.yaw = "descend", self.home_yaw
        if r.phase == "descend":
            if abs(-st.z - r.land_alt) > alt_rad or not self._rtl_heading(r, st):
                return self._goal_set(GoalKind.POSITION, hx, hy, -r.land_alt, r.yaw)
            # LOITER_HOLD: RTL_LAND_DELAY there (negative: for ever); setLoiterHoldMissionItem
            # leaves the heading to FlightTaskAuto, which holds it within the acceptance radius
            r.phase, r.since, r.yaw = "loiter", now, math.nan
            if rtl_loiters_forever(p["RTL_LAND_DELAY"]):
                self.events.append(Event(EventKind.TEXT, (MavSeverity.INFO, "RTL: completed, loitering")))
        if r.phase == "loiter":
            delay = p["RTL_LAND_DELAY"]
            if rtl_loiters_forever(delay) or now - r.since < delay:
                return self._goal_set(GoalKind.POSITION, hx, hy, -r.land_alt)
            # MOVE_TO_LAND_HOVER: over the destination, facing its heading
            r.phase, r.yaw = "approach", self.home_yaw
        if r.phase == "approach":
            far = math.hypot(st.x - hx, st.y - hy) > p["NAV_ACC_RAD"]
            if far or abs(-st.z - r.land_alt) > alt_rad or not self._rtl_heading(r, st):
                return self._goal_set(GoalKind.POSITION, hx, hy, -r.land_alt, r.yaw)
            r.phase = "land"
            self.events.append(Event(EventKind.TEXT, (MavSeverity.INFO, "RTL: land at destination")))
        if r.phase == "land":
            if st.landed:
                r.phase = "done"
            else:
                g = self._goal_set(GoalKind.LAND, hx, hy, st.z, r.yaw)
                g.alt_amsl = self.home_alt  # RtlDirect's land item: the destination's altitude
                return g
        return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
