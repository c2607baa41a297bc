"""PX4-Avoidance's local planner model: its histogram and costs (pure), and flights with it.

The flights are in-process (``fly_mission``): the competition's missions with the case-study
README's two sample boxes, a narrow gap, a wall, and the same box without avoidance.
"""

from __future__ import annotations

import dataclasses
import math
import random
from pathlib import Path

import numpy as np
import pytest

from uavtest.analysis.geometry import distances_to_obstacles
from uavtest.analysis.verdict import simulator_warnings
from uavtest.runner.events import MissionItemInt
from uavtest.runner.progress import ProgressWatch
from uavtest.sitl.inprocess import Flight, fly_mission
from uavtest.sitl.local_planner import (
    BINS,
    LEG_SPEED,
    LocalPlanner,
    PlannerParams,
    bin_of,
    costs,
    histogram,
)
from uavtest.sitl.mc_pos_control import Goal, GoalKind
from uavtest.sitl.mission import from_spec
from uavtest.sitl.sensor_depth_sim import DepthCamera
from uavtest.sitl.simulator_sih import World
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.loaders import load_test_text
from uavtest.spec.mission import mission_items
from uavtest.spec.models import Avoidance, Home, Obstacle, Simulator, UavTestSpec

from .conftest import competition


#: the two sample obstacles of the competition's snippets/case_studies/README.md
def _box(length: float, w: float, h: float, x: float, y: float) -> Obstacle:
    size = {"l": length, "w": w, "h": h}
    return Obstacle.model_validate({"size": size, "position": {"x": x, "y": y, "z": 0, "r": 0}})


SAMPLE_BOXES = (_box(10, 5, 20, 10, 20), _box(10, 5, 20, -10, 20))


def _north_mission(obstacles: tuple[Obstacle, ...], avoidance: str = "local-planner") -> UavTestSpec:
    """Take off, fly 50 m north at 10 m, land."""
    spec = load_test_text(
        f"""apiVersion: uavtest.io/v1alpha1
kind: UavTest
metadata: {{name: planner}}
spec:
  vehicle: {{avoidance: {avoidance}}}
  mission:
    takeoffAltitude: 10
    waypoints:
      - {{x: 0, "y": 0, z: -10}}
      - {{x: 50, "y": 0, z: -10}}
    land: true
""",
        "planner",
    ).spec
    return spec.model_copy(update={"world": spec.world.model_copy(update={"obstacles": list(obstacles)})})


def _fly(spec: UavTestSpec, seed: int, limit_s: float = 300.0) -> tuple[Flight, np.ndarray, float]:
    flight = fly_mission(SimConfig.from_spec(spec, seed), from_spec(mission_items(spec)), limit_s=limit_s)
    s = np.array(flight.samples)
    d = distances_to_obstacles(s[:, 1], s[:, 2], s[:, 3], spec.world.obstacles)
    return flight, s, float(d.min())


# ---------------------------------------------------------------------- pure parts


def test_bins_are_six_degrees_from_south_round_to_south() -> None:
    assert BINS == 60
    assert bin_of(math.radians(-180.0)) == 0
    assert bin_of(0.0) == 30  # north
    assert bin_of(math.radians(90.0)) == 45  # east
    assert bin_of(math.radians(179.9)) == 59


def test_histogram_holds_the_mean_distance_per_bin_and_drops_far_points() -> None:
    points = [(4.0, 0.0), (6.0, 0.0), (0.0, 3.0), (20.0, 0.0)]
    hist = histogram(points, 0.0, 0.0, 15.0)
    assert hist[30] == pytest.approx(5.0)  # north: (4 + 6) / 2; the point at 20 m is out of range
    assert hist[45] == pytest.approx(3.0)
    assert sum(1 for r in hist if r > 0) == 2


def test_a_box_on_the_goal_line_makes_the_straight_direction_dearest_nearby() -> None:
    hist = [0.0] * BINS
    for i in (29, 30, 31):  # an obstacle 4 m north, the goal 30 m north
        hist[i] = 4.0
    cost, facing = costs(hist, 0.0, 0.0, 1.0, 0.0, (30.0, 0.0), (0.0, 0.0), PlannerParams(), 15.0)
    assert facing
    best = min(range(BINS), key=cost.__getitem__)
    assert best not in (29, 30, 31)  # not into the box
    assert abs(best - 30) <= 15  # but not back either: sideways-forward, within 90 deg
    free = [0.0] * BINS
    cost, facing = costs(free, 0.0, 0.0, 1.0, 0.0, (30.0, 0.0), (0.0, 0.0), PlannerParams(), 15.0)
    assert not facing and min(range(BINS), key=cost.__getitem__) in (29, 30)  # the bins either side of north


