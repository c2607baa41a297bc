"""An independent client: MAVSDK (native binding, ``mavsdk`` >= 4) drives ``uavtest sitl``.

The simulator runs free at 10x real time on the port MAVSDK listens on (``udpin://``), as
PX4 SITL would; MAVSDK reads telemetry, uploads a mission, arms, starts it and sees it finish.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from harness.net import free_udp_port
from harness.sitl import eventually, free_running_argv, running_sitl

pytestmark = pytest.mark.integration

mavsdk = pytest.importorskip("mavsdk")


@pytest.fixture
def sitl_port(tmp_path: Path) -> Iterator[int]:
    port = free_udp_port()
    with running_sitl(free_running_argv(port, tmp_path / "log", 10)):
        yield port


def test_mavsdk_reads_telemetry_uploads_arms_and_flies_a_mission(sitl_port: int):
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.action import Action
    from mavsdk.plugins.mission import Mission, MissionItem, MissionPlan
    from mavsdk.plugins.telemetry import LandedState, Telemetry

    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    sdk.add_any_connection(f"udpin://127.0.0.1:{sitl_port}")
    system = sdk.first_autopilot(15.0)
    assert system is not None, "MAVSDK saw no autopilot"
    telemetry, action, mission = Telemetry(system), Action(system), Mission(system)

    eventually(
        lambda: telemetry.health().is_global_position_ok and telemetry.health().is_home_position_ok,
        20,
        "a global position and home",
    )
    eventually(lambda: telemetry.health().is_armable, 20, "armable")
    home = telemetry.home()
    assert abs(home.latitude_deg - 47.397742) < 1e-4 and abs(home.longitude_deg - 8.545594) < 1e-4
    assert telemetry.landed_state() == LandedState.ON_GROUND

    lat, lon = home.latitude_deg, home.longitude_deg
    plan = MissionPlan(
        [
            MissionItem(lat, lon, 8, vehicle_action=MissionItem.VehicleAction.TAKEOFF),
            MissionItem(lat + 0.0002, lon, 8),  # 22 m north
            MissionItem(lat + 0.0002, lon + 0.0003, 8, vehicle_action=MissionItem.VehicleAction.LAND),
        ]
    )
    mission.upload_mission(plan)
    downloaded = mission.download_mission()
    assert len(downloaded.mission_items) == 3
    action.arm()
    eventually(telemetry.armed, 10, "armed")
    mission.start_mission()
    eventually(lambda: telemetry.position().relative_altitude_m > 6, 30, "the takeoff")
    rates: list[tuple[float, float, float]] = []

    def finished_sampling_rates() -> bool:  # the body rates MAVSDK reads (ATTITUDE) on the legs
        w = telemetry.attitude_angular_velocity_body()
        rates.append((w.roll_rad_s, w.pitch_rad_s, w.yaw_rad_s))
        return mission.is_mission_finished()

    eventually(finished_sampling_rates, 60, "the mission to finish")
    # the vehicle leans into each leg and out of it, and turns: it reports rolling and pitching
    assert max(abs(r[0]) for r in rates) > 0.05 and max(abs(r[1]) for r in rates) > 0.05, rates
    eventually(lambda: not telemetry.armed(), 30, "disarm after landing")
    eventually(lambda: telemetry.landed_state() == LandedState.ON_GROUND, 5, "landed state on ground")
    pos = telemetry.position()
    assert abs(pos.latitude_deg - (lat + 0.0002)) < 2e-5 and abs(pos.longitude_deg - (lon + 0.0003)) < 3e-5
