"""PX4 v1.15 navigator semantics, item by item: a waypoint's hold time and heading
(mission_block.cpp is_mission_item_reached_or_completed), a takeoff item's position
(mission.cpp Mission::handleTakeoff), Hold's braking stop (loiter.cpp set_loiter_position,
navigator_main.cpp calculate_breaking_stop) and a loiter item's braking (FlightTaskAuto.cpp
_evaluateTriplets). Most drive the navigator alone with made-up states and a simulated clock;
the flights check the outcome on the built-in vehicle."""

from __future__ import annotations

import dataclasses
import math

import pytest

from uavtest.px4.modes import AutoSubMode, MainMode, NavState
from uavtest.sitl.geo import Projection
from uavtest.sitl.inprocess import _command
from uavtest.sitl.mav import MavCmd, MavFrame, MavSeverity
from uavtest.sitl.mc_pos_control import GoalKind
from uavtest.sitl.mission import NavItem, from_spec
from uavtest.sitl.navigator import Event, EventKind, Navigator, State
from uavtest.sitl.navigator.navigator_main import braking_distance
from uavtest.sitl.params import ParamStore
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.mission import mission_items
from uavtest.spec.models import Home, UavTestSpec

HOME = Home()
PROJ = Projection(HOME.lat, HOME.lon)
REL = MavFrame.GLOBAL_RELATIVE_ALT_INT
DT = 0.02


def at(seq: int, cmd: int, north: float, east: float, alt: float = 10.0, **params: float) -> NavItem:
    lat, lon = PROJ.reproject(north, east)
    return NavItem(seq, cmd, REL, x=round(lat * 1e7), y=round(lon * 1e7), z=alt, **params)


def navigator(items: list[NavItem], st: State, **params: float) -> Navigator:
    nav = Navigator(ParamStore(params), PROJ, HOME.alt)
    nav.set_mission(items)
    nav.enter(NavState.AUTO_MISSION, st, 0.0)
    nav.events.clear()
    return nav


def run(nav: Navigator, st: State, t0: float, t1: float) -> list[tuple[float, Event]]:
    """The navigator's events, timed, from ``t0`` to ``t1`` (50 Hz) with the vehicle at ``st``."""
    out: list[tuple[float, Event]] = []
    for k in range(round((t1 - t0) / DT)):
        now = t0 + k * DT
        nav.update(st, now)
        out += [(now, e) for e in nav.events]
        nav.events.clear()
    return out


def reached(events: list[tuple[float, Event]], seq: int) -> float | None:
    return next((t for t, e in events if e.kind is EventKind.REACHED and e.value == seq), None)


def texts(events: list[tuple[float, Event]]) -> list[str]:
    return [e.value[1] for _, e in events if e.kind is EventKind.TEXT]  # type: ignore[index]


# ---------------------------------------------------------------- 1. hold time and heading


def _on_the_waypoint(item: NavItem, **params: float) -> tuple[Navigator, State]:
    """Hovering on ``item`` (seq 1, 10 m up) facing North, item 0 behind it already reached."""
    st = State(x=0.0, y=0.0, z=-10.0, yaw=0.0, landed=False)
    nav = navigator(
        [at(0, MavCmd.NAV_WAYPOINT, 0.0, 0.0), item, at(2, MavCmd.NAV_WAYPOINT, 0.0, 50.0)], st, **params
    )
    nav.set_current(1)
    nav.events.clear()
    return nav, st


def test_the_hold_time_counts_from_the_arrival_not_from_the_heading():
    """A 5 s hold on a waypoint whose heading (South) takes 3 s to reach: PX4 leaves 5 s after
    arriving (_time_wp_reached), not 3 + 5 s."""
    nav, st = _on_the_waypoint(at(1, MavCmd.NAV_WAYPOINT, 0.0, 0.0, param1=5.0, param4=180.0))
    events = run(nav, st, 0.0, 3.0)  # still facing North: the heading is not reached
    assert reached(events, 1) is None
    assert nav.update(st, 3.0).yaw == pytest.approx(math.pi)  # the setpoint's yaw is the item's
    st.yaw = math.pi
    events = run(nav, st, 3.0, 10.0)
    assert reached(events, 1) == pytest.approx(5.0, abs=DT)


