"""PX4 v1.15's FeasibilityChecker for a multicopter: which missions PX4 refuses, and what it says."""

from __future__ import annotations

import pytest

from uavtest.sitl.geo import Projection
from uavtest.sitl.mav import MavCmd, MavFrame
from uavtest.sitl.mission import NavItem
from uavtest.sitl.navigator.mission_feasibility import feasibility_failures
from uavtest.spec.models import Home

HOME = Home()
PROJ = Projection(HOME.lat, HOME.lon)


def at(seq: int, cmd: int, north: float = 0.0, east: float = 0.0, alt: float = 10.0) -> NavItem:
    lat, lon = PROJ.reproject(north, east)
    return NavItem(seq, cmd, MavFrame.GLOBAL_RELATIVE_ALT_INT, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)


def check(items: list[NavItem], *, landed: bool = True, dist_1wp: float = 900.0, req: int = 0) -> list[str]:
    def distance(item: NavItem) -> float:
        x, y = PROJ.project(item.lat, item.lon)
        return (x * x + y * y) ** 0.5

    return feasibility_failures(
        items,
        landed=landed,
        home_amsl=HOME.alt,
        distance_to=distance,
        dist_1wp=dist_1wp,
        takeoff_land_req=req,
    )


TAKEOFF = at(0, MavCmd.NAV_TAKEOFF, alt=5.0)
WAYPOINT = at(1, MavCmd.NAV_WAYPOINT, 30.0)
LAND = at(2, MavCmd.NAV_LAND, 30.0, alt=0.0)


def test_a_plain_mission_passes() -> None:
    assert check([TAKEOFF, WAYPOINT, LAND]) == []
    assert check([WAYPOINT, LAND]) == []  # no takeoff item: PX4 climbs to the first waypoint


def test_a_takeoff_must_come_before_any_item_that_flies_somewhere() -> None:
    home_item = at(0, MavCmd.NAV_WAYPOINT, alt=0.0)  # an ArduPilot-style WPL file's home
    assert check([home_item, TAKEOFF, LAND]) == ["Mission rejected: takeoff not first waypoint item"]
    speed = NavItem(0, MavCmd.DO_CHANGE_SPEED, MavFrame.MISSION, param1=1.0, param2=3.0)
    assert check([speed, TAKEOFF, LAND]) == []  # an action item before it is fine


def test_a_takeoff_at_or_below_home_is_refused() -> None:
    assert check([at(0, MavCmd.NAV_TAKEOFF, alt=0.0), LAND]) == [
        "Mission rejected: Takeoff altitude below home altitude!"
    ]


def test_a_mission_starting_with_a_landing_is_refused_on_the_ground_only() -> None:
    assert check([LAND, WAYPOINT]) == ["Mission rejected: starts with landing"]
    assert check([LAND, WAYPOINT], landed=False) == []


def test_the_first_waypoint_must_be_within_mis_dist_1wp() -> None:
    far = at(1, MavCmd.NAV_WAYPOINT, 1000.5)  # int() truncates, as PX4 prints it
    assert check([far, LAND]) == ["First waypoint too far away: 1000m, 900 max"]
    assert check([far, LAND], dist_1wp=-1.0) == []  # no limit
    assert check([WAYPOINT, far]) == []  # only the first item with a position counts


@pytest.mark.parametrize(
    ("req", "items", "text"),
    [
        (1, [WAYPOINT, LAND], "Mission rejected: Takeoff waypoint required."),
        (2, [TAKEOFF, WAYPOINT], "Mission rejected: Landing waypoint/pattern required."),
        (3, [TAKEOFF, WAYPOINT], "Mission rejected: Takeoff or Landing item missing."),
        (4, [TAKEOFF, WAYPOINT], "Mission rejected: Add Landing item or remove Takeoff."),
        (4, [WAYPOINT, LAND], "Mission rejected: Add Takeoff item or remove Landing."),
        (5, [WAYPOINT, LAND], "Mission rejected: Add Takeoff item or remove Landing."),
        (4, [WAYPOINT], None),
        (3, [TAKEOFF, WAYPOINT, LAND], None),
    ],
)
def test_mis_tko_land_req(req: int, items: list[NavItem], text: str | None) -> None:
    assert check(items, req=req) == ([text] if text else [])


def test_mis_tko_land_req_5_asks_only_for_a_landing_in_the_air() -> None:
    assert check([WAYPOINT], req=5, landed=False) == ["Mission rejected: Landing waypoint/pattern required."]
    assert check([WAYPOINT, LAND], req=5, landed=False) == []
