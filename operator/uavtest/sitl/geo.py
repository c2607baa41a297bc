"""PX4's map projection on plain floats (fast per-sample), same formulas as ``uavtest.spec.geo``."""

from __future__ import annotations

import math

__all__ = ["Projection"]

EARTH_RADIUS = 6_371_000.0


class Projection:
    """Azimuthal equidistant projection around a reference (PX4 ``MapProjection``)."""

    __slots__ = ("_cos0", "_lat0r", "_lon0r", "_sin0", "lat0", "lon0")

    def __init__(self, lat0: float, lon0: float) -> None:
        self.lat0, self.lon0 = lat0, lon0
        self._lat0r, self._lon0r = math.radians(lat0), math.radians(lon0)
        self._sin0, self._cos0 = math.sin(self._lat0r), math.cos(self._lat0r)

    def project(self, lat: float, lon: float) -> tuple[float, float]:
        """(north, east) metres of a lat/lon in degrees."""
        lat_r, lon_r = math.radians(lat), math.radians(lon)
        sin_lat, cos_lat = math.sin(lat_r), math.cos(lat_r)
        cos_d = math.cos(lon_r - self._lon0r)
        arg = max(-1.0, min(1.0, self._sin0 * sin_lat + self._cos0 * cos_lat * cos_d))
        c = math.acos(arg)
        k = c / math.sin(c) if abs(c) > 0 else 1.0
        north = k * (self._cos0 * sin_lat - self._sin0 * cos_lat * cos_d) * EARTH_RADIUS
        east = k * cos_lat * math.sin(lon_r - self._lon0r) * EARTH_RADIUS
        return north, east

    def reproject(self, north: float, east: float) -> tuple[float, float]:
        """(lat, lon) degrees of a point ``north, east`` metres from the reference."""
        x, y = north / EARTH_RADIUS, east / EARTH_RADIUS
        c = math.hypot(x, y)
        if c == 0:
            return self.lat0, self.lon0
        sin_c, cos_c = math.sin(c), math.cos(c)
        lat = math.asin(max(-1.0, min(1.0, cos_c * self._sin0 + x * sin_c * self._cos0 / c)))
        lon = self._lon0r + math.atan2(y * sin_c, c * self._cos0 * cos_c - x * self._sin0 * sin_c)
        return math.degrees(lat), math.degrees(lon)