def test_a_heading_is_waited_for_without_mis_yaw_tmt():
    """MIS_YAW_TMT -1 (PX4's default): the item waits for its heading however long it takes."""
    nav, st = _on_the_waypoint(at(1, MavCmd.NAV_WAYPOINT, 0.0, 0.0, param4=180.0))
    assert reached(run(nav, st, 0.0, 60.0), 1) is None
    st.yaw = math.radians(170.0)  # within MIS_YAW_ERR (12 degrees)
    assert reached(run(nav, st, 60.0, 61.0), 1) == pytest.approx(60.0)


def test_mis_yaw_tmt_accepts_an_unforced_heading_at_once():
    nav, st = _on_the_waypoint(at(1, MavCmd.NAV_WAYPOINT, 0.0, 0.0, param4=180.0), MIS_YAW_TMT=3.0)
    events = run(nav, st, 0.0, 1.0)
    assert reached(events, 1) == 0.0
    assert not nav.failure


def test_a_forced_heading_not_reached_within_mis_yaw_tmt_fails_the_mission():
    """A LOITER_TIME with param2 1 (heading required) facing the wrong way: after MIS_YAW_TMT PX4
    says "unable to reach heading within timeout" and sets mission_result.failure, once; the item
    is not reached."""
    item = at(1, MavCmd.NAV_LOITER_TIME, 0.0, 0.0, param1=0.0, param2=1.0, param4=90.0)
    nav, st = _on_the_waypoint(item, MIS_YAW_TMT=3.0)
    events = run(nav, st, 0.0, 2.9)
    assert not nav.failure and not texts(events)
    events = run(nav, st, 2.9, 10.0)
    assert nav.failure and reached(events, 1) is None
    assert texts(events) == ["unable to reach heading within timeout"]
    assert [e.value for _, e in events if e.kind is EventKind.TEXT] == [
        (MavSeverity.CRITICAL, "unable to reach heading within timeout")
    ]
    assert sum(e.kind is EventKind.FAILURE for _, e in events) == 1
    nav.set_mission(nav.mission)  # a new mission clears it (MissionBase::check_mission_valid)
    assert not nav.failure


def test_a_waypoint_is_flown_to_facing_its_heading():
    """FlightTaskAuto takes the triplet's yaw when finite: the vehicle turns on the way there."""
    st = State(x=0.0, y=0.0, z=-10.0, yaw=0.0, landed=False)
    items = [at(0, MavCmd.NAV_WAYPOINT, 0.0, 0.0), at(1, MavCmd.NAV_WAYPOINT, 50.0, 0.0, param4=270.0)]
    nav = navigator(items, st)
    run(nav, st, 0.0, 0.1)
    assert nav.current == 1
    assert nav.update(st, 0.2).yaw == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize(("yaw", "facing"), [(None, 0.0), (90.0, 90.0), (-135.0, -135.0)])
