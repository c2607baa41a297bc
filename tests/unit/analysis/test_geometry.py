"""3-D distance to oriented boxes, checked against distances worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uavtest.analysis.geometry import box_corners, collides, distances_to_obstacles, min_distance_to_obstacles
from uavtest.spec.models import Obstacle


def box(l: float, w: float, h: float, x: float, y: float, z: float = 0.0, r: float = 0.0) -> Obstacle:  # noqa: E741
    return Obstacle.model_validate(
        {"size": {"l": l, "w": w, "h": h}, "position": {"x": x, "y": y, "z": z, "r": r}}
    )


# a 10 m (North) × 4 m (East) × 5 m tall box centred at (20, 0), base on the ground
BOX = box(10, 4, 5, 20, 0)


def test_point_above_a_box_is_its_height_above_the_roof() -> None:
    # 8 m up (z = -8) over the centre: the roof is at 5 m, so 3 m away — not a hit as in Aerialist's 2-D check
    assert min_distance_to_obstacles(20, 0, -8, [BOX]) == pytest.approx(3.0)
    assert not collides(20, 0, -8, [BOX])


def test_flying_over_a_box_is_not_a_collision() -> None:
    # a straight pass at 6 m over the whole box, North to South
    x = np.linspace(0, 40, 401)
    d = distances_to_obstacles(x, np.zeros_like(x), np.full_like(x, -6.0), [BOX])
    assert d.min() == pytest.approx(1.0)
    assert not collides(x, np.zeros_like(x), np.full_like(x, -6.0), [BOX])


def test_point_beside_a_box_is_its_horizontal_gap() -> None:
    # East face at y = 2; a point at y = 5, mid-height
    assert min_distance_to_obstacles(20, 5, -2.5, [BOX]) == pytest.approx(3.0)


def test_point_off_a_corner_is_the_diagonal_to_the_corner() -> None:
    # top corner (25, 2, 5 m up); point at (28, 6, 9 m up): offsets 3, 4, 4
    assert min_distance_to_obstacles(28, 6, -9, [BOX]) == pytest.approx(math.sqrt(9 + 16 + 16))


def test_inside_and_touching_are_collisions() -> None:
    assert min_distance_to_obstacles(20, 0, -1, [BOX]) == 0.0
    assert collides(25, 2, -5, [BOX])  # exactly on the top corner edge
    assert collides(20, 0, -1, [BOX])


def test_yaw_turns_the_box_from_north_towards_east() -> None:
    rotated = box(10, 2, 10, 0, 0, r=90)  # now 10 m long East-West, 2 m North-South
    assert min_distance_to_obstacles(0, 4, -5, [rotated]) == 0.0  # inside along East
    assert min_distance_to_obstacles(6, 0, -5, [rotated]) == pytest.approx(5.0)  # beyond the 1 m half-width
    diagonal = box(10, 2, 10, 0, 0, r=45)  # long axis along North-East
    s = math.sqrt(0.5)
    assert min_distance_to_obstacles(4 * s, 4 * s, -5, [diagonal]) == 0.0
    # 3 m off the long axis towards North-West, beyond the 1 m half-width by 2 m
    assert min_distance_to_obstacles(3 * s, -3 * s, -5, [diagonal]) == pytest.approx(2.0)


def test_base_height_lifts_the_box() -> None:
    floating = box(4, 4, 2, 0, 0, z=10)  # spans 10..12 m up
    assert min_distance_to_obstacles(0, 0, -5, [floating]) == pytest.approx(5.0)  # below it
    assert min_distance_to_obstacles(0, 0, -11, [floating]) == 0.0


def test_nearest_of_several_boxes_and_vehicle_radius() -> None:
    far = box(2, 2, 2, 100, 100)
    assert min_distance_to_obstacles(28, 6, -9, [far, BOX]) == pytest.approx(math.sqrt(41))
    assert min_distance_to_obstacles(20, 5, -2.5, [BOX], radius=0.5) == pytest.approx(2.5)
    assert collides(20, 5, -2.5, [BOX], radius=3.0)


def test_no_obstacles_is_infinitely_far() -> None:
    assert min_distance_to_obstacles(0, 0, 0, []) == math.inf
    assert not collides(0, 0, 0, [])


def test_box_corners_follow_the_yaw() -> None:
    corners = box_corners(box(10, 2, 1, 5, 5, r=90))
    assert sorted(map(tuple, np.round(corners, 6).tolist())) == [(4, 0), (4, 10), (6, 0), (6, 10)]
