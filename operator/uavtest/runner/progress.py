"""Stage 5: is the vehicle still getting to its next waypoint? (pure)

A vehicle flying a mission that stops getting closer to its next waypoint — in front of a wall
its obstacle avoidance cannot get around, or hesitating until it gives up — would otherwise hover
until the test's timeout and fail with "mission not completed" after minutes of nothing. The
runner ends such a flight early, as ``blocked``.

The next waypoint is the first mission item with a horizontal position (waypoint, loiter, land)
after the last item the vehicle reported reached (MISSION_ITEM_REACHED). Progress is a new
closest approach, ``PROGRESS_M`` closer than the previous one, in 3-D (a long climb to the
waypoint's altitude is progress too; a land item counts horizontally). Blocked: no progress for
``BLOCKED_AFTER_S`` seconds of vehicle time while armed, airborne and in mission mode, still
farther than ``NEAR_M`` from the waypoint (holding at a waypoint — a loiter time, the turn
towards the next leg — is not being blocked). PX4-Avoidance's slowest recoveries seen in the
competition's pictures (``mission2-failing.png``) hesitate for about a minute, with progress of a
metre or two between; 60 s without a metre of progress is past that.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from uavtest.runner.events import MissionItemInt
from uavtest.spec.geo import geodetic_to_ned
from uavtest.spec.models import Home

__all__ = ["BLOCKED_AFTER_S", "NEAR_M", "PROGRESS_M", "ProgressWatch"]

BLOCKED_AFTER_S = 60.0
PROGRESS_M = 1.0
NEAR_M = 3.0
#: MAV_CMD items that fly to a horizontal position: NAV_WAYPOINT, NAV_LOITER_UNLIM, NAV_LOITER_TURNS,
#: NAV_LOITER_TIME, NAV_LAND, NAV_LOITER_TO_ALT
_PLACES = frozenset({16, 17, 18, 19, 21, 31})
_GLOBAL_FRAMES = frozenset({0, 3, 5, 6, 10, 11})
_RELATIVE_FRAMES = frozenset({3, 6})  # altitude above home (0, 5: above mean sea level)
_LAND = 21


def mission_places(items: Sequence[MissionItemInt], home: Home) -> dict[int, tuple[float, float, float]]:
    """seq → (north, east, down) metres from home of the items that fly to a horizontal position
    (down NaN: not checked, for a land item and terrain frames)."""
    out: dict[int, tuple[float, float, float]] = {}
    for item in items:
        if item.command in _PLACES and item.frame in _GLOBAL_FRAMES and (item.x or item.y):
            n, e = geodetic_to_ned(item.x / 1e7, item.y / 1e7, home.lat, home.lon)
            down = math.nan
            if item.command != _LAND and item.frame in _RELATIVE_FRAMES:
                down = -item.z
            elif item.command != _LAND and item.frame in (0, 5):
                down = home.alt - item.z
            out[item.seq] = (float(n), float(e), down)
    return out


class ProgressWatch:
    """Folds positions and reached items into ``blocked`` (None, or why the flight is blocked)."""

    def __init__(
        self, items: Sequence[MissionItemInt], home: Home, *, after_s: float = BLOCKED_AFTER_S
    ) -> None:
        self.places = mission_places(items, home)
        self.after_ms = after_s * 1000.0
        self.reached = -1
        self.best = math.inf
        self.since_ms: int | None = None
        self.blocked: str | None = None

    def target(self) -> int | None:
        """The seq of the next place to fly to, None when none is left."""
        ahead: Iterable[int] = (s for s in self.places if s > self.reached)
        return min(ahead, default=None)

    def on_reached(self, seq: int) -> None:
        if seq > self.reached:
            self.reached = seq
            self.best, self.since_ms = math.inf, None

    def on_position(self, x: float, y: float, z: float, now_ms: int, flying_mission: bool) -> None:
        seq = self.target()
        if seq is None or not flying_mission or self.blocked is not None:
            self.best, self.since_ms = math.inf, None
            return
        tx, ty, tz = self.places[seq]
        d = math.hypot(tx - x, ty - y, 0.0 if tz != tz else tz - z)
        if self.since_ms is None or d <= NEAR_M or d < self.best - PROGRESS_M:
            self.best = min(self.best, d)
            self.since_ms = now_ms
            return
        if now_ms - self.since_ms >= self.after_ms:
            self.blocked = (
                f"blocked: no progress toward mission item {seq} for {self.after_ms / 1000:g} s "
                f"({d:.1f} m away)"
            )