def test_a_test_files_waypoint_heading_is_flown(yaw: float | None, facing: float):
    """``mission.waypoints[].yaw`` goes to the vehicle as param4 (degrees, as QGC and PX4 read
    it): the vehicle holds at the waypoint facing it; without one it faces the waypoint it flew
    to (MPC_YAW_MODE 0), here North."""
    wp: dict[str, float] = {"x": 20.0, "y": 0.0, "z": -5.0, "hold": 20.0}
    if yaw is not None:
        wp["yaw"] = yaw
    spec = UavTestSpec.model_validate({"mission": {"takeoffAltitude": 5, "waypoints": [wp], "land": False}})
    v = Vehicle(dataclasses.replace(SimConfig.from_spec(spec, 1), links=()), None)
    v.load_mission(from_spec(mission_items(spec)))
    v.fly_until(lambda v: v.ready, 10_000_000)
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 1.0) == 0
    _command(v, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.MISSION))
    v.fly_until(lambda v: math.hypot(v.st.x - 20.0, v.st.y) < 0.5 and -v.st.z > 4.5, 40_000_000)
    v.fly_until(lambda v: False, 8_000_000)
    heading = math.degrees(v.st.yaw)
    # the heading locks on the last approach, which EKF2's errors turn by a few degrees
    assert abs((heading - facing + 180.0) % 360.0 - 180.0) < 10.0, heading


# ---------------------------------------------------------------- 2. the takeoff item's position


def test_a_takeoff_after_a_waypoint_is_refused_as_px4s_feasibility_checker_does():
    """An ArduPilot-style QGC WPL file (MAVProxy's ``wp load``) sends home as item 0, a waypoint
    where the vehicle stands, then the takeoff: PX4 v1.15 refuses that mission ("Mission
    rejected: takeoff not first waypoint item", FeasibilityChecker::checkTakeoff), so it is not
    valid and MISSION_START is denied (PX4 SIH, ``tests/integration/test_ground_waypoint_against_px4.py``)."""
    st = State(x=0.0, y=0.0, z=0.02, yaw=0.0, landed=True)
    items = [at(0, MavCmd.NAV_WAYPOINT, 0.0, 0.0, 0.0), at(1, MavCmd.NAV_TAKEOFF, 0.0, 0.0, 5.0)]
    nav = navigator(items, st)
    assert not nav.mission_valid
    nav.check_mission_feasible()  # said at each check (the upload's was cleared above)
    assert texts([(0.0, e) for e in nav.events]) == ["Mission rejected: takeoff not first waypoint item"]
    nav.set_mission([items[1], dataclasses.replace(items[0], seq=1, z=5.0)])  # takeoff first: fine
    assert nav.mission_valid


def test_a_waypoint_is_never_reached_on_the_ground():
    """MissionBlock::is_mission_item_reached_or_completed updates "waypoint position reached" only
    while not landed: a mission started on the ground whose first item is a waypoint where the
    vehicle stands (no climb owed: checkClimbRequired) stays on it, on the ground, and PX4 SIH
    then disarms (COM_DISARM_PRFLT)."""
    st = State(x=0.0, y=0.0, z=0.02, yaw=0.0, landed=True)
    items = [at(0, MavCmd.NAV_WAYPOINT, 0.0, 0.0, 0.0), at(1, MavCmd.NAV_WAYPOINT, 15.0, 0.0, 5.0)]
    nav = navigator(items, st)
    assert nav.mission_valid
    events = run(nav, st, 0.0, 5.0)
    assert reached(events, 0) is None and nav.current == 0
    assert not any(t.startswith("Climb to") for t in texts(events))
    g = nav.update(st, 5.0)
    assert g.kind is GoalKind.POSITION and g.z == pytest.approx(0.0, abs=0.05)