def test_the_camera_sees_a_box_ahead_only_in_its_field_of_view() -> None:
    world = World([_box(4, 4, 20, 10, 0)])
    cam = DepthCamera(world, random.Random(1))
    ahead = [r for _, r in cam.scan(0.0, 0.0, -5.0, 0.0)]
    assert min(ahead) == pytest.approx(8.0, abs=0.5)  # the face at x = 8
    assert all(r == math.inf for _, r in cam.scan(0.0, 0.0, -5.0, math.pi))  # looking away
    assert all(r == math.inf for _, r in cam.scan(0.0, 0.0, -25.0, 0.0))  # above the box


def test_without_obstacles_the_planner_hands_the_waypoint_to_px4_at_the_leg_speed() -> None:
    planner = LocalPlanner(DepthCamera(World([]), random.Random(0)), random.Random(0))
    goal = Goal(GoalKind.POSITION, 40.0, 0.0, -10.0)
    out = planner.update(0.0, 0.02, 0.0, 0.0, -10.0, 0.0, 0.0, 0.0, goal)
    assert out.kind is GoalKind.POSITION and (out.x, out.y, out.z) == (40.0, 0.0, -10.0)
    assert out.speed == pytest.approx(LEG_SPEED * planner.speed_scale)
    assert out is not goal  # the navigator's goal object is never changed
    takeoff = Goal(GoalKind.TAKEOFF, 0.0, 0.0, -10.0)
    assert planner.update(0.1, 0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, takeoff) is takeoff


def test_with_a_box_ahead_the_planner_steers_a_velocity_around_it() -> None:
    planner = LocalPlanner(DepthCamera(World([_box(4, 8, 20, 8, 0)]), random.Random(0)), random.Random(0))
    goal = Goal(GoalKind.POSITION, 30.0, 0.0, -10.0)
    out = planner.update(0.0, 0.02, 0.0, 0.0, -10.0, 0.0, 1.0, 0.0, goal)
    assert out.kind is GoalKind.OFFBOARD and planner.active
    assert abs(math.degrees(planner.direction)) >= 15  # not straight into the box


def test_progress_watch_calls_a_hover_far_from_the_waypoint_blocked_after_a_minute() -> None:
    home = Home(lat=47.0, lon=8.0, alt=0.0)
    items = [
        MissionItemInt(0, 6, 22, z=10.0),
        MissionItemInt(1, 6, 16, x=int(47.0004 * 1e7), y=int(8.0 * 1e7), z=100.0),  # ~44 m north, 100 m up
    ]
    watch = ProgressWatch(items, home)
    watch.on_reached(0)
    for k in range(59):  # 59 s in front of a wall, 20 m short
        watch.on_position(24.0 + 0.3 * (k % 2), 0.0, -100.0, 10_000 + k * 1000, True)
    assert watch.blocked is None
    watch.on_position(24.0, 2.0, -100.0, 70_000, True)
    assert watch.blocked is not None and watch.blocked.startswith(
        "blocked: no progress toward mission item 1"
    )
    moving = ProgressWatch(items, home)
    moving.on_reached(0)
    for k in range(120):  # slow but steady: a metre every 3 s
        moving.on_position(k / 3.0, 0.0, -100.0, k * 1000, True)
    assert moving.blocked is None
    holding = ProgressWatch(items, home)
    holding.on_reached(0)
    for k in range(120):  # not in mission mode (hold): never blocked
        holding.on_position(5.0, 0.0, -10.0, k * 1000, False)
    assert holding.blocked is None
    climbing = ProgressWatch(items, home)
    for k in range(200):  # a 100 m takeoff climb at 0.5 m/s: no horizontal progress, yet progress
        climbing.on_position(0.0, 0.0, -k * 0.5, k * 1000, True)
    assert climbing.blocked is None


# ---------------------------------------------------------------------- flights


@pytest.mark.parametrize("n", [1, 2, 3])
def test_competition_missions_fly_around_the_sample_boxes(shared_data: Path, n: int) -> None:
    """No collision in at least 9 of 10 replicas (18 of 20 seeds); the legs that meet a box pass it
    on the side the competition's pictures show (mission2-2.png, mission3-2.png: the return leg
    passes outside the box at x = -15..-5, on the -x side, in at least 4 of 5; mission2 does in
    35 of 40 seeds since PX4's takeoff stalls, 37 before; mission1-2.png, mission2-2.png: the
    outbound leg through the 10 m gap, pushed away from the nearer box)."""
    collisions, outer = 0, 0
    for seed in range(20):
        config, items = competition(shared_data, n, seed, Avoidance.LOCAL_PLANNER)
        flight = fly_mission(dataclasses.replace(config, obstacles=SAMPLE_BOXES), items)
        assert flight.vehicle is not None
        collisions += flight.vehicle.crashed
        s = np.array(flight.samples)
        at_boxes = [s[i, 1] for i in range(1, len(s)) if (s[i - 1, 2] - 20.0) * (s[i, 2] - 20.0) < 0]
        if n == 1:
            assert len(at_boxes) == 1 and -5.0 < at_boxes[0] < 5.0  # through the gap
            assert at_boxes[0] < 1.2  # not pulled towards the box on its right (line: x = 1.2)
        else:
            assert len(at_boxes) == 2 and -5.0 < at_boxes[0] < 5.0  # out through the gap
            outer += at_boxes[1] < -15.0  # back outside the box, on the -x side
    assert collisions <= 2
    if n > 1:
        assert outer >= 16


