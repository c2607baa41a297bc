"""The mission a vehicle flies, as mission items in global coordinates (altitude relative to home).

Both mission sources become the same list: a QGroundControl plan (inline or ``planFile``)
and NED waypoints (projected around ``world.home`` as PX4 does). The list always starts with
a takeoff: a plan without one gets a takeoff to ``mission.takeoffAltitude`` above home.
"""

from __future__ import annotations

from pathlib import Path

from uavtest.spec.geo import ned_to_geodetic
from uavtest.spec.models import MissionItem, MissionItemKind, UavTestSpec
from uavtest.spec.plan import parse_plan, read_plan

__all__ = ["mission_items"]


def mission_items(spec: UavTestSpec) -> list[MissionItem]:
    """The mission items of ``spec`` in upload order; empty when the test has no mission.

    A takeoff item without a position takes off over home. ``planFile`` is read relative to
    the current folder (``load_test`` has inlined it already for tests loaded from files).
    """
    mission = spec.mission
    if mission is None:
        return []
    home = spec.world.home
    if mission.waypoints is not None:
        items = [
            MissionItem(
                kind=MissionItemKind.TAKEOFF, lat=home.lat, lon=home.lon, alt=mission.takeoff_altitude
            )
        ]
        for wp in mission.waypoints:
            lat, lon = ned_to_geodetic(wp.x, wp.y, home.lat, home.lon)
            items.append(
                MissionItem(
                    kind=MissionItemKind.WAYPOINT, lat=lat, lon=lon, alt=-wp.z, hold=wp.hold, yaw=wp.yaw
                )
            )
        if mission.land:
            last = items[-1]
            items.append(MissionItem(kind=MissionItemKind.LAND, lat=last.lat, lon=last.lon, alt=0.0))
        return items
    if mission.plan is not None:
        plan, source = mission.plan, "spec.mission.plan"
    else:
        assert mission.plan_file is not None  # the Mission model requires one source
        plan, source = read_plan(Path(mission.plan_file)), mission.plan_file
    items = parse_plan(plan, source, home_alt=home.alt, warn=False)
    if not any(item.kind == MissionItemKind.TAKEOFF for item in items):
        items.insert(0, MissionItem(kind=MissionItemKind.TAKEOFF, alt=mission.takeoff_altitude))
    return [
        item.model_copy(update={"lat": home.lat, "lon": home.lon})
        if item.kind == MissionItemKind.TAKEOFF and item.lat is None
        else item
        for item in items
    ]