def test_a_takeoff_item_climbs_then_flies_to_its_position():
    """Mission::handleTakeoff: a TAKEOFF setpoint above where the vehicle stands (the item as
    next), then the item as a waypoint from there (previous: the climb's setpoint); the item is
    reached at its position, not at the top of the climb."""
    st = State(x=0.0, y=0.0, z=0.0, yaw=0.0, landed=True)
    items = [at(0, MavCmd.NAV_TAKEOFF, 5.0, 0.0, 10.0, param4=90.0), at(1, MavCmd.NAV_WAYPOINT, 5.0, 40.0)]
    nav = navigator(items, st)
    g = nav.update(st, 0.0)
    assert (g.kind, g.x, g.y, g.z) == (GoalKind.TAKEOFF, 0.0, 0.0, -10.0)
    assert math.isnan(g.yaw)  # the item's yaw is ignored ("FlightTaskAuto handles yaw directly")
    assert texts([(0.0, e) for e in nav.events]) == ["Climb to 10.0 meters above home"]
    st.z, st.landed = -9.5, False
    events = run(nav, st, 0.02, 1.0)
    assert reached(events, 0) is None
    g = nav.update(st, 1.0)
    assert g.kind is GoalKind.POSITION and (g.x, g.y, g.z) == pytest.approx((5.0, 0.0, -10.0), abs=0.01)
    assert g.prev == (0.0, 0.0, -10.0) and g.next == pytest.approx((5.0, 40.0, -10.0), abs=0.01)
    assert math.isnan(g.yaw)
    st.x = 4.0  # within NAV_ACC_RAD (2 m)
    events = run(nav, st, 1.02, 1.1)
    assert reached(events, 0) == pytest.approx(1.02)
    g = nav.update(st, 1.1)
    assert g.prev == pytest.approx((5.0, 0.0, -10.0), abs=0.01) and g.y == pytest.approx(40.0, abs=0.01)


def test_a_flying_vehicle_climbs_to_the_first_item_before_heading_for_it():
    """MissionBase::checkClimbRequired on activation: 5 m below the first waypoint, the vehicle
    climbs where it is (LOITER_TO_ALT), then flies the leg."""
    st = State(x=0.0, y=0.0, z=-5.0, yaw=0.0, landed=False)
    nav = navigator([at(0, MavCmd.NAV_WAYPOINT, 30.0, 0.0)], st)
    g = nav.update(st, 0.0)
    assert (g.kind, g.x, g.y, g.z) == (GoalKind.POSITION, 0.0, 0.0, -10.0)
    st.z = -9.5
    g = nav.update(st, 0.1)
    assert (g.x, g.y, g.z) == pytest.approx((30.0, 0.0, -10.0), abs=0.01)


def test_the_vehicle_flies_to_a_takeoff_item_away_from_home():
    """A takeoff item 6 m North of home: the built-in vehicle climbs, then comes within
    NAV_ACC_RAD of the item before it is reported reached (PX4 v1.15 SIH's log: a TAKEOFF
    setpoint at the vehicle, then a POSITION setpoint at the item, then the item reached)."""
    items = [at(0, MavCmd.NAV_TAKEOFF, 6.0, 0.0, 8.0), at(1, MavCmd.NAV_LAND, 6.0, 0.0, 0.0)]
    v = Vehicle(
        dataclasses.replace(SimConfig(home=HOME, params={"NAV_ACC_RAD": 1.0}, seed=3), links=()), None
    )
    v.load_mission(items)
    v.fly_until(lambda v: v.ready, 10_000_000)
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 1.0) == 0
    _command(v, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.MISSION))
    top = None
    for _ in range(2000):
        out = v.advance(v.time_us + 20_000)
        if top is None and -v.st.z > 7.0:
            top = (v.st.x, v.st.y)
        if any(m.name == "MISSION_ITEM_REACHED" and int(m.fields["seq"]) == 0 for m in out):
            break
    else:
        raise AssertionError("the takeoff item was never reached")
    assert top is not None and math.hypot(*top) < 1.5  # climbed above home
    assert math.hypot(v.st.x - 6.0, v.st.y) <= 1.0 and -v.st.z > 7.0


# ---------------------------------------------------------------- 3. Hold's braking stop


def test_braking_distance_is_px4s():
    """computeBrakingDistanceFromVelocity(v, MPC_JERK_AUTO, MPC_ACC_HOR, 0.6 MPC_JERK_AUTO)."""
    assert braking_distance(5.0, 4.0, 3.0) == pytest.approx(5.0 * (5.0 / 6.0 + 0.6))
    assert braking_distance(0.0, 4.0, 3.0) == 0.0


