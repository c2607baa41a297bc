"""NED ⇄ geodetic projection and mission items from waypoints."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uavtest.spec.geo import EARTH_RADIUS, geodetic_to_ned, ned_to_geodetic
from uavtest.spec.mission import mission_items
from uavtest.spec.models import MissionItemKind, UavTestSpec

HOME = (47.397742, 8.545594)


def _haversine_and_bearing(lat0: float, lon0: float, lat: float, lon: float) -> tuple[float, float]:
    """Great-circle distance and initial bearing: an independent formula."""
    p0, p1, dl = math.radians(lat0), math.radians(lat), math.radians(lon - lon0)
    a = math.sin((p1 - p0) / 2) ** 2 + math.cos(p0) * math.cos(p1) * math.sin(dl / 2) ** 2
    distance = 2 * EARTH_RADIUS * math.asin(math.sqrt(a))
    bearing = math.atan2(
        math.sin(dl) * math.cos(p1), math.cos(p0) * math.sin(p1) - math.sin(p0) * math.cos(p1) * math.cos(dl)
    )
    return distance, bearing


@pytest.mark.parametrize(("lat", "lon"), [(47.39768051930175, 8.546310969707491), (47.40, 8.50), (47.2, 8.9)])
def test_projection_keeps_distance_and_bearing_from_home(lat: float, lon: float) -> None:
    # the azimuthal equidistant projection (PX4's) is exact in distance and bearing from its centre
    north, east = geodetic_to_ned(lat, lon, *HOME)
    distance, bearing = _haversine_and_bearing(*HOME, lat, lon)
    assert math.hypot(north, east) == pytest.approx(distance, abs=1e-6)
    assert math.atan2(east, north) == pytest.approx(bearing, abs=1e-9)


def test_projection_round_trip_on_arrays() -> None:
    north = np.array([0.0, 10.0, -250.0, 3000.0])
    east = np.array([0.0, -5.0, 400.0, -1200.0])
    lat, lon = ned_to_geodetic(north, east, *HOME)
    n2, e2 = geodetic_to_ned(lat, lon, *HOME)
    np.testing.assert_allclose(n2, north, atol=1e-6)
    np.testing.assert_allclose(e2, east, atol=1e-6)
    assert ned_to_geodetic(0.0, 0.0, *HOME) == HOME


def test_waypoints_become_takeoff_waypoints_land() -> None:
    spec = UavTestSpec.model_validate(
        {
            "mission": {
                "waypoints": [{"x": 30, "y": 0, "z": -10, "hold": 2}, {"x": 30, "y": 30, "z": -15}],
                "takeoffAltitude": 5,
            }
        }
    )
    items = mission_items(spec)
    assert [i.kind for i in items] == [
        MissionItemKind.TAKEOFF,
        MissionItemKind.WAYPOINT,
        MissionItemKind.WAYPOINT,
        MissionItemKind.LAND,
    ]
    takeoff, first, second, land = items
    assert (takeoff.lat, takeoff.lon, takeoff.alt) == (spec.world.home.lat, spec.world.home.lon, 5)
    assert (first.alt, first.hold, second.alt) == (10, 2, 15)
    north, east = geodetic_to_ned(second.lat, second.lon, spec.world.home.lat, spec.world.home.lon)
    assert (north, east) == (pytest.approx(30, abs=1e-6), pytest.approx(30, abs=1e-6))
    assert (land.lat, land.lon, land.alt) == (second.lat, second.lon, 0)


def test_waypoints_without_landing_and_commands_only() -> None:
    spec = UavTestSpec.model_validate({"mission": {"waypoints": [{"x": 1, "y": 1, "z": -3}], "land": False}})
    assert [i.kind for i in mission_items(spec)] == [MissionItemKind.TAKEOFF, MissionItemKind.WAYPOINT]
    assert mission_items(UavTestSpec.model_validate({"commands": [{"at": 0, "action": "arm"}]})) == []
