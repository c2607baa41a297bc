"""MAVSDK (native binding) as a PX4 user would use it against `uavtest sitl`: Geofence plugin
upload, MissionRaw rally points and fence download, a mission beyond the fence refused, sticks
(ManualControl) across the fence, and the vehicle returning to the closest rally point."""

from __future__ import annotations

import math
import threading
import time
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
    with running_sitl(free_running_argv(port, tmp_path / "log", 2)):
        yield port


def test_mavsdk_fence_rally_and_return(sitl_port: int):
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.action import Action, ActionError
    from mavsdk.plugins.geofence import Circle, FenceType, Geofence, GeofenceData, Point, Polygon
    from mavsdk.plugins.manual_control import ManualControl
    from mavsdk.plugins.mission import Mission, MissionItem, MissionPlan
    from mavsdk.plugins.mission_raw import MissionItem as RawItem
    from mavsdk.plugins.mission_raw import MissionRaw
    from mavsdk.plugins.param import Param
    from mavsdk.plugins.telemetry import FlightMode, Telemetry

    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    sdk.add_any_connection(f"udpin://127.0.0.1:{sitl_port}")
    system = sdk.first_autopilot(15.0)
    assert system is not None, "MAVSDK saw no autopilot"
    telemetry, action, mission = Telemetry(system), Action(system), Mission(system)
    geofence, raw, param, manual = Geofence(system), MissionRaw(system), Param(system), ManualControl(system)
    eventually(lambda: telemetry.health().is_home_position_ok, 20, "home")
    eventually(lambda: telemetry.health().is_armable, 20, "armable")
    home = telemetry.home()
    lat0, lon0 = home.latitude_deg, home.longitude_deg
    m_lat = 1 / 111_195.0  # degrees per metre North
    m_lon = m_lat / math.cos(math.radians(lat0))

    def at(north: float, east: float) -> tuple[float, float]:
        return lat0 + north * m_lat, lon0 + east * m_lon

    param.set_param_int("GF_ACTION", 3)  # Return
    param.set_param_float("COM_FAIL_ACT_T", 1.0)
    square = [Point(*at(n, e)) for n, e in ((-30, -30), (30, -30), (30, 30), (-30, 30))]
    far_circle = Circle(Point(*at(0, 100)), 10.0, FenceType.EXCLUSION)
    geofence.upload_geofence(GeofenceData([Polygon(square, FenceType.INCLUSION)], [far_circle]))
    fence = raw.download_geofence()
    assert [(i.command, i.mission_type) for i in fence] == [(5001, 1)] * 4 + [(5004, 1)]
    rally = [RawItem(i, 6, 5100, 0, 1, 0, 0, 0, 0, round(la * 1e7), round(lo * 1e7), 10, 2)
             for i, (la, lo) in enumerate([at(25, 0), at(-40, 0)])]  # fmt: skip
    raw.upload_rally_points(rally)
    assert len(raw.download_rallypoints()) == 2
    assert raw.download_mission() == []  # the mission store is apart

    # a mission with a waypoint beyond the fence: PX4 accepts the upload, refuses to fly it.
    # Disarmed, PX4 v1.15 takes the switch to Mission (every mode change while disarmed), then
    # refuses to arm in it: the mission is not valid
    mission.upload_mission(MissionPlan([MissionItem(*at(0, 0), 10), MissionItem(*at(50, 0), 10)]))
    mission.start_mission()
    with pytest.raises(ActionError):
        action.arm()
    action.hold()

    action.set_takeoff_altitude(10.0)
    action.arm()
    action.takeoff()
    eventually(lambda: telemetry.position().relative_altitude_m > 9, 30, "the takeoff")
    eventually(lambda: telemetry.flight_mode() == FlightMode.HOLD, 30, "hold after takeoff")

    sticks = [0.0, 0.0, 0.5, 0.0]
    stop = threading.Event()

    def stream() -> None:
        while not stop.is_set():
            manual.set_manual_control_input(*sticks)
            time.sleep(0.02)

    streamer = threading.Thread(target=stream, daemon=True)
    streamer.start()
    try:
        time.sleep(0.3)
        manual.start_position_control()
        eventually(lambda: telemetry.flight_mode() == FlightMode.POSCTL, 10, "position mode")
        sticks[0] = 0.6  # North, across the fence at 30 m
        eventually(lambda: telemetry.flight_mode() == FlightMode.HOLD, 30, "the breach hold")
        # the stick stays where it is: moved once the Return has begun, it would take over
        # (COM_RC_OVERRIDE), in PX4 too
        eventually(lambda: telemetry.flight_mode() == FlightMode.RETURN_TO_LAUNCH, 10, "return")
        eventually(lambda: not telemetry.armed(), 90, "landing")
    finally:
        stop.set()
        streamer.join(2)
    pos = telemetry.position()
    north = (pos.latitude_deg - lat0) / m_lat
    east = (pos.longitude_deg - lon0) / m_lon
    assert math.hypot(north - 25, east) < 3.0  # the rally point 25 m North, closer than home
