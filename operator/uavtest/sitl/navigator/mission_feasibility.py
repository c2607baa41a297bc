"""Whether PX4 v1.15 would fly a mission: the multicopter checks of ``FeasibilityChecker`` (pure).

``src/modules/navigator/MissionFeasibility/FeasibilityChecker.cpp``, item by item as
``processNextItem`` runs them, each failure said once as PX4's ``mavlink_log_critical`` says it:

- validity: a mission that starts with a land item while the vehicle is landed ("Mission
  rejected: starts with landing"); a failing item stops the other checks;
- takeoff (``checkTakeoff``): a takeoff item at or below home ("Mission rejected: Takeoff
  altitude below home altitude!"), or after an item that flies somewhere ("Mission rejected:
  takeoff not first waypoint item": an ArduPilot-style QGC WPL file, whose item 0 is home,
  followed by a takeoff, is refused by PX4);
- the first item with a position farther than ``MIS_DIST_1WP`` from the vehicle ("First
  waypoint too far away: Nm, M max"; 0 or less: no limit);
- at the last item, ``MIS_TKO_LAND_REQ`` (0 nothing required; 1 a takeoff; 2 a landing; 3
  both; 4 both or neither; 5 as 4 on the ground, a landing in the air).

Not here: unsupported commands (the built-in vehicle refuses them at upload:
``uavtest.sitl.mission.check_item``), VTOL and fixed-wing checks (a multicopter only), gates; the
geofence check is the navigator's (``Navigator.check_mission_feasible``). Without a home the
mission is not checked here (PX4: "Not yet ready for mission, no position lock").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from uavtest.sitl.mav import MavCmd
from uavtest.sitl.mission import NavItem, has_position

__all__ = ["feasibility_failures"]

#: MAV_CMDs that do not make a later takeoff "not first" (``checkTakeoff``'s
#: ``_found_item_with_position`` turns true on any other: NAV_DELAY, DO_JUMP, DO_CHANGE_SPEED,
#: DO_SET_HOME, DO_LAND_START, DO_TRIGGER_CONTROL, DO_DIGICAM_CONTROL, IMAGE_START/STOP_CAPTURE,
#: VIDEO_START/STOP_CAPTURE, DO_CONTROL_VIDEO, DO_MOUNT_CONFIGURE/CONTROL,
#: DO_GIMBAL_MANAGER_PITCHYAW/CONFIGURE, DO_SET_ROI(_LOCATION, _WPNEXT_OFFSET, _NONE),
#: DO_SET_CAM_TRIGG_DIST, OBLIQUE_SURVEY, DO_SET_CAM_TRIGG_INTERVAL, SET_CAMERA_MODE/ZOOM/FOCUS,
#: DO_VTOL_TRANSITION)
_NO_POSITION_YET = frozenset(
    {93, 177, 178, 179, 189, 2003, 203, 2000, 2001, 2500, 2501, 200, 204, 205, 1000, 1001, 201, 195, 196, 197}
    | {206, 260, 214, 530, 531, 532, 3000}
)


def _takeoff_land_required(req: int, has_takeoff: bool, has_land: bool, landed: bool) -> str | None:
    """``checkTakeoffLandAvailable``: the failure text for ``MIS_TKO_LAND_REQ``, None if it holds."""
    if req == 1 and not has_takeoff:
        return "Mission rejected: Takeoff waypoint required."
    if req == 2 and not has_land:
        return "Mission rejected: Landing waypoint/pattern required."
    if req == 3 and not (has_takeoff and has_land):
        return "Mission rejected: Takeoff or Landing item missing."
    if req == 4 or (req == 5 and landed):
        if has_takeoff and not has_land:
            return "Mission rejected: Add Landing item or remove Takeoff."
        if has_land and not has_takeoff:
            return "Mission rejected: Add Takeoff item or remove Landing."
    elif req == 5 and not has_land:
        return "Mission rejected: Landing waypoint/pattern required."
    return None


def feasibility_failures(
    items: Sequence[NavItem],
    *,
    landed: bool,
    home_amsl: float,
    distance_to: Callable[[NavItem], float],  # horizontal metres from the vehicle to the item
    dist_1wp: float,
    takeoff_land_req: int,
) -> list[str]:
    """The texts of the checks ``items`` fail, in PX4's order; empty: PX4 would fly it."""
    failures: list[str] = []
    found_position = False
    first_checked = False
    has_takeoff = has_land = False
    takeoff_failed = distance_failed = False
    for i, item in enumerate(items):
        cmd = item.command
        if i == 0 and cmd == MavCmd.NAV_LAND and landed:
            return ["Mission rejected: starts with landing"]  # checkMissionItemValidity: stop
        if not distance_failed and dist_1wp > 0 and not first_checked and has_position(item):
            first_checked = True
            d = distance_to(item)
            if not d < dist_1wp:
                distance_failed = True
                failures.append(f"First waypoint too far away: {int(d)}m, {int(dist_1wp)} max")
        if not takeoff_failed and cmd == MavCmd.NAV_TAKEOFF:
            if not item.alt_rel(home_amsl) > 1.1920929e-07:  # FLT_EPSILON
                takeoff_failed = True
                failures.append("Mission rejected: Takeoff altitude below home altitude!")
            else:
                has_takeoff = True
                if found_position:
                    takeoff_failed = True
                    failures.append("Mission rejected: takeoff not first waypoint item")
        if not found_position:
            found_position = cmd not in _NO_POSITION_YET
        has_land |= cmd == MavCmd.NAV_LAND
    text = _takeoff_land_required(takeoff_land_req, has_takeoff, has_land, landed)
    if text is not None:
        failures.append(text)
    return failures
