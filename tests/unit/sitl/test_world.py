import math
import random

import numpy as np
import pytest

from uavtest.analysis.geometry import collides
from uavtest.sitl.geo import Projection
from uavtest.sitl.simulator_sih import Box, World
from uavtest.spec.geo import geodetic_to_ned, ned_to_geodetic
from uavtest.spec.models import BoxPosition, BoxSize, Obstacle


def test_box_contains_agrees_with_the_analysis_geometry():
    """Differential: the simulator's fast box test against the analysis' 3-D distance."""
    rng = random.Random(1)
    for _ in range(20):
        o = Obstacle(
            size=BoxSize(l=rng.uniform(1, 10), w=rng.uniform(1, 10), h=rng.uniform(1, 20)),
            position=BoxPosition(
                x=rng.uniform(-5, 5), y=rng.uniform(-5, 5), z=rng.uniform(0, 3), r=rng.uniform(-180, 180)
            ),
        )
        box = Box.of(0, o)
        for _ in range(200):
            x, y, z = rng.uniform(-10, 10), rng.uniform(-10, 10), -rng.uniform(0, 25)
            assert box.contains(x, y, z) == collides(x, y, z, [o]), (o, x, y, z)


def test_projection_matches_the_spec_geo_module():
    proj = Projection(47.397742, 8.545594)
    for north, east in [(0.0, 0.0), (12.3, -45.6), (-300.0, 250.0)]:
        lat, lon = proj.reproject(north, east)
        ref_lat, ref_lon = ned_to_geodetic(north, east, 47.397742, 8.545594)
        assert math.isclose(lat, ref_lat, abs_tol=1e-12) and math.isclose(lon, ref_lon, abs_tol=1e-12)
        n, e = proj.project(lat, lon)
        ref = geodetic_to_ned(lat, lon, 47.397742, 8.545594)
        assert np.allclose((n, e), ref, atol=1e-6) and np.allclose((n, e), (north, east), atol=1e-6)


def test_a_ray_reaches_the_near_face_of_a_box_and_misses_above_it() -> None:
    box = Obstacle.model_validate({"size": {"l": 2, "w": 4, "h": 10}, "position": {"x": 10, "y": 0, "z": 0}})
    world = World([box])
    assert world.ray(0, 0, -5, 1, 0, 0, 50) == pytest.approx(9.0)  # the face at x = 9
    assert world.ray(0, 0, -15, 1, 0, 0, 50) == math.inf  # 15 m up, the box is 10 m tall
    assert world.ray(0, 0, -5, 0, 1, 0, 50) == math.inf  # looking East, past it
    assert world.ray(0, 0, -5, 1, 0, 0, 5) == math.inf  # beyond the sensor's range
    assert world.ray(10, 0, -5, 1, 0, 0, 50) == 0.0  # from inside


def test_a_ray_sees_a_yawed_box_where_its_corner_is() -> None:
    # a 2 x 2 box turned 45 degrees: its corner points at the origin, sqrt(2) closer than its centre
    box = Obstacle.model_validate({"size": {"l": 2, "w": 2, "h": 5}, "position": {"x": 10, "y": 0, "r": 45}})
    assert World([box]).ray(0, 0, -1, 1, 0, 0, 50) == pytest.approx(10 - math.sqrt(2))