def test_hold_while_flying_holds_at_the_braking_stop():
    st = State(x=10.0, y=20.0, z=-10.0, yaw=0.0, landed=False, vx=3.0, vy=4.0)  # 5 m/s
    nav = Navigator(ParamStore(), PROJ, HOME.alt)
    nav.enter(NavState.POSCTL, st, 0.0)
    nav.enter(NavState.AUTO_LOITER, st, 1.0)
    g = nav.update(st, 1.0)
    d = 5.0 * (5.0 / 6.0 + 0.6)
    assert (g.kind, g.x, g.y, g.z) == pytest.approx(
        (GoalKind.POSITION, 10.0 + 0.6 * d, 20.0 + 0.8 * d, -10.0)
    )


def test_hold_on_a_loiter_item_keeps_its_position():
    """Loiter::set_loiter_position: already within NAV_ACC_RAD + NAV_LOITER_RAD of a loiter
    setpoint, Hold keeps it (setLoiterItemFromCurrentPositionSetpoint)."""
    st = State(x=0.0, y=0.0, z=-10.0, yaw=0.0, landed=False, vx=5.0)
    nav = navigator([at(0, MavCmd.NAV_LOITER_UNLIM, 30.0, 0.0)], st)
    nav.update(st, 0.0)
    nav.enter(NavState.AUTO_LOITER, st, 1.0)
    assert (nav.update(st, 1.0).x, nav.update(st, 1.0).y) == pytest.approx((30.0, 0.0), abs=0.01)


def test_the_vehicle_switched_to_hold_at_speed_stops_ahead_and_stays():
    """The built-in vehicle flying a 60 m leg is switched to Hold: it settles where it could stop
    (about v (v / 2 MPC_ACC_HOR + 0.6) ahead), not back where the switch happened."""
    items = [at(0, MavCmd.NAV_TAKEOFF, 0.0, 0.0, 10.0), at(1, MavCmd.NAV_WAYPOINT, 80.0, 0.0, 10.0)]
    v = Vehicle(dataclasses.replace(SimConfig(home=HOME, seed=3), links=()), None)
    v.load_mission(items)
    v.fly_until(lambda v: v.ready, 10_000_000)
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 1.0) == 0
    _command(v, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.MISSION))
    v.fly_until(lambda v: v.st.x > 30.0, 60_000_000)
    speed = math.hypot(v.st.vx, v.st.vy)
    assert speed > 3.0
    switched = v.st.x
    _command(v, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.LOITER))
    assert v.nav_state == NavState.AUTO_LOITER
    v.fly_until(lambda v: False, 10_000_000)
    ahead = braking_distance(speed, 4.0, 3.0)
    assert v.st.x - switched == pytest.approx(ahead, abs=1.0)
    held = v.st.x
    v.fly_until(lambda v: False, 5_000_000)
    assert v.st.x == pytest.approx(held, abs=0.5)


# ---------------------------------------------------------------- 4. a loiter item brakes


@pytest.mark.parametrize(("cmd", "stops"), [(MavCmd.NAV_WAYPOINT, False), (MavCmd.NAV_LOITER_TIME, True)])
def test_a_loiter_time_item_without_hold_time_still_stops(cmd: int, stops: bool):
    """FlightTaskAuto::_evaluateTriplets: a loiter setpoint's next is its own target, so a
    LOITER_TIME of 0 s is braked onto; a waypoint of 0 s is turned through (next: the item after)."""
    st = State(x=0.0, y=0.0, z=-10.0, yaw=0.0, landed=False)
    items = [
        at(0, MavCmd.NAV_WAYPOINT, 0.0, 0.0),
        at(1, cmd, 30.0, 0.0),
        at(2, MavCmd.NAV_WAYPOINT, 30.0, 30.0),
    ]
    nav = navigator(items, st)
    run(nav, st, 0.0, 0.1)
    g = nav.update(st, 0.2)
    assert nav.current == 1
    assert math.isnan(g.next[0]) is stops
