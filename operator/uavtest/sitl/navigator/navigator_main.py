"""What the vehicle should do now: PX4's navigator for mission, hold, takeoff, land and return.

Pure logic: fed the estimated state and the clock, it returns the controller's ``Goal`` and
queues events (mission item reached, mission finished, status texts). PX4 behaviour kept:

- takeoff to the item's altitude (``MIS_TAKEOFF_ALT`` is Takeoff mode's default, not a minimum, in
  PX4 v1.15), done within ``NAV_MC_ALT_RAD``;
- a waypoint is reached within its acceptance radius (``NAV_ACC_RAD`` unless the item sets one)
  and ``NAV_MC_ALT_RAD``; an item with a heading (param4, degrees) then waits until the heading
  error is below ``MIS_YAW_ERR`` (or ``MIS_YAW_TMT`` passes) before it counts as reached, one
  without (NaN, as QGC and the runner send) is reached at once (PX4 v1.15's
  ``get_yaw_to_be_accepted``); then it holds ``param1`` seconds;
- a waypoint is flown along the track from the previous one (``Goal.prev``, PX4's
  position_setpoint_triplet.previous): the controller's FlightTaskAuto states (offtrack, ...);
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
from uavtest.sitl.navigator.rtl import (
    f32,
    rtl_heading_accepted,
    rtl_loiters_forever,
    rtl_return_altitude,
    rtl_start_text,
)
from uavtest.sitl.params import ParamStore
from uavtest.sitl.uorb import GeofenceResult

__all__ = ["Event", "EventKind", "Navigator", "State"]

#: items whose successor becomes the triplet's next unless they hold (param1) or stop
_PASS_THROUGH = frozenset({MavCmd.NAV_WAYPOINT, MavCmd.NAV_LOITER_TIME})


class EventKind(Enum):
    REACHED = "reached"  # value: seq
    CURRENT = "current"  # value: seq
    FINISHED = "finished"
    TEXT = "text"  # value: (severity, text)
    HOLD = "hold"  # the navigator asks the commander to switch to hold (after takeoff)
    RTL = "rtl"  # a mission RTL item: vehicle_command NAV_RETURN_TO_LAUNCH (commander → Return)


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
    extra: dict[str, float] = field(default_factory=dict)


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
        self.mission_feasible = True  # the mission passes the geofence
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
        """MissionFeasibilityChecker::checkMissionAgainstGeofence: every waypoint inside the fence."""
        p = self.params
        gf = self.geofence
        max_hor, max_ver = p["GF_MAX_HOR_DIST"], p["GF_MAX_VER_DIST"]
        ok = True
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

    def geofence_breach_check(self, st: State, t_us: int) -> GeofenceResult | None:
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
                s.x, s.y = st.x, st.y
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
        """Start flying a mode from the current state (a hold keeps ``hold_z`` when given)."""
        self.nav_state = nav_state
        self._step = _Step(since=now, x=st.x, y=st.y, z=st.z if hold_z is None else hold_z, yaw=st.yaw)
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
        elif nav_state == NavState.ORBIT:
            self.orbit.activate(st.x, st.y, st.z, st.yaw)
        if math.isnan(self.home_yaw):
            # home came without its heading: the commander sets home and then starts the mode in
            # the same step (arming), so the state seen here is the one home was set from
            self.home_yaw = st.yaw

    # ------------------------------------------------------------------ the tick

    def update(self, st: State, now: float) -> Goal:
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
            return self._goal_set(GoalKind.LAND, s.x, s.y, st.z, s.yaw)
        if ns == NavState.AUTO_RTL:
            if s.rtl is None:
                s.rtl = self._rtl_start(st, now)
            return self._rtl(s.rtl, st, now)
        if st.landed:
            return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
        if ns == NavState.ORBIT:
            return self.orbit.update(st.x, st.y, st.z, st.yaw, self.params["NAV_MC_ALT_RAD"], self._goal)
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

    def _advance(self, st: State, now: float, *, report: bool = True) -> None:
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
            self._finish()

    def _finish(self) -> None:
        if not self.finished:
            self.finished = True
            self.events.append(Event(EventKind.FINISHED))
        self._step.phase = Phase.DONE

    def _mission(self, st: State, now: float) -> Goal:
        s = self._step
        if not self.mission or s.phase == Phase.DONE or self.current >= len(self.mission):
            if self.mission and not self.finished:
                self._finish()
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
                self._advance(st, now)
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
                if cmd == MavCmd.NAV_TAKEOFF:
                    s.x, s.y = st.x, st.y
                    s.phase = Phase.TAKEOFF
                    # the item's heading (param4); NaN: FlightTaskAuto's MPC_YAW_MODE decides
                    s.yaw = math.radians(item.param4) if math.isfinite(item.param4) else math.nan
                    self.events.append(
                        Event(EventKind.TEXT, (MavSeverity.INFO, f"Climb to {-s.z:.1f} meters above home"))
                    )
                elif cmd == MavCmd.NAV_LAND:
                    # MissionBase::handleLanding MOVE_TO_LAND: at the current position setpoint's
                    # altitude (the previous item's), else the current altitude
                    prev = self._goal
                    held = prev.kind in (GoalKind.POSITION, GoalKind.TAKEOFF) and not st.landed
                    s.z = prev.z if held else st.z
                    s.phase = Phase.FLY
                elif st.landed:
                    s.extra.update(after_takeoff=1.0, tx=st.x, ty=st.y)
                    s.phase = Phase.TAKEOFF
                    s.yaw = math.nan  # Mission's climb work item: "FlightTaskAuto handles yaw directly"
                else:
                    s.phase = Phase.FLY
        if s.phase == Phase.TAKEOFF:
            if "after_takeoff" in s.extra:  # implicit takeoff before the first waypoint
                target_z = s.z  # the first position item's altitude (MissionBase's climb)
                if st.landed or abs(st.z - target_z) > p["NAV_MC_ALT_RAD"]:
                    return self._goal_set(GoalKind.TAKEOFF, s.extra["tx"], s.extra["ty"], target_z, s.yaw)
                s.phase = Phase.FLY
            else:
                if st.landed or abs(st.z - s.z) > p["NAV_MC_ALT_RAD"]:
                    return self._goal_set(GoalKind.TAKEOFF, s.x, s.y, s.z, s.yaw)
                s.yaw = st.yaw
                self._advance(st, now)
                return self._mission(st, now)
        if s.phase == Phase.FLY:
            radius = p["NAV_ACC_RAD"]
            if cmd == MavCmd.NAV_WAYPOINT and item.param2 > 0:
                radius = item.param2
            dxy = math.hypot(s.x - st.x, s.y - st.y)
            dz = abs(s.z - st.z)
            if dxy <= radius and (cmd == MavCmd.NAV_LAND or dz <= p["NAV_MC_ALT_RAD"]):
                if cmd == MavCmd.NAV_LAND:
                    self.reached = self.current
                    self.events.append(Event(EventKind.REACHED, self.current))
                    s.phase = Phase.DESCEND
                else:
                    # MissionBlock::is_mission_item_reached_or_completed: the heading is waited
                    # for only when the item carries one (param4); QGC and the runner send NaN,
                    # so PX4 accepts the waypoint at once and FlightTaskAuto turns on the way on
                    s.phase = Phase.YAW
                    s.since = now
                    s.yaw = math.radians(item.param4) if math.isfinite(item.param4) else math.nan
            else:
                g = self._goal_set(GoalKind.POSITION, s.x, s.y, s.z)
                if "prev_x" in s.extra:
                    g.prev = (s.extra["prev_x"], s.extra["prev_y"], s.extra["prev_z"])
                g.acc_rad = radius
                # Mission::setActiveMissionItems: a waypoint without a hold time hands its
                # successor to the triplet's next, so the trajectory turns through the corner
                # instead of stopping (a hold time or autocontinue 0 brakes: next invalid)
                if cmd in _PASS_THROUGH and item.param1 <= 0 and item.autocontinue:
                    if s.next is None:  # once per item
                        s.next = self._next_setpoint(self.current, st) or NO_NEXT
                    g.next = s.next
                return g
        if s.phase == Phase.YAW:
            err = abs(wrap_pi(s.yaw - st.yaw)) if math.isfinite(s.yaw) else 0.0
            timeout = p["MIS_YAW_TMT"]
            if not math.isfinite(s.yaw):
                s.yaw = st.yaw  # the heading held while the item's hold time runs
            if (
                not self.yaw_acceptance
                or err <= math.radians(p["MIS_YAW_ERR"])
                or (timeout > 0 and now - s.since >= timeout)
            ):
                s.phase = Phase.HOLD
                s.since = now
            else:
                return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
        if s.phase == Phase.HOLD:
            if cmd == MavCmd.NAV_LOITER_UNLIM:
                return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
            hold = item.param1 if cmd in (MavCmd.NAV_WAYPOINT, MavCmd.NAV_LOITER_TIME) else 0.0
            if now - s.since < hold:
                return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)
            self._advance(st, now)
            return self._mission(st, now)
        if s.phase == Phase.DESCEND:
            if st.landed:
                self._finish()
                return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
            return self._goal_set(GoalKind.LAND, s.x, s.y, st.z, s.yaw)
        return self._goal_set(GoalKind.POSITION, s.x, s.y, s.z, s.yaw)

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
                return self._goal_set(GoalKind.LAND, hx, hy, st.z, r.yaw)
        return self._goal_set(GoalKind.IDLE, st.x, st.y, 0.0)