def test_competition_mission2_legs_take_about_1_3_m_s(shared_data: Path) -> None:
    config, items = competition(shared_data, 2, 0, Avoidance.LOCAL_PLANNER)
    s = np.array(fly_mission(config, items).samples)
    high = s[-s[:, 3] > 9.5]
    legs = high[-1, 0] - high[0, 0]
    # the competition: 28 s -> 113 s at 10 m (mission2.png), about 1.3 m/s over 2 x 53 m
    assert 75.0 < legs < 110.0


def test_narrow_gap_gives_soft_fails_and_flakiness() -> None:
    """Two 4 m boxes with a 4 m gap on the path: the planner goes round one or the other, too
    close for the competition's 1.5 m in most replicas but not all."""
    spec = _north_mission((_box(4, 4, 30, 25, 4.0), _box(4, 4, 30, 25, -4.0)))
    dmins = []
    for seed in range(12):
        flight, _, dmin = _fly(spec, seed)
        assert flight.vehicle is not None and not flight.vehicle.crashed
        dmins.append(dmin)
    soft = sum(d < 1.5 for d in dmins)
    assert 0 < soft < len(dmins), dmins  # soft fails, and passes: flaky


def test_a_wall_blocks_the_planner_and_the_progress_watch_says_so() -> None:
    spec = _north_mission((_box(4, 80, 30, 25, 0),))
    flight, s, dmin = _fly(spec, 0, limit_s=200.0)
    assert flight.vehicle is not None and not flight.vehicle.crashed and dmin > 1.0
    assert s[:, 1].max() < 23.0  # never past the wall
    watch = ProgressWatch(
        [MissionItemInt(0, 6, 22, z=10.0), MissionItemInt(1, 6, 16, z=10.0)], Home(lat=0.0, lon=0.0, alt=0.0)
    )
    watch.places[1] = (50.0, 0.0, -10.0)
    watch.on_reached(0)
    for t, x, y, z in flight.samples:
        watch.on_position(x, y, z, round(t * 1000), -z > 5.0)
    assert watch.blocked is not None


def test_without_avoidance_the_same_box_is_a_collision() -> None:
    box = (_box(4, 8, 30, 25, 0),)
    flight, _, _ = _fly(_north_mission(box, avoidance="none"), 0)
    assert flight.vehicle is not None and flight.vehicle.crashed
    flight, _, dmin = _fly(_north_mission(box), 0)
    assert flight.vehicle is not None and not flight.vehicle.crashed and dmin > 0.5


def test_px4_sitl_says_it_flies_without_the_local_planner() -> None:
    spec = _north_mission(())
    px4 = spec.model_copy(update={"vehicle": spec.vehicle.model_copy(update={"simulator": Simulator.PX4})})
    assert any("without PX4-Avoidance" in w for w in simulator_warnings(px4))
    assert simulator_warnings(spec) == []  # the built-in simulator flies it


def test_competition_failing_layout_hesitates_and_soft_fails(shared_data: Path) -> None:
    """``mission2-failing.png``: a box across mission2's outbound leg (x -10..-2.5, y 15..20) and
    one right of it (x 5.5..13). The competition's replicas go round the left box's far side
    (x about -13 at y = 17.5), come close, and take very different times (hesitation)."""
    boxes = (_box(7.5, 5, 20, -6.25, 17.5), _box(7.5, 5, 20, 9.25, 17.5))
    times, dmins, sides = [], [], []
    for seed in range(10):
        config, items = competition(shared_data, 2, seed, Avoidance.LOCAL_PLANNER)
        flight = fly_mission(dataclasses.replace(config, obstacles=boxes), items)
        assert flight.vehicle is not None and not flight.vehicle.crashed
        assert flight.flight_time is not None
        times.append(flight.flight_time)
        s = np.array(flight.samples)
        dmins.append(float(distances_to_obstacles(s[:, 1], s[:, 2], s[:, 3], boxes).min()))
        outbound = next(s[i, 1] for i in range(1, len(s)) if s[i - 1, 2] < 17.5 <= s[i, 2])
        sides.append(outbound)
    assert all(x < -10.0 for x in sides), sides  # round the far side of the left box
    assert max(times) - min(times) > 15.0, times  # hesitation differs from replica to replica
    assert sum(d < 1.5 for d in dmins) >= 5, dmins  # mostly soft fails
