"""Mission items as the vehicle stores them (the MISSION_ITEM_INT wire form), and checks.

Items keep exactly what was uploaded, so a download returns it unchanged. ``from_spec``
turns the test model's ``MissionItem`` list (global, altitude relative to home) into the same
form, for flying a mission in-process without MAVLink.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from uavtest.sitl.mav import MavCmd, MavFrame, MissionResult
from uavtest.spec.models import MissionItem, MissionItemKind

__all__ = [
    "GLOBAL_FRAMES",
    "NAV_COMMANDS",
    "SUPPORTED_COMMANDS",
    "NavItem",
    "check_item",
    "from_spec",
    "has_position",
]

#: commands that fly somewhere (have a position)
NAV_COMMANDS = frozenset(
    {
        MavCmd.NAV_WAYPOINT,
        MavCmd.NAV_LOITER_UNLIM,
        MavCmd.NAV_LOITER_TIME,
        MavCmd.NAV_LAND,
        MavCmd.NAV_TAKEOFF,
    }
)
#: every command a mission may hold: the nav commands, RTL, change speed, and camera no-ops
SUPPORTED_COMMANDS = NAV_COMMANDS | {
    MavCmd.NAV_RETURN_TO_LAUNCH,
    MavCmd.DO_CHANGE_SPEED,
    MavCmd.DO_LAND_START,  # a marker: DO_LAND_START jumps here (navigator: skipped when flown)
    MavCmd.SET_CAMERA_MODE,
    203,  # DO_DIGICAM_CONTROL
    206,  # DO_SET_CAM_TRIGG_DIST
    2000,  # IMAGE_START_CAPTURE
    2001,  # IMAGE_STOP_CAPTURE
    2500,  # VIDEO_START_CAPTURE
    2501,  # VIDEO_STOP_CAPTURE
}
GLOBAL_FRAMES = _GLOBAL_FRAMES = frozenset(
    {MavFrame.GLOBAL, MavFrame.GLOBAL_RELATIVE_ALT, MavFrame.GLOBAL_INT, MavFrame.GLOBAL_RELATIVE_ALT_INT}
)
_RELATIVE_FRAMES = frozenset({MavFrame.GLOBAL_RELATIVE_ALT, MavFrame.GLOBAL_RELATIVE_ALT_INT})


@dataclass(frozen=True, slots=True)
class NavItem:
    """One mission item as MISSION_ITEM_INT carries it (x, y: degrees * 1e7; z: metres)."""

    seq: int
    command: int
    frame: int
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = math.nan
    x: int = 0
    y: int = 0
    z: float = 0.0
    autocontinue: int = 1

    @property
    def lat(self) -> float:
        return self.x / 1e7

    @property
    def lon(self) -> float:
        return self.y / 1e7

    def alt_rel(self, home_alt: float) -> float:
        """Altitude above home, whatever the frame."""
        return self.z if self.frame in _RELATIVE_FRAMES else self.z - home_alt


def has_position(item: NavItem) -> bool:
    return item.command in NAV_COMMANDS and not (item.x == 0 and item.y == 0)


def check_item(item: NavItem) -> MissionResult:
    """ACCEPTED, or why PX4 would refuse the item (MAV_MISSION_UNSUPPORTED / _FRAME / INVALID)."""
    if item.command not in SUPPORTED_COMMANDS:
        return MissionResult.UNSUPPORTED
    if item.command in NAV_COMMANDS:
        if item.frame not in _GLOBAL_FRAMES:
            return MissionResult.UNSUPPORTED_FRAME
        if not math.isfinite(item.z) or abs(item.x) > 900_000_000 or abs(item.y) > 1_800_000_000:
            return MissionResult.INVALID
    return MissionResult.ACCEPTED


def from_spec(items: Sequence[MissionItem]) -> list[NavItem]:
    """The test model's mission items as uploadable items (frame GLOBAL_RELATIVE_ALT_INT)."""
    out: list[NavItem] = []
    rel = MavFrame.GLOBAL_RELATIVE_ALT_INT
    for item in items:
        seq = len(out)
        lat = round(item.lat * 1e7) if item.lat is not None else 0
        lon = round(item.lon * 1e7) if item.lon is not None else 0
        alt = item.alt if item.alt is not None else 0.0
        yaw = item.yaw if item.yaw is not None else math.nan  # param4: heading, degrees
        if item.kind == MissionItemKind.TAKEOFF:
            out.append(NavItem(seq, MavCmd.NAV_TAKEOFF, rel, param4=yaw, x=lat, y=lon, z=alt))
        elif item.kind == MissionItemKind.WAYPOINT:
            out.append(
                NavItem(seq, MavCmd.NAV_WAYPOINT, rel, param1=item.hold, param4=yaw, x=lat, y=lon, z=alt)
            )
        elif item.kind == MissionItemKind.LOITER_TIME:
            out.append(
                NavItem(seq, MavCmd.NAV_LOITER_TIME, rel, param1=item.hold, param4=yaw, x=lat, y=lon, z=alt)
            )
        elif item.kind == MissionItemKind.LAND:
            out.append(NavItem(seq, MavCmd.NAV_LAND, rel, param4=yaw, x=lat, y=lon, z=alt))
        elif item.kind == MissionItemKind.RETURN:
            out.append(NavItem(seq, MavCmd.NAV_RETURN_TO_LAUNCH, MavFrame.MISSION))
        elif item.kind == MissionItemKind.CHANGE_SPEED:
            out.append(
                NavItem(
                    seq,
                    MavCmd.DO_CHANGE_SPEED,
                    MavFrame.MISSION,
                    param1=1.0,
                    param2=item.speed or -1.0,
                    param3=-1.0,
                )
            )
    return out
