"""A mission that ends in the air, as PX4 v1.15 ends it.

The navigator says "Mission finished, loitering" (MissionBase::advance_mission) and sets a loiter
at the current position (setEndOfMissionItems; at the loiter item's position when the last item
was one); the commander then switches the user's mode to Hold (Commander.cpp
checkForMissionUpdate), which keeps that loiter point. HEARTBEAT reports AUTO / LOITER.
"""

from __future__ import annotations

import math

from uavtest.px4.modes import AutoSubMode, MainMode, NavState, split_custom_mode
from uavtest.sitl.mav import MavCmd
from uavtest.sitl.mission import from_spec
from uavtest.spec.models import Home, MissionItem, MissionItemKind

from .test_battery_failures import Flight

HOME = Home()


def _fly(items: list[MissionItem]) -> Flight:
    f = Flight()
    f.v.load_mission(from_spec(items))
    f.fly(5, until=lambda v: v.ready)
    f.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    f.command(MavCmd.DO_SET_MODE, 1, 4, 4)
    f.fly(90, until=lambda v: v.nav.finished)
    assert f.v.nav.finished
    return f


def test_a_mission_ending_in_the_air_switches_to_hold_where_it_finished():
    f = _fly(
        [
            MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=5),
            MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0002, lon=HOME.lon, alt=6),
        ]
    )
    v = f.v
    where = (v.st.x, v.st.y, v.st.z)  # the estimate when the last waypoint was accepted
    assert f.texts[-1][1] == "Mission finished, loitering"
    assert v.nav_state == NavState.AUTO_LOITER and v.user_nav_state == NavState.AUTO_LOITER
    f.fly(15)
    assert v.armed and v.nav_state == NavState.AUTO_LOITER
    assert split_custom_mode(f.last["HEARTBEAT"].fields["custom_mode"]) == (MainMode.AUTO, AutoSubMode.LOITER)
    # held there, not at the waypoint: within EKF2's wander (its tilt error leans the hover)
    assert math.dist((v.st.x, v.st.y, v.st.z), where) < 0.75
    wp = v.proj.project(HOME.lat + 0.0002, HOME.lon)
    assert math.dist(wp, where[:2]) > 0.5  # accepted short of it (NAV_ACC_RAD)
    assert [s for _, s in f.texts].count("Mission finished, loitering") == 1


def test_ending_on_a_loiter_item_holds_at_the_item():
    f = _fly(
        [
            MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=5),
            MissionItem(kind=MissionItemKind.LOITER_TIME, lat=HOME.lat + 0.0001, lon=HOME.lon, alt=7, hold=2),
        ]
    )
    v = f.v
    assert v.nav_state == NavState.AUTO_LOITER and f.said("Mission finished, loitering")
    f.fly(10)
    x, y = v.proj.project(HOME.lat + 0.0001, HOME.lon)
    assert math.dist((v.st.x, v.st.y, v.st.z), (x, y, -7.0)) < 0.5


def test_a_mission_ending_with_return_says_nothing_of_loitering():
    f = _fly(
        [
            MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=5),
            MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0001, lon=HOME.lon, alt=5),
            MissionItem(kind=MissionItemKind.RETURN),
        ]
    )
    assert f.v.nav_state == NavState.AUTO_RTL and not f.said("Mission finished")
