"""Local NED ⇄ geodetic conversion around a home position, exactly as PX4 does it.

PX4 maps latitude/longitude to its local frame with an azimuthal equidistant projection
around the reference (``MapProjection::project`` / ``reproject`` in PX4's
``lib/geo/geo.cpp``, Earth radius 6 371 000 m). Using the same formulas here keeps the
built-in simulator, the runner's mission upload and the analysis of real PX4 logs in the
same frame to the millimetre. Works on floats and on numpy arrays alike.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np
import numpy.typing as npt

__all__ = ["EARTH_RADIUS", "alt_to_down", "down_to_alt", "geodetic_to_ned", "ned_to_geodetic"]

EARTH_RADIUS = 6_371_000.0  # metres, PX4 CONSTANTS_RADIUS_OF_EARTH

Scalar = TypeVar("Scalar", float, npt.NDArray[np.float64])


def _out(value: npt.NDArray[np.float64], like: object) -> object:
    return float(value) if np.ndim(like) == 0 else value


def geodetic_to_ned(lat: Scalar, lon: Scalar, ref_lat: float, ref_lon: float) -> tuple[Scalar, Scalar]:
    """North, East metres of ``lat, lon`` (degrees) from the reference ``ref_lat, ref_lon``."""
    lat_r = np.radians(np.asarray(lat, dtype=float))
    lon_r = np.radians(np.asarray(lon, dtype=float))
    ref_lat_r, ref_lon_r = np.radians(ref_lat), np.radians(ref_lon)
    sin_ref, cos_ref = np.sin(ref_lat_r), np.cos(ref_lat_r)
    sin_lat, cos_lat = np.sin(lat_r), np.cos(lat_r)
    cos_d_lon = np.cos(lon_r - ref_lon_r)
    c = np.arccos(np.clip(sin_ref * sin_lat + cos_ref * cos_lat * cos_d_lon, -1.0, 1.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(np.abs(c) > 0, c / np.sin(c), 1.0)
    north = k * (cos_ref * sin_lat - sin_ref * cos_lat * cos_d_lon) * EARTH_RADIUS
    east = k * cos_lat * np.sin(lon_r - ref_lon_r) * EARTH_RADIUS
    return _out(north, lat), _out(east, lat)  # type: ignore[return-value]


def ned_to_geodetic(north: Scalar, east: Scalar, ref_lat: float, ref_lon: float) -> tuple[Scalar, Scalar]:
    """Latitude, longitude (degrees) of the point ``north, east`` metres from the reference."""
    x = np.asarray(north, dtype=float) / EARTH_RADIUS
    y = np.asarray(east, dtype=float) / EARTH_RADIUS
    ref_lat_r, ref_lon_r = np.radians(ref_lat), np.radians(ref_lon)
    sin_ref, cos_ref = np.sin(ref_lat_r), np.cos(ref_lat_r)
    c = np.hypot(x, y)
    sin_c, cos_c = np.sin(c), np.cos(c)
    with np.errstate(invalid="ignore", divide="ignore"):
        lat_r = np.where(
            c > 0, np.arcsin(np.clip(cos_c * sin_ref + (x * sin_c * cos_ref) / c, -1, 1)), ref_lat_r
        )
    lon_r = np.where(
        c > 0, ref_lon_r + np.arctan2(y * sin_c, c * cos_ref * cos_c - x * sin_ref * sin_c), ref_lon_r
    )
    return _out(np.degrees(lat_r), north), _out(np.degrees(lon_r), north)  # type: ignore[return-value]


def alt_to_down(alt_amsl: Scalar, ref_alt: float) -> Scalar:
    """NED Down (metres) of an altitude above mean sea level, relative to the reference altitude."""
    return ref_alt - alt_amsl  # type: ignore[return-value]


def down_to_alt(down: Scalar, ref_alt: float) -> Scalar:
    """Altitude above mean sea level of a NED Down coordinate."""
    return ref_alt - down  # type: ignore[return-value]
