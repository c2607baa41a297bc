"""The UAV Testing Competition's outcomes: 2-D distance, points, hard / soft fail.

The 2-D distance is checked against geometry worked out by hand, then against the competition's
own formula — Aerialist's pipeline written out with shapely, as its ``Trajectory`` and
``Obstacle`` classes do it — on a real flight log.
"""

from __future__ import annotations

import math
import statistics

import numpy as np
import pytest
from pyulog import ULog
from shapely import affinity
from shapely.geometry import LineString, Point, box

from uavtest.analysis.competition import (
    competition_distance,
    competition_points,
    window_means,
)
from uavtest.analysis.flakiness import competition_score
from uavtest.analysis.geometry import line_distances_2d, min_distance_to_obstacles
from uavtest.analysis.models import FlightMetrics
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import topic
from uavtest.analysis.verdict import judge_flight
from uavtest.spec.models import Assertions, Obstacle


def obstacle(l: float, w: float, h: float, x: float, y: float, z: float = 0.0, r: float = 0.0) -> Obstacle:  # noqa: E741
    return Obstacle.model_validate(
        {"size": {"l": l, "w": w, "h": h}, "position": {"x": x, "y": y, "z": z, "r": r}}
    )


# 10 m (North) × 4 m (East) × 5 m tall, centred at (20, 0): footprint x 15..25, y -2..2
BOX = obstacle(10, 4, 5, 20, 0)


def line(*points: tuple[float, float], dt: float = 0.1, alt: float = 6.0) -> Trajectory:
    xy = np.array(points, dtype=np.float64)
    n = len(xy)
    return Trajectory(np.arange(n) * dt, xy[:, 0], xy[:, 1], np.full(n, -alt))


def flight(y: float, alt: float) -> Trajectory:
    """North from x = 0 to 40 m along ``y`` at ``alt``, sampled at 10 Hz (0.1 m apart)."""
    x = np.linspace(0.0, 40.0, 401)
    return Trajectory(x.copy(), x, np.full_like(x, y), np.full_like(x, -alt))


# ------------------------------------------------------------------ geometry, by hand


def test_a_pass_beside_a_box_is_its_horizontal_gap() -> None:
    # North along y = 5: 3 m from the East face (y = 2)
    assert line_distances_2d([0, 40], [5, 5], [BOX]) == pytest.approx([3.0])


def test_a_segment_is_measured_along_its_length_not_at_its_samples() -> None:
    # two samples far apart (x = 0 and x = 40) on y = -3: the segment passes 1 m from the West face
    assert line_distances_2d([0, 40], [-3, -3], [BOX]) == pytest.approx([1.0])
    # each sample alone is 15.03 m away: the line between them is what counts
    assert line_distances_2d([0], [-3], [BOX]) == pytest.approx([math.hypot(15, 1)])


def test_flying_over_a_box_is_a_distance_of_zero_in_2d() -> None:
    # at 8 m over a 5 m box: 3 m away in 3-D, 0 in the competition's 2-D measure
    t = flight(0.0, alt=8.0)
    assert line_distances_2d(t.x, t.y, [BOX]) == pytest.approx([0.0])
    assert min_distance_to_obstacles(t.x, t.y, t.z, [BOX]) == pytest.approx(3.0)


def test_a_segment_passing_a_corner_is_nearest_at_the_corner() -> None:
    # a diagonal through (27, 0) and (25, 4) (direction (-1, 2)) passes the corner (25, 2) at
    # distance |(-2, 2) × (-1, 2)| / √5 = 2/√5 and misses the footprint
    d = line_distances_2d([29, 23], [-4, 8], [BOX])
    assert d == pytest.approx([2 / math.sqrt(5)])


def test_yaw_turns_the_footprint_from_north_towards_east() -> None:
    # a 10 × 2 box at the origin turned 90°: its long side now runs East, so a point 4 m East
    # of the centre is 1 m beyond its end, and a point 4 m North is 3 m from its North face
    turned = obstacle(10, 2, 5, 0, 0, r=90)
    assert line_distances_2d([0], [6], [turned]) == pytest.approx([1.0])
    assert line_distances_2d([4], [0], [turned]) == pytest.approx([3.0])
    # 45°: the corner (5, 1) of the unturned box lands at (5 cos45 - sin45, 5 sin45 + cos45)
    diagonal = obstacle(10, 2, 5, 0, 0, r=45)
    c = np.array(
        [5 * math.cos(math.pi / 4) - math.sin(math.pi / 4), 5 * math.sin(math.pi / 4) + 1 / math.sqrt(2)]
    )
    beyond = c + np.array([1.0, 1.0]) / math.sqrt(2) * 2.0  # 2 m further along the diagonal
    assert line_distances_2d([beyond[0]], [beyond[1]], [diagonal]) == pytest.approx([2.0])


