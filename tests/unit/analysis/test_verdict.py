"""judge: metrics, assertions and the verdict of one flight."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.models import MissionProgress, Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import mission_progress_from_ulog, trajectory_from_ulog
from uavtest.analysis.verdict import judge
from uavtest.spec.models import UavTestSpec


def north_pass(altitude: float, y: float = 0.0) -> Trajectory:
    """Take off at home, fly North 0→40 m at ``altitude``, East offset ``y``, 1 m/s."""
    t = np.arange(0.0, 40.0, 0.1)
    return Trajectory(t, t.copy(), np.full_like(t, y), np.full_like(t, -altitude))


def spec(**extra: Any) -> UavTestSpec:
    obstacle = {"size": {"l": 4, "w": 4, "h": 10}, "position": {"x": 20, "y": 0, "z": 0, "r": 0}}
    doc: dict[str, Any] = {
        "mission": {"waypoints": [{"x": 40, "y": 0, "z": -5}], "land": False, "takeoffAltitude": 5},
        "world": {"obstacles": [obstacle]},
    }
    doc.update(extra)
    return UavTestSpec.model_validate(doc)


def by_name(results: list) -> dict:
    return {r.name: r for r in results}


def test_flying_through_a_box_fails_with_a_collision() -> None:
    metrics, results, verdict, reason = judge(north_pass(5.0), spec(), mission=None)
    checks = by_name(results)
    assert verdict == Verdict.FAIL
    assert metrics.collision and metrics.min_obstacle_distance == 0.0
    assert not checks["noCollision"].passed
    assert "collision" in reason and "t=18.0 s" in reason  # the box spans x 18..22


def test_flying_over_a_box_is_no_collision_but_too_close() -> None:
    metrics, results, verdict, _reason = judge(north_pass(11.0), spec())
    checks = by_name(results)
    assert not metrics.collision
    assert metrics.min_obstacle_distance == pytest.approx(1.0)
    assert checks["noCollision"].passed
    assert not checks["minObstacleDistance"].passed
    message = checks["minObstacleDistance"].message
    assert message == "soft fail: min distance 1.00 m < 1.50 m (short by 0.50 m)"
    assert verdict == Verdict.FAIL


def test_a_clear_pass() -> None:
    metrics, results, verdict, reason = judge(
        north_pass(5.0, y=6.0),
        spec(mission={"waypoints": [{"x": 39, "y": 6, "z": -5}], "land": False, "takeoffAltitude": 5}),
    )
    assert verdict == Verdict.PASS, reason
    assert reason == ""
    assert metrics.min_obstacle_distance == pytest.approx(4.0)
    assert metrics.flight_time == pytest.approx(39.9)
    assert metrics.max_altitude == pytest.approx(5.0)
    assert by_name(results)["missionCompleted"].passed
    assert (metrics.waypoints_reached, metrics.waypoints_total) == (2, 2)


def test_mission_progress_from_the_log_wins_over_the_path() -> None:
    progress = MissionProgress(reached=1, total=3, finished=False, source="mission_result")
    metrics, results, verdict, _ = judge(north_pass(5.0, y=6.0), spec(), mission=progress)
    assert not by_name(results)["missionCompleted"].passed
    assert metrics.mission_completed is False and verdict == Verdict.FAIL


def test_flight_time_and_geofence() -> None:
    s = spec(
        assertions={
            "maxFlightTime": 30,
            "geofence": {"maxX": 35, "minZ": -20},
            "minObstacleDistance": None,
            "missionCompleted": False,
        },
        world={},
    )
    metrics, results, _verdict, _reason = judge(north_pass(5.0), s)
    checks = by_name(results)
    assert not checks["maxFlightTime"].passed and checks["maxFlightTime"].value == pytest.approx(39.9)
    assert metrics.geofence_violation == pytest.approx(39.9 - 35)
    assert not checks["geofence"].passed
    assert set(checks) == {"maxFlightTime", "geofence"}


def test_similarity_to_an_inline_reference() -> None:
    ref = [[t, t, 0.0, -5.0] for t in np.arange(0.0, 40.0, 1.0)]
    s = spec(
        world={}, assertions={"similarity": {"metric": "dtw", "threshold": 1.0, "reference": {"points": ref}}}
    )
    metrics, _, verdict, _ = judge(north_pass(5.0), s)
    assert metrics.similarity == pytest.approx(0.0, abs=0.05) and verdict == Verdict.PASS  # ends 0.9 m apart
    metrics, _results, verdict, reason = judge(north_pass(7.0), s)
    assert metrics.similarity == pytest.approx(2.0, abs=0.01)
    assert verdict == Verdict.FAIL and "DTW per step to the reference 2.00 m > 1.00 m" in reason


def test_an_empty_flight_does_not_complete_its_mission() -> None:
    empty = Trajectory([], [], [], [])
    metrics, _results, verdict, reason = judge(empty, spec())
    assert metrics.flight_time == 0.0 and metrics.min_obstacle_distance is None
    assert verdict == Verdict.FAIL and "mission not completed: 0/2" in reason


def test_square_mission_log_against_a_native_test(square_log: ULog) -> None:
    # a 10 m tall box beside the first leg, 3 m West of it: the path (x≈0→30 at y≈0) passes ~3 m away
    box = {"size": {"l": 10, "w": 2, "h": 10}, "position": {"x": 15, "y": -4, "z": 0, "r": 0}}
    s = UavTestSpec.model_validate(
        {
            "mission": {"waypoints": [{"x": 30, "y": 0, "z": -10}, {"x": 30, "y": 30, "z": -10}]},
            "world": {"obstacles": [box]},
        }
    )
    tr = trajectory_from_ulog(square_log)
    metrics, _results, _verdict, _reason = judge(tr, s, mission=mission_progress_from_ulog(square_log))
    lateral = tr.y[(tr.x > 10) & (tr.x < 20)] + 3.0  # gap to the box East face (y = -3) along the box
    assert metrics.min_obstacle_distance == pytest.approx(lateral.min(), abs=0.05)
    assert metrics.mission_completed and metrics.waypoints_total == 4
