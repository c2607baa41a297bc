import math
import random

import numpy as np

from uavtest.analysis.geometry import collides
from uavtest.sitl.geo import Projection
from uavtest.sitl.simulator_sih import Box
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
