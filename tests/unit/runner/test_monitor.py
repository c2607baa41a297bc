"""The online monitor agrees with the analysis geometry, and watches the geofence."""

from __future__ import annotations

import math
import random

import pytest

from uavtest.analysis.geometry import min_distance_to_obstacles
from uavtest.runner.events import LocalPosition
from uavtest.runner.monitor import FlightMonitor
from uavtest.spec.models import Geofence, Obstacle


def box(l: float, w: float, h: float, x: float, y: float, z: float = 0.0, r: float = 0.0) -> Obstacle:  # noqa: E741
    return Obstacle.model_validate(
        {"size": {"l": l, "w": w, "h": h}, "position": {"x": x, "y": y, "z": z, "r": r}}
    )


def test_distance_matches_the_analysis_geometry_for_yawed_and_raised_boxes() -> None:
    rng = random.Random(7)
    boxes = [box(10, 4, 15, 20, 5, 0, 30), box(3, 3, 5, -10, -10, 8, -75), box(1, 8, 2, 0, 30, 1, 90)]
    monitor = FlightMonitor(boxes)
    for _ in range(500):
        x, y, z = rng.uniform(-30, 40), rng.uniform(-30, 40), rng.uniform(-25, 2)
        assert monitor.distance(x, y, z) == pytest.approx(min_distance_to_obstacles(x, y, z, boxes), abs=1e-9)


def test_positions_fold_into_min_distance_collision_and_airborne() -> None:
    monitor = FlightMonitor([box(2, 2, 10, 10, 0)])
    monitor.on_position(LocalPosition(0, 0, 0, 0))
    assert not monitor.airborne
    monitor.on_position(LocalPosition(100, 5, 0, -5))
    assert monitor.airborne and monitor.min_distance == pytest.approx(4.0)
    assert monitor.collision is None
    monitor.on_position(LocalPosition(200, 9.5, 0, -5))
    monitor.on_position(LocalPosition(300, 9.8, 0, -5))
    assert monitor.collision == LocalPosition(200, 9.5, 0, -5)  # the first contact
    assert monitor.min_distance == 0.0


def test_flying_over_a_box_is_not_a_collision() -> None:
    monitor = FlightMonitor([box(4, 4, 10, 0, 0)])
    monitor.on_position(LocalPosition(0, 0, 0, -12))
    assert monitor.collision is None and monitor.min_distance == pytest.approx(2.0)


def test_geofence_violation_is_the_furthest_distance_outside() -> None:
    monitor = FlightMonitor([], Geofence(min_x=-10, max_x=10, min_z=-20))
    monitor.on_position(LocalPosition(0, 5, 0, -5))
    assert monitor.geofence_violation == 0.0
    monitor.on_position(LocalPosition(0, 13, 0, -24))
    assert monitor.geofence_violation == pytest.approx(5.0)
    assert math.isinf(monitor.min_distance)
