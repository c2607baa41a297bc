"""Mission completion from the path: targets reached in order."""

from __future__ import annotations

from pyulog import ULog

from uavtest.analysis.mission import (
    MissionTarget,
    mission_targets,
    progress_from_waypoints,
    targets_from_items,
)
from uavtest.analysis.ulog import trajectory_from_ulog
from uavtest.spec.models import Home, MissionItem, MissionItemKind, UavTestSpec

K = MissionItemKind
SQUARE = [
    MissionTarget(K.TAKEOFF, None, None, 10.0),
    MissionTarget(K.WAYPOINT, 30.0, 0.0, 10.0),
    MissionTarget(K.WAYPOINT, 30.0, 30.0, 10.0),
    MissionTarget(K.LAND, 30.0, 30.0, None),
]


def test_square_mission_reaches_every_target(square_log: ULog) -> None:
    progress = progress_from_waypoints(trajectory_from_ulog(square_log), SQUARE)
    assert (progress.reached, progress.total, progress.finished, progress.source) == (4, 4, True, "waypoints")


def test_an_unvisited_waypoint_stops_the_count(square_log: ULog) -> None:
    targets = [*SQUARE[:2], MissionTarget(K.WAYPOINT, 60.0, 0.0, 10.0), *SQUARE[2:]]
    progress = progress_from_waypoints(trajectory_from_ulog(square_log), targets)
    assert (progress.reached, progress.total, progress.finished) == (2, 5, False)


def test_order_matters(square_log: ULog) -> None:
    backwards = [SQUARE[0], SQUARE[2], SQUARE[1], SQUARE[3]]
    progress = progress_from_waypoints(trajectory_from_ulog(square_log), backwards)
    assert progress.reached == 2  # (30, 30) is reached, (30, 0) never again after it
    assert not progress.finished


def test_landing_elsewhere_is_not_reaching_the_land_item(square_log: ULog) -> None:
    targets = [*SQUARE[:3], MissionTarget(K.LAND, 0.0, 0.0, None)]
    assert progress_from_waypoints(trajectory_from_ulog(square_log), targets).reached == 3


def test_ned_waypoint_missions_become_targets() -> None:
    spec = UavTestSpec.model_validate(
        {
            "mission": {
                "takeoffAltitude": 8,
                "waypoints": [{"x": 30, "y": 0, "z": -8}, {"x": 30, "y": 30, "z": -8}],
            }
        }
    )
    targets = mission_targets(spec)
    assert targets == [
        MissionTarget(K.TAKEOFF, None, None, 8.0),
        MissionTarget(K.WAYPOINT, 30.0, 0.0, 8.0),
        MissionTarget(K.WAYPOINT, 30.0, 30.0, 8.0),
        MissionTarget(K.LAND, 30.0, 30.0, None),
    ]


def test_global_items_are_projected_around_home() -> None:
    home = Home(lat=47.397742, lon=8.545594, alt=488.0)
    # 0.001° of latitude is 111.19 m North on PX4's 6371 km sphere
    items = [
        MissionItem(kind=K.TAKEOFF, lat=home.lat, lon=home.lon, alt=10),
        MissionItem(kind=K.CHANGE_SPEED, speed=5),
        MissionItem(kind=K.WAYPOINT, lat=home.lat + 0.001, lon=home.lon, alt=10),
    ]
    targets = targets_from_items(items, home)
    assert len(targets) == 2
    assert targets[0] == MissionTarget(K.TAKEOFF, None, None, 10.0)
    assert abs(targets[1].x - 111.195) < 0.01 and abs(targets[1].y) < 1e-6
