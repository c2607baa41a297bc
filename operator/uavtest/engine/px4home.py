"""Where PX4 SITL's SIH physics starts: the test's home, as PX4's own environment variables.

PX4's startup script copies ``PX4_HOME_LAT``/``PX4_HOME_LON`` into the SIH parameters
``SIH_LOC_LAT0``/``SIH_LOC_LON0`` verbatim. Up to v1.15 those are INT32 in degrees * 1e7 (default
Montreal, 45.467116, -73.757837); from v1.16 they are FLOAT degrees (default Zurich). The build's
``parameters.json`` (next to ``bin/``) says which; without it the float form of newer PX4 is used.
Without this, PX4 flies from its default place and rejects a mission written around the test's
home ("First waypoint too far away").
"""

from __future__ import annotations

import json
from pathlib import Path

from uavtest.spec.models import Home

__all__ = ["px4_home_env", "sih_latlon_is_int"]


def sih_latlon_is_int(px4_bin: Path) -> bool:
    """True when this PX4 build's ``SIH_LOC_LAT0`` is an INT32 (degrees * 1e7, PX4 <= v1.15)."""
    meta = px4_bin.resolve().parent.parent / "parameters.json"
    try:
        params = json.loads(meta.read_text())["parameters"]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    for param in params:
        if isinstance(param, dict) and param.get("name") == "SIH_LOC_LAT0":
            return str(param.get("type", "")).lower().startswith("int")
    return False


def px4_home_env(home: Home, *, int_latlon: bool) -> dict[str, str]:
    """``PX4_HOME_LAT``/``LON``/``ALT`` for PX4 SITL so that it starts at ``home``."""
    if int_latlon:
        lat, lon = str(round(home.lat * 1e7)), str(round(home.lon * 1e7))
    else:
        lat, lon = f"{home.lat:.8f}", f"{home.lon:.8f}"
    return {"PX4_HOME_LAT": lat, "PX4_HOME_LON": lon, "PX4_HOME_ALT": f"{home.alt:.2f}"}
