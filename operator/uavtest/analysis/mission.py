"""Mission completion from the path itself: were the mission's targets reached, in order?

Used when a log has no ``mission_result`` (PX4's own account, read by
``uavtest.analysis.ulog.mission_progress_from_ulog``). A target is reached when a sample comes
within the acceptance radius of it, after the previous target was reached:

- takeoff: altitude within ``altitude_tolerance`` of the takeoff altitude (position not checked);
- waypoint / loiter: horizontal distance ≤ ``acceptance_radius`` and altitude within
  ``altitude_tolerance``;
- land / return: horizontal distance ≤ ``acceptance_radius`` (return: of home) and the flight
  ends there, back down (altitude below ``ground_tolerance``, 2 m: the estimator's ground drifts)
  — checked on the last sample of the flight.

The acceptance radius defaults to PX4's ``NAV_ACC_RAD`` from the test's params (2 m when unset),
floored at 1 m so logging noise does not miss a waypoint PX4 itself accepted.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from uavtest.analysis.models import MissionProgress
from uavtest.analysis.trajectory import Trajectory
from uavtest.spec.geo import geodetic_to_ned
from uavtest.spec.models import Home, MissionItem, MissionItemKind, UavTestSpec

__all__ = [
    "MissionTarget",
    "acceptance_radius",
    "mission_targets",
    "progress_from_waypoints",
    "targets_from_items",
]

MIN_ACCEPTANCE = 1.0


@dataclass(frozen=True, slots=True)
class MissionTarget:
    """A place the mission must reach: NED metres from home; None = not checked."""

    kind: MissionItemKind
    x: float | None
    y: float | None
    altitude: float | None  # metres above home (up)


def targets_from_items(items: Sequence[MissionItem], home: Home) -> list[MissionTarget]:
    """Targets of global mission items (change-speed items set no target)."""
    targets: list[MissionTarget] = []
    for item in items:
        if item.kind == MissionItemKind.CHANGE_SPEED:
            continue
        if item.kind == MissionItemKind.RETURN:
            targets.append(MissionTarget(item.kind, 0.0, 0.0, None))
            continue
        x = y = None
        if item.lat is not None and item.lon is not None and item.kind != MissionItemKind.TAKEOFF:
            x, y = geodetic_to_ned(item.lat, item.lon, home.lat, home.lon)
        alt = item.alt if item.kind not in (MissionItemKind.LAND,) else None
        targets.append(MissionTarget(item.kind, x, y, alt))
    return targets


def mission_targets(spec: UavTestSpec) -> list[MissionTarget] | None:
    """The targets of the test's mission; None when it has none or it cannot be resolved here."""
    mission = spec.mission
    if mission is None:
        return None
    if mission.waypoints is not None:
        targets = [MissionTarget(MissionItemKind.TAKEOFF, None, None, mission.takeoff_altitude)]
        targets += [MissionTarget(MissionItemKind.WAYPOINT, w.x, w.y, -w.z) for w in mission.waypoints]
        if mission.land and mission.waypoints:
            last = mission.waypoints[-1]
            targets.append(MissionTarget(MissionItemKind.LAND, last.x, last.y, None))
        return targets
    try:  # plans: the spec package turns them into global items (written in parallel)
        from uavtest.spec.mission import mission_items
    except ImportError:
        return None
    return targets_from_items(mission_items(spec), spec.world.home)


def acceptance_radius(spec: UavTestSpec | None) -> float:
    """PX4 NAV_ACC_RAD from the test's params (2 m default), at least 1 m."""
    value = spec.vehicle.params.get("NAV_ACC_RAD", 2.0) if spec is not None else 2.0
    return max(float(value), MIN_ACCEPTANCE)


def progress_from_waypoints(
    trajectory: Trajectory,
    targets: Sequence[MissionTarget],
    *,
    acceptance_radius: float = 2.0,
    altitude_tolerance: float = 1.0,
    ground_tolerance: float = 2.0,
) -> MissionProgress:
    """How many targets the flight reached in order (module docstring for the rules)."""
    reached = 0
    start = 0
    n = len(trajectory)
    alt = trajectory.altitude
    for target in targets:
        if start >= n:
            break
        ok = np.ones(n - start, dtype=bool)
        if target.x is not None and target.y is not None:
            dist = np.hypot(trajectory.x[start:] - target.x, trajectory.y[start:] - target.y)
            ok &= dist <= acceptance_radius
        if target.kind in (MissionItemKind.LAND, MissionItemKind.RETURN):
            # the flight must end there, on the ground
            if not (ok[-1] and alt[-1] <= ground_tolerance):
                break
            reached += 1
            start = n - 1
            continue
        if target.altitude is not None:
            if target.kind == MissionItemKind.TAKEOFF:
                ok &= alt[start:] >= target.altitude - altitude_tolerance
            else:
                ok &= np.abs(alt[start:] - target.altitude) <= altitude_tolerance
        hits = np.flatnonzero(ok)
        if not len(hits):
            break
        reached += 1
        start += int(hits[0])
    total = len(targets)
    return MissionProgress(reached=reached, total=total, finished=reached == total, source="waypoints")
