"""A MAVSDK-Python 3.x client (the asyncio/gRPC API most MAVSDK examples use) flying a mission.

Run as a script by ``test_sitl_mavsdk3.py`` with MAVSDK 3.x first on ``PYTHONPATH``:
``python mavsdk3_mission.py PORT``. Prints one JSON line of what it saw; exits non-zero on a
timeout. Written as a MAVSDK 3 user writes it, from MAVSDK-Python's own examples.
"""

from __future__ import annotations

import asyncio
import json
import sys
from collections.abc import AsyncIterator
from typing import TypeVar

import mavsdk
from mavsdk import System
from mavsdk.mission import MissionItem, MissionPlan

T = TypeVar("T")


def item(lat: float, lon: float, alt: float) -> MissionItem:
    nan = float("nan")
    return MissionItem(
        lat,
        lon,
        alt,
        5.0,
        True,
        nan,
        nan,
        MissionItem.CameraAction.NONE,
        nan,
        nan,
        nan,
        nan,
        nan,
        MissionItem.VehicleAction.NONE,
    )


async def first(stream: AsyncIterator[T]) -> T:
    async for value in stream:
        return value
    raise RuntimeError("the telemetry stream ended")


async def fly(port: int) -> dict[str, object]:
    drone = System()
    await drone.connect(system_address=f"udp://:{port}")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok and health.is_armable:
            break
    home = await first(drone.telemetry.home())
    info = await drone.info.get_version()
    lat, lon = home.latitude_deg, home.longitude_deg
    plan = MissionPlan([item(lat + 0.0002, lon, 8.0), item(lat + 0.0002, lon + 0.0003, 8.0)])
    await drone.mission.set_return_to_launch_after_mission(False)
    await drone.mission.upload_mission(plan)
    await drone.action.arm()
    await drone.mission.start_mission()
    async for progress in drone.mission.mission_progress():
        if progress.current == progress.total:
            break
    max_alt = (await first(drone.telemetry.position())).relative_altitude_m
    await drone.action.land()
    async for armed in drone.telemetry.armed():
        if not armed:
            break
    pos = await first(drone.telemetry.position())
    return {
        "mavsdk": mavsdk.__file__,
        "flight_sw_major": info.flight_sw_major,
        "flight_sw_minor": info.flight_sw_minor,
        "home": [lat, lon],
        "end": [pos.latitude_deg, pos.longitude_deg],
        "alt_at_end_of_mission": max_alt,
    }


if __name__ == "__main__":
    result = asyncio.run(asyncio.wait_for(fly(int(sys.argv[1])), 120))
    print(json.dumps(result))
