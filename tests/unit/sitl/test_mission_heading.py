"""A waypoint's heading, as PX4 v1.15's navigator accepts it
(MissionBlock::is_mission_item_reached_or_completed, Navigator::get_yaw_to_be_accepted): the heading
is waited for only when the item carries one (param4), and turned to on the way there;
an item without (NaN, as QGroundControl and the runner send) is reached as soon as the vehicle is
within NAV_ACC_RAD, whatever its heading."""

from __future__ import annotations

import dataclasses
import math

import pytest

from uavtest.px4.modes import AutoSubMode, MainMode
from uavtest.sitl.geo import Projection
from uavtest.sitl.inprocess import _command
from uavtest.sitl.mav import MavCmd, MavFrame
from uavtest.sitl.mission import NavItem
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Home

HOME = Home()


def _items(param4: float) -> list[NavItem]:
    """Takeoff, 30 m North, a corner to 30 m East (the next leg points East), land there."""
    proj = Projection(HOME.lat, HOME.lon)
    rel = MavFrame.GLOBAL_RELATIVE_ALT_INT

    def at(seq: int, cmd: int, north: float, east: float, alt: float, p4: float = math.nan) -> NavItem:
        lat, lon = proj.reproject(north, east)
        return NavItem(seq, cmd, rel, param4=p4, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)

    return [
        at(0, MavCmd.NAV_TAKEOFF, 0.0, 0.0, 10.0),
        at(1, MavCmd.NAV_WAYPOINT, 30.0, 0.0, 10.0, param4),
        at(2, MavCmd.NAV_WAYPOINT, 30.0, 30.0, 10.0),
        at(3, MavCmd.NAV_LAND, 30.0, 30.0, 0.0),
    ]


def _heading_when_reached(param4: float, seq: int = 1) -> tuple[float, float]:
    """(heading in degrees, seconds since the corner came within 1 m) when item ``seq`` is reached."""
    config = SimConfig(home=HOME, params={"NAV_ACC_RAD": 1.0}, seed=3)
    v = Vehicle(dataclasses.replace(config, links=()), None)
    v.load_mission(_items(param4))
    v.fly_until(lambda v: v.ready, 10_000_000)
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 1.0) == 0
    _command(v, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.MISSION))
    near = None
    for _ in range(3000):
        out = v.advance(v.time_us + 20_000)
        if near is None and math.hypot(v.st.x - 30.0, v.st.y) < 1.0:
            near = v.time_us / 1e6
        for m in out:
            if m.name == "MISSION_ITEM_REACHED" and int(m.fields["seq"]) == seq:
                assert near is not None
                return math.degrees(v.st.yaw) % 360.0, v.time_us / 1e6 - near
    raise AssertionError(f"item {seq} never reached")


def test_a_waypoint_without_heading_is_reached_at_once_whatever_the_heading() -> None:
    heading, waited = _heading_when_reached(math.nan)
    # still facing North along the first leg (MPC_YAW_MODE 0), not yet turned East
    assert heading < 30.0 or heading > 330.0, heading
    assert waited < 1.0


def test_a_waypoint_with_a_heading_is_flown_to_facing_it() -> None:
    """The item's heading is the triplet's yaw, which FlightTaskAuto follows all the way there:
    a 30 m leg is time enough for the 180 deg turn (45 deg/s), so the vehicle arrives within
    MIS_YAW_ERR and is accepted at once (the wait itself: test_navigator_px4_semantics)."""
    heading, waited = _heading_when_reached(180.0)
    assert abs(heading - 180.0) < 12.0, heading  # MIS_YAW_ERR 12 deg
    assert waited < 1.0


def _takeoff_yaw_setpoint(drift_east: float, goal_yaw: float) -> float:
    from uavtest.sitl.mc_pos_control import Controller, Goal, GoalKind, Limits
    from uavtest.sitl.params import ParamStore

    ctrl = Controller(Limits.of(ParamStore({"NAV_ACC_RAD": 0.5})))
    ctrl.reset(0.0, drift_east, -3.0, 0.0, 0.0, 0.0, 0.0)
    goal = Goal(GoalKind.TAKEOFF, x=0.0, y=0.0, z=-10.0, yaw=goal_yaw)
    for _ in range(150):  # 3 s: FlightTaskAuto moves the setpoint at MPC_YAWRAUTO_MAX
        ctrl.update(0.02, goal, 0.0, drift_east, -3.0, 0.0, 0.0, -1.0, 0.0)
    return math.degrees(ctrl.yaw_sp)


def test_a_takeoff_without_heading_turns_to_the_takeoff_point_once_drifted_past_nav_acc_rad() -> None:
    """FlightTaskAuto::_set_heading_from_mode (MPC_YAW_MODE 0) in the takeoff: PX4 v1.15 SIH swings
    round in two of its four mission1 takeoffs."""
    assert _takeoff_yaw_setpoint(0.3, math.nan) == 0.0  # inside the radius: heading held
    assert _takeoff_yaw_setpoint(0.6, math.nan) == pytest.approx(-90.0)  # 0.6 m East: face West, back to it
    assert _takeoff_yaw_setpoint(0.6, math.radians(30.0)) == pytest.approx(30.0)  # the item's heading
