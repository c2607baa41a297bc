"""Is the vehicle where the test says it starts? HOME_POSITION against ``world.home``. Pure.

A test's mission, obstacles and geofence are written around ``world.home``. A vehicle whose
home is elsewhere horizontally would fly the mission in the wrong place (or refuse it: "First
waypoint too far away"), so that is a bench error naming both positions. A home at the right
place but another altitude (PX4 v1.15's SIH ignores ``PX4_HOME_ALT``: its ground is
``SIH_LOC_H0``, 32.34 m by default) flies the same relative mission: the runner says so as a
warning in the output and in ``result.json``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.runner.events import HomePosition
from uavtest.spec.geo import geodetic_to_ned
from uavtest.spec.models import Home

__all__ = ["ALTITUDE_TOLERANCE_M", "HORIZONTAL_TOLERANCE_M", "HomeCheck", "check_home"]

#: a home this far from world.home is elsewhere (GPS and estimator noise stay well below: PX4 SIH
#: reports its home within ~0.2 m of PX4_HOME_LAT/LON)
HORIZONTAL_TOLERANCE_M = 5.0
ALTITUDE_TOLERANCE_M = 5.0  # PX4 SIH's home is ~0.2 m above SIH_LOC_H0 (the estimator's offset)


@dataclass(frozen=True, slots=True)
class HomeCheck:
    """The outcome: how far the reported home is, and the error or warning it makes."""

    horizontal_m: float
    vertical_m: float  # reported minus expected (positive: the vehicle's home is higher)
    error: str | None = None
    warning: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None and self.warning is None


def _where(lat: float, lon: float, alt: float) -> str:
    return f"{lat:.7f}, {lon:.7f} at {alt:.1f} m AMSL"


def check_home(
    expected: Home,
    reported: HomePosition,
    *,
    horizontal_tolerance_m: float = HORIZONTAL_TOLERANCE_M,
    altitude_tolerance_m: float = ALTITUDE_TOLERANCE_M,
) -> HomeCheck:
    """Compare the vehicle's HOME_POSITION with the test's ``world.home``."""
    lat, lon, alt = reported.lat / 1e7, reported.lon / 1e7, reported.alt_mm / 1000.0
    north, east = geodetic_to_ned(lat, lon, expected.lat, expected.lon)
    horizontal = math.hypot(north, east)
    vertical = alt - expected.alt
    theirs = f"the vehicle reports its home at {_where(lat, lon, alt)}"
    ours = f"the test's world.home is {_where(expected.lat, expected.lon, expected.alt)}"
    if horizontal > horizontal_tolerance_m:
        return HomeCheck(
            horizontal,
            vertical,
            error=(
                f"home mismatch: {theirs}, {ours}: {_distance(horizontal)} apart, so the mission would "
                "be flown in the wrong place (does the simulator get the test's home? PX4: PX4_HOME_LAT/LON)"
            ),
        )
    if abs(vertical) > altitude_tolerance_m:
        return HomeCheck(
            horizontal,
            vertical,
            warning=(  # whole metres: the same words for every replica of a run
                f"home altitude mismatch: the vehicle's home is at {alt:.0f} m AMSL, the test's "
                f"world.home at {expected.alt:.0f} m ({vertical:+.0f} m); the flight is relative "
                "to the vehicle's home, so absolute altitudes (AMSL) in its log differ from the test's "
                "(PX4 SIH takes its ground altitude from SIH_LOC_H0, not PX4_HOME_ALT)"
            ),
        )
    return HomeCheck(horizontal, vertical)


def _distance(metres: float) -> str:
    return f"{metres / 1000:.1f} km" if metres >= 10_000 else f"{metres:.1f} m"