def test_one_distance_per_obstacle_and_none_without() -> None:
    other = obstacle(2, 2, 5, 0, 10)  # footprint x -1..1, y 9..11
    d = line_distances_2d([0, 40], [5, 5], [BOX, other])
    assert d == pytest.approx([3.0, 4.0])
    assert line_distances_2d([0, 1], [0, 1], []).size == 0


def test_window_means_average_half_second_windows_from_the_first_sample() -> None:
    # samples at 10 Hz; Aerialist's windows: [0, 0.5] holds 6 samples, (0.5, 1.0] the next 5
    t = Trajectory(np.arange(11) * 0.1, np.arange(11.0), np.zeros(11), np.zeros(11))
    assert window_means(t)[:, 0] == pytest.approx([2.5, 8.0])  # mean of 0..5, mean of 6..10
    assert window_means(Trajectory([], [], [], [])).shape == (0, 2)


def test_window_means_follow_aerialist_boundaries_in_microseconds() -> None:
    # a sample exactly on a window's end belongs to that window; gaps leave no empty point
    t = Trajectory([0.0, 0.5, 0.500001, 3.0], [0.0, 2.0, 10.0, 20.0], [0.0] * 4, [0.0] * 4)
    assert window_means(t)[:, 0] == pytest.approx([1.0, 10.0, 20.0])


# ------------------------------------------------------------------ the competition's measure


def test_competition_distance_subtracts_half_the_vehicle_width() -> None:
    t = line((0, 5), (40, 5), dt=1.0)  # one sample per window: the line is the samples' line
    assert competition_distance(t, [BOX]) == pytest.approx(3.0 - 0.125)
    grazing = line((0, 2.1), (40, 2.1), dt=1.0)  # 0.1 m from the face: inside the 0.25 m wide line
    assert competition_distance(grazing, [BOX]) == 0.0
    assert competition_distance(t, []) is None
    assert competition_distance(Trajectory([], [], [], []), [BOX]) is None


@pytest.mark.parametrize(
    ("distance", "points"),
    [
        (0.0, 5),
        (0.2499, 5),
        (0.25, 2),  # every bound is strict: point(sim) = 2 for 0.25 <= min_dist < 1
        (0.99, 2),
        (1.0, 1),
        (1.4999, 1),
        (1.5, 0),
        (30.0, 0),
        (None, None),
    ],
)
def test_points_follow_the_competition_table(distance: float | None, points: int | None) -> None:
    assert competition_points(distance) == points


def _aerialist_distance(ulog: ULog, obstacles: list[tuple[float, ...]]) -> float:
    """Aerialist's measure as its code does it (aerialist/px4/trajectory.py ``extract_from_log``,
    ``downsample_time``, ``to_thick_line``; obstacle.py ``Obstacle.__init__`` and ``distance``;
    the competition's ``TestCase.get_distances`` and ``min``), with shapely."""
    lp = topic(ulog, "vehicle_local_position")
    assert lp is not None
    stamps = [int(s) for s in lp["timestamp"]]
    pos = [
        [float(x), float(y), -float(z), s - stamps[0]]
        for x, y, z, s in zip(lp["x"], lp["y"], lp["z"], stamps, strict=True)
    ]
    origin = list(pos[0])
    for p in pos:
        p[0], p[1], p[2] = p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]
    down: list[list[float]] = []
    start, i, period = pos[0][3], 0, 500000
    while i < len(pos):
        window = []
        while i < len(pos) and pos[i][3] <= start + period:
            window.append(pos[i])
            i += 1
        if window:
            down.append([statistics.mean(p[k] for p in window) for k in range(3)])
        start += period
    thick = LineString(down).buffer(0.25 / 2)
    distances = []
    for length, width, _h, x, y, _z, r in obstacles:
        rect = box(-length / 2, -width / 2, length / 2, width / 2)
        geometry = affinity.translate(affinity.rotate(rect, r, "centroid"), x, y)
        distances.append(geometry.distance(thick))
    return min(distances)


@pytest.mark.parametrize(
    "obstacles",
    [
        [(5, 5, 5, -8, 3, 0, 0)],  # the obstacle of Aerialist's own mission1.yaml
        [(5, 5, 5, -8, 3, 0, 30)],
        [(4, 1, 5, -3, 1, 0, -60)],
        [(10, 5, 20, -10, 20, 0, 0), (10, 5, 20, 10, 20, 0, 45)],  # the case-study README's two
        [(2, 3, 5, -20, 0, 0, 17)],
    ],
)
def test_competition_distance_equals_aerialists_on_a_real_flight(
    aerialist_log: ULog, obstacles: list[tuple[float, ...]]
) -> None:
    lp = topic(aerialist_log, "vehicle_local_position")
    assert lp is not None
    # the same samples Aerialist takes: the whole log, relative to its first sample
    whole = Trajectory(
        lp["timestamp"] / 1e6, lp["x"] - lp["x"][0], lp["y"] - lp["y"][0], lp["z"] - lp["z"][0]
    )
    ours = competition_distance(whole, [obstacle(*o) for o in obstacles])
    # shapely's buffer rounds the line's caps with 16 segments a quarter: <= 0.125 (1 - cos(pi/64)) m
    assert ours == pytest.approx(_aerialist_distance(aerialist_log, obstacles), abs=2e-4)


