"""Geofence and rally (safe) points, as PX4 v1.15's navigator keeps and checks them.

Follows ``src/modules/navigator/geofence.cpp`` and ``navigator_main.cpp``
(``Navigator::geofence_breach_check``), release/1.15:

- ``GF_MAX_HOR_DIST`` (> 0): breach when the horizontal distance to home is not below it;
  ``GF_MAX_VER_DIST`` (> 0): breach when the altitude above home is not below it.
- The fence plan (MAV_MISSION_TYPE_FENCE): polygons (``NAV_FENCE_POLYGON_VERTEX_INCLUSION`` /
  ``_EXCLUSION``, param1 = vertex count, one item per vertex) and circles
  (``NAV_FENCE_CIRCLE_INCLUSION`` / ``_EXCLUSION``, param1 = radius). As
  ``Geofence::isInsidePolygonOrCircle`` does, *every* area must pass: the point is inside each
  inclusion area and outside each exclusion area (PNPOLY on lat/lon for polygons, a local
  projection for circles). A return point (``NAV_FENCE_RETURN_POINT``) is stored and not used,
  as in PX4. ``Geofence::_updateFence`` drops an area that does not contain home ("Geofence
  invalid, doesn't contain Home position") or, when flying with GF_ACTION set, the vehicle.
- The check runs every ``GEOFENCE_CHECK_INTERVAL_US`` (0.2 s) while ``GF_ACTION`` is not 0 and
  publishes ``geofence_result``. ``GF_PREDICT`` (experimental, default 0) is not modelled: the
  current position is checked, never a predicted one.
- Rally points (MAV_MISSION_TYPE_RALLY, ``NAV_RALLY_POINT``) are the RTL's safe points
  (``rtl.cpp`` ``findRtlDestination``): ones within 10 m of home are ignored, and one is taken
  instead of home when it is more than 2 m closer (``MIN_DIST_THRESHOLD``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from uavtest.sitl.geo import Projection
from uavtest.sitl.mission import NavItem

__all__ = [
    "FENCE_COMMANDS",
    "GEOFENCE_CHECK_INTERVAL_US",
    "NAV_FENCE_CIRCLE_EXCLUSION",
    "NAV_FENCE_CIRCLE_INCLUSION",
    "NAV_FENCE_POLYGON_VERTEX_EXCLUSION",
    "NAV_FENCE_POLYGON_VERTEX_INCLUSION",
    "NAV_FENCE_RETURN_POINT",
    "NAV_RALLY_POINT",
    "Area",
    "Geofence",
    "rally_destination",
]

NAV_FENCE_RETURN_POINT = 5000
NAV_FENCE_POLYGON_VERTEX_INCLUSION = 5001
NAV_FENCE_POLYGON_VERTEX_EXCLUSION = 5002
NAV_FENCE_CIRCLE_INCLUSION = 5003
NAV_FENCE_CIRCLE_EXCLUSION = 5004
NAV_RALLY_POINT = 5100
FENCE_COMMANDS = frozenset(
    {
        NAV_FENCE_RETURN_POINT,
        NAV_FENCE_POLYGON_VERTEX_INCLUSION,
        NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
        NAV_FENCE_CIRCLE_INCLUSION,
        NAV_FENCE_CIRCLE_EXCLUSION,
    }
)
_POLYGONS = (NAV_FENCE_POLYGON_VERTEX_INCLUSION, NAV_FENCE_POLYGON_VERTEX_EXCLUSION)
_INCLUSION = (NAV_FENCE_POLYGON_VERTEX_INCLUSION, NAV_FENCE_CIRCLE_INCLUSION)

GEOFENCE_CHECK_INTERVAL_US = 200_000  # GeofenceBreachAvoidance/geofence_breach_avoidance.h
SAFE_POINT_MIN_HOME_DIST = 10.0  # rtl.cpp MAX_DIST_FROM_HOME_FOR_LAND_APPROACHES
MIN_DIST_THRESHOLD = 2.0  # rtl.cpp


@dataclass(frozen=True, slots=True)
class Area:
    """One fence area: a polygon (vertices as lat/lon degrees) or a circle (centre, radius m)."""

    command: int
    vertices: tuple[tuple[float, float], ...] = ()
    radius: float = 0.0

    @property
    def inclusion(self) -> bool:
        return self.command in _INCLUSION

    def contains(self, lat: float, lon: float, proj: Projection) -> bool:
        if self.command in _POLYGONS:  # PNPOLY, exactly as Geofence::insidePolygon
            inside = False
            v = self.vertices
            j = len(v) - 1
            for i in range(len(v)):
                lat_i, lon_i = v[i]
                lat_j, lon_j = v[j]
                if (lon_i >= lon) != (lon_j >= lon) and lat <= (lat_j - lat_i) * (lon - lon_i) / (
                    lon_j - lon_i
                ) + lat_i:
                    inside = not inside
                j = i
            return inside
        cx, cy = proj.project(*self.vertices[0])
        x, y = proj.project(lat, lon)
        return (x - cx) ** 2 + (y - cy) ** 2 < self.radius * self.radius

    def passes(self, lat: float, lon: float, proj: Projection) -> bool:
        """Geofence::checkPointAgainstPolygonCircle: inside an inclusion, outside an exclusion."""
        return self.contains(lat, lon, proj) == self.inclusion


def areas_of(items: Sequence[NavItem]) -> list[Area]:
    """The areas of a fence plan, walked as Geofence::_updateFence does (return points skipped)."""
    out: list[Area] = []
    seq = 0
    while seq < len(items):
        item = items[seq]
        if item.command in _POLYGONS:
            count = int(item.param1 + 0.5)
            if count == 0:
                seq += 1
                continue
            verts = tuple((it.lat, it.lon) for it in items[seq : seq + count])
            out.append(Area(item.command, verts))
            seq += count
        elif item.command in (NAV_FENCE_CIRCLE_INCLUSION, NAV_FENCE_CIRCLE_EXCLUSION):
            out.append(Area(item.command, ((item.lat, item.lon),), item.param1))
            seq += 1
        else:
            seq += 1
    return out


class Geofence:
    """The geofence the navigator checks: parameters, the uploaded areas, and the last result."""

    def __init__(self, proj: Projection) -> None:
        self.proj = proj
        self.areas: list[Area] = []
        self.max_dist = False
        self.max_alt = False
        self.custom = False

    @property
    def breached(self) -> bool:
        return self.max_dist or self.max_alt or self.custom

    def set_areas(
        self, items: Sequence[NavItem], home: tuple[float, float], flying_at: tuple[float, float] | None
    ) -> list[str]:
        """Install a fence plan; returns PX4's critical texts for areas it drops (home, vehicle)."""
        self.areas = []
        texts: list[str] = []
        for area in areas_of(items):
            if not area.passes(home[0], home[1], self.proj):
                texts.append("Geofence invalid, doesn't contain Home position")
            elif flying_at is not None and not area.passes(flying_at[0], flying_at[1], self.proj):
                texts.append("Geofence invalid, doesn't contain current vehicle position")
            else:
                self.areas.append(area)
        return texts

    def inside_areas(self, lat: float, lon: float) -> bool:
        """Geofence::isInsidePolygonOrCircle (empty fence: everything is inside)."""
        proj = self.proj
        return all(a.passes(lat, lon, proj) for a in self.areas)

    def check(
        self, x: float, y: float, alt: float, home: tuple[float, float, float], max_hor: float, max_ver: float
    ) -> None:
        """One breach check at local (x, y) and ``alt`` above home; home = local (x, y, alt)."""
        self.max_dist = max_hor > 0 and not math.hypot(x - home[0], y - home[1]) < max_hor
        self.max_alt = max_ver > 0 and not alt - home[2] < max_ver
        if self.areas:
            lat, lon = self.proj.reproject(x, y)
            self.custom = not self.inside_areas(lat, lon)
        else:
            self.custom = False

    def allows(
        self, x: float, y: float, alt: float, home: tuple[float, float, float], max_hor: float, max_ver: float
    ) -> bool:
        """Geofence::checkPointAgainstAllGeofences for a local point (mission feasibility)."""
        if max_hor > 0 and not math.hypot(x - home[0], y - home[1]) < max_hor:
            return False
        if max_ver > 0 and not alt - home[2] < max_ver:
            return False
        if self.areas:
            lat, lon = self.proj.reproject(x, y)
            return self.inside_areas(lat, lon)
        return True


def rally_destination(
    rally: Sequence[tuple[float, float]], pos: tuple[float, float], home: tuple[float, float]
) -> tuple[float, float, int] | None:
    """RTL_TYPE 0 (rtl.cpp findRtlDestination): the rally point (local x, y, index) closer than
    home by more than ``MIN_DIST_THRESHOLD``, the closest such; None = home."""
    best = None
    min_dist = math.hypot(pos[0] - home[0], pos[1] - home[1])
    for i, (rx, ry) in enumerate(rally):
        if not math.hypot(rx - home[0], ry - home[1]) > SAFE_POINT_MIN_HOME_DIST:
            continue
        d = math.hypot(pos[0] - rx, pos[1] - ry)
        if d + MIN_DIST_THRESHOLD < min_dist:
            min_dist = d
            best = (rx, ry, i)
    return best
