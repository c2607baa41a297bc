"""Where PX4 SITL's SIH physics starts: the test's home, as PX4's own environment variables.

PX4's startup script copies ``PX4_HOME_LAT``/``PX4_HOME_LON`` into the SIH parameters
``SIH_LOC_LAT0``/``SIH_LOC_LON0`` verbatim. Up to v1.15 those are INT32 in degrees * 1e7 (default
Montreal, 45.467116, -73.757837); from v1.16 they are FLOAT degrees (default Zurich). The build's
``parameters.json`` (next to ``bin/``) says which; without it the float form of newer PX4 is used.
Without this, PX4 flies from its default place and rejects a mission written around the test's
home ("First waypoint too far away").

PX4's start-up ignores ``PX4_HOME_ALT``: SIH's ground altitude is the parameter ``SIH_LOC_H0``
(default 32.34 m), so PX4 would report a home 450 m below a test at 488 m AMSL. Setting it over
MAVLink after boot is too late (the estimator and home are already initialised on the old
ground). PX4's rcS sources ``px4-rc.params`` ("user defined params for instances can be in
PATH") after its parameter reset and airframe and before it starts SIH: the engine writes one
into a folder of the replica's working directory that comes first in PX4's PATH; it sets
``SIH_LOC_H0`` to the test's altitude and then sources the build's own ``px4-rc.params``. The
runner checks the home PX4 reports either way (``uavtest.runner.home``).
"""

from __future__ import annotations

import json
from pathlib import Path

from uavtest.spec.models import Home

__all__ = [
    "RC_PARAMS",
    "px4_home_env",
    "px4_rc_params",
    "px4_search_path",
    "px4_start_files",
    "sih_latlon_is_int",
]

RC_PARAMS = "px4-rc.params"  # what PX4's rcS sources from PATH before it starts SIH
RC_DIR = "uavtest-rc"  # the folder in PX4's working directory that holds it


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


def px4_rc_params(home: Home) -> str:
    """The ``px4-rc.params`` that puts SIH's ground at the test's altitude (AMSL)."""
    return (
        "#!/bin/sh\n"
        "# uavtest: SIH's ground altitude is the test's world.home.alt (PX4 ignores PX4_HOME_ALT)\n"
        f"param set SIH_LOC_H0 {home.alt:.3f}\n"
        '. "${R}etc/init.d-posix/px4-rc.params"\n'
    )


def px4_start_files(working_dir: Path, home: Home) -> dict[Path, str]:
    """The files the engine writes into PX4's working directory before starting it."""
    return {working_dir / RC_DIR / RC_PARAMS: px4_rc_params(home)}


def px4_search_path(working_dir: Path, path: str) -> str:
    """PX4's PATH: the engine's rc folder first, so rcS sources its ``px4-rc.params``."""
    rc_dir = str(working_dir / RC_DIR)
    return f"{rc_dir}:{path}" if path else rc_dir