def test_line_distance_equals_shapely_on_random_lines_and_turned_boxes() -> None:
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(1, 6))
        pts = rng.uniform(-10, 10, (n, 2))
        length, width = rng.uniform(0.5, 6, 2)
        x, y = rng.uniform(-5, 5, 2)
        r = float(rng.uniform(-180, 180))
        footprint = affinity.translate(
            affinity.rotate(box(-length / 2, -width / 2, length / 2, width / 2), r, "centroid"), x, y
        )
        expected = footprint.distance(LineString(pts) if n > 1 else Point(pts[0]))
        got = line_distances_2d(pts[:, 0], pts[:, 1], [obstacle(length, width, 5, x, y, r=r)])
        assert got == pytest.approx([expected], abs=1e-9)


# ------------------------------------------------------------------ verdict and score


def test_the_verdict_names_hard_and_soft_fails_and_carries_the_points() -> None:
    near = flight(2.6, alt=2.0)  # 0.6 m from the East face, below the roof
    metrics, _, verdict, reason = judge_flight(near, Assertions(mission_completed=False), obstacles=[BOX])
    assert verdict.value == "fail"
    assert reason == "soft fail: min distance 0.60 m < 1.50 m (short by 0.90 m)"
    assert metrics.min_obstacle_distance == pytest.approx(0.6)
    assert metrics.min_obstacle_distance_2d == pytest.approx(0.475)
    assert metrics.competition_points == 2

    through = flight(0.0, alt=2.0)
    metrics, _, verdict, reason = judge_flight(through, Assertions(mission_completed=False), obstacles=[BOX])
    assert reason.startswith("hard fail: collision with an obstacle at t=")
    assert "; soft fail: min distance 0.00 m" in reason
    assert metrics.competition_points == 5

    clear = flight(8.0, alt=2.0)
    metrics, _, verdict, reason = judge_flight(clear, Assertions(mission_completed=False), obstacles=[BOX])
    assert verdict.value == "pass" and reason == ""
    assert metrics.competition_points == 0


def test_points_do_not_change_a_verdict_without_obstacle_assertions() -> None:
    # over a short box at 8 m: 3 m away in 3-D (passes 1.5 m), 0 m in 2-D (5 points)
    over = flight(0.0, alt=8.0)
    metrics, _, verdict, _ = judge_flight(over, Assertions(mission_completed=False), obstacles=[BOX])
    assert verdict.value == "pass"
    assert metrics.competition_points == 5 and metrics.min_obstacle_distance_2d == 0.0
    metrics, _, _, _ = judge_flight(over, Assertions(mission_completed=False))
    assert metrics.competition_points is None and metrics.min_obstacle_distance_2d is None


def test_the_score_totals_and_averages_points_and_counts_hard_and_soft_fails() -> None:
    flights = [
        FlightMetrics(min_obstacle_distance_2d=0.0, competition_points=5, collision=True),
        FlightMetrics(min_obstacle_distance_2d=0.6, competition_points=2),
        FlightMetrics(min_obstacle_distance_2d=1.2, competition_points=1),
        FlightMetrics(min_obstacle_distance_2d=3.0, competition_points=0),
        FlightMetrics(),  # no obstacles: not scored
    ]
    score = competition_score(flights)
    assert score is not None
    assert (score.total, score.mean, score.count) == (8, 2.0, 4)
    assert (score.hard_fails, score.soft_fails) == (1, 2)
    assert competition_score([FlightMetrics()]) is None


def test_assertions_not_judged_are_no_hard_or_soft_fail() -> None:
    empty = Trajectory([], [], [], [])
    metrics, _, verdict, reason = judge_flight(empty, Assertions(), obstacles=[BOX], expect_flight=True)
    assert verdict.value == "fail" and "not judged" in reason
    assert "hard fail" not in reason and "soft fail" not in reason
    assert metrics.competition_points is None
    # a crash the log reports is a hard fail even without a trajectory near the box
    _, _, _, reason = judge_flight(
        flight(8.0, alt=2.0), Assertions(mission_completed=False), obstacles=[BOX], crash="crash: collided"
    )
    assert reason.startswith("hard fail: collision with an obstacle: the log reports 'crash: collided'")
