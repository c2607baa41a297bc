"""Navigator commands and ground-station regressions against a real `uavtest sitl` process over UDP
(pymavlink in lockstep; MAVSDK for goto_location / do_orbit as a PX4 user sends them)."""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from harness.mavlink_client import connect
from harness.net import free_udp_port
from harness.sitl import eventually, free_running_argv, running_sitl

pytestmark = pytest.mark.integration

DEADLINE_S = 90.0
LAT, LON, ALT = 47.397742, 8.545594, 488.0
INT32_MAX = 2**31 - 1
AUTO, POSCTL = 4, 3
LOITER, SUB_MISSION, RTL = 3, 4, 5


def mode(hb) -> tuple[int, int]:
    return (hb.custom_mode >> 16) & 0xFF, (hb.custom_mode >> 24) & 0xFF


class Client:
    """A lockstep pymavlink client: grants 50 ms of vehicle time whenever the sim waits.

    Not harness.mavlink_client.LockstepClient: it keeps the last message of each type and the
    STATUSTEXTs instead of every message, acks wait granting time, and the vehicle-time limit
    starts at the first LOCKSTEP seen; DEADLINE_S here is 90 s."""

    def __init__(self, port: int) -> None:
        self.conn = connect(port)
        self.last: dict[str, object] = {}
        self.texts: list[str] = []

    def wait(self, cond: Callable, vehicle_s: float = 300.0, *, grant: bool = True):
        wall = time.monotonic() + DEADLINE_S
        limit_ms = None
        while time.monotonic() < wall:
            msg = self.conn.recv_match(blocking=True, timeout=1.0)
            if msg is None:
                continue
            self.last[msg.get_type()] = msg
            if msg.get_type() == "STATUSTEXT":
                self.texts.append(msg.text)
            if cond(msg):
                return msg
            if msg.get_type() == "NAMED_VALUE_INT" and msg.name == "LOCKSTEP":
                if limit_ms is None:
                    limit_ms = msg.value + vehicle_s * 1000
                if grant:
                    if msg.value > limit_ms:
                        break
                    self.conn.mav.named_value_int_send(msg.value, b"LOCKSTEP", msg.value + 50)
        raise AssertionError("condition not met in time")

    def fly(self, vehicle_s: float) -> None:
        start = None

        def done(m) -> bool:
            nonlocal start
            if m.get_type() == "NAMED_VALUE_INT" and m.name == "LOCKSTEP":
                start = m.value if start is None else start
                return m.value - start >= vehicle_s * 1000
            return False

        self.wait(done, vehicle_s + 5)

    def ack(self, cmd: int) -> int:
        return self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd).result

    def command(self, cmd: int, *params: float) -> int:
        p = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, cmd, 0, *p)
        return self.ack(cmd)

    def command_int(self, cmd: int, p: tuple[float, float, float, float], x: int, y: int, z: float) -> int:
        self.conn.mav.command_int_send(1, 1, 0, cmd, 0, 0, *p, x, y, z)
        return self.ack(cmd)

    def upload(self, items: list[tuple[int, float, float, float]]) -> int:
        """(command, lat, lon, rel alt) items, frame GLOBAL_RELATIVE_ALT_INT; returns MISSION_ACK.type."""
        mav = self.conn.mav
        mav.mission_count_send(1, 1, len(items), 0)
        while True:
            msg = self.wait(lambda m: m.get_type() in ("MISSION_REQUEST_INT", "MISSION_ACK"))
            if msg.get_type() == "MISSION_ACK":
                return msg.type
            cmd, lat, lon, alt = items[msg.seq]
            frame = 2 if cmd in (20, 189) else 6
            mav.mission_item_int_send(
                1, 1, msg.seq, frame, cmd, 0, 1, 0, 0, 0, math.nan, round(lat * 1e7), round(lon * 1e7), alt, 0
            )

    def position(self):
        return self.wait(lambda m: m.get_type() == "LOCAL_POSITION_NED")

    def heartbeat(self):
        return self.wait(lambda m: m.get_type() == "HEARTBEAT")

    def hover(self, alt: float = 10.0) -> None:
        self.wait(lambda m: m.get_type() == "STATUSTEXT" and "Ready" in m.text)
        assert self.command(400, 1) == 0
        assert self.command(22, 0, 0, 0, math.nan, math.nan, math.nan, ALT + alt) == 0
        self.wait(lambda m: m.get_type() == "LOCAL_POSITION_NED" and -m.z > alt - 0.3, 60)
        self.wait(lambda m: m.get_type() == "HEARTBEAT" and mode(m) == (AUTO, LOITER), 30)
        self.fly(3)


@pytest.fixture
def client(tmp_path: Path) -> Iterator[Client]:
    port = free_udp_port()
    c = Client(port)
    argv = [sys.executable, "-m", "uavtest.cli", "sitl", "--seed", "3", "--host", "127.0.0.1"]
    argv += ["--api-port", str(port), "--gcs-port", str(free_udp_port()), "--api-local-port", "0"]
    argv += ["--gcs-local-port", "0", "--log-dir", str(tmp_path / "log"), "--lockstep"]
    try:
        with running_sitl(argv, env={**os.environ, "PYTHONUNBUFFERED": "1"}, graceful=False) as proc:
            yield c
            assert proc.poll() is None, "the simulator died"
    finally:
        c.conn.close()


MISSION = [
    (22, LAT, LON, 8.0),
    (16, LAT + 0.0003, LON, 8.0),
    (16, LAT + 0.0003, LON + 0.0003, 8.0),
]


def test_mission_upload_set_current_and_clear_while_holding_keep_holding(client: Client):
    client.hover(10)
    p0 = client.position()
    assert client.upload(MISSION) == 0
    client.conn.mav.mission_set_current_send(1, 1, 1)
    client.fly(2)
    client.conn.mav.mission_clear_all_send(1, 1, 0)
    client.wait(lambda m: m.get_type() == "MISSION_ACK")
    client.fly(10)
    p = client.position()
    hb = client.heartbeat()
    assert mode(hb) == (AUTO, LOITER) and hb.base_mode & 128  # still armed, in Hold
    assert math.hypot(p.x - p0.x, p.y - p0.y) < 1.0 and abs(p.z - p0.z) < 0.5


def test_mission_upload_during_return_keeps_returning(client: Client):
    client.hover(10)
    r = client.command_int(192, (-1, 1, 0, math.nan), round((LAT + 0.0003) * 1e7), round(LON * 1e7), ALT + 10)
    assert r == 0
    client.wait(lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.x > 30, 60)
    assert client.command(20) == 0
    client.fly(2)
    assert client.upload(MISSION) == 0
    armed_modes: set[tuple[int, int]] = set()

    def disarmed(m) -> bool:
        if m.get_type() != "HEARTBEAT":
            return False
        if m.base_mode & 128:
            armed_modes.add(mode(m))
        return not m.base_mode & 128

    hb = client.wait(disarmed, 120)
    assert armed_modes == {(AUTO, RTL)}  # returned all the way: the upload changed nothing
    assert mode(hb) == (AUTO, LOITER)  # disarmed, back in the last mode that may arm (onDisarm)
    p = client.position()
    # on the ground at home; the estimated altitude ends up to ~2 m off it, as PX4 SIH's does
    # (EKF2's drift in flight and its shift after touchdown: z -1.65..+2.12 m in 40 PX4 flights)
    assert math.hypot(p.x, p.y) < 2.0 and abs(p.z) < 2.2


def test_mission_rtl_item_switches_to_return_which_lands_and_disarms(client: Client):
    client.wait(lambda m: m.get_type() == "STATUSTEXT" and "Ready" in m.text)
    assert client.upload([*MISSION, (20, 0.0, 0.0, 0.0)]) == 0
    assert client.command(300) == 0  # MISSION_START arms and starts
    client.wait(lambda m: m.get_type() == "HEARTBEAT" and mode(m) == (AUTO, RTL), 200)
    hb = client.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128, 200)
    assert mode(hb) == (AUTO, SUB_MISSION)  # disarmed, PX4's onDisarm: the user's mission again
    p = client.position()
    assert math.hypot(p.x, p.y) < 2.0
    assert any("RTL" in t for t in client.texts)


def test_reposition_goes_there_and_without_the_flag_is_unsupported(client: Client):
    client.hover(10)
    assert client.command(192, -1, 0, 0, math.nan, LAT + 0.001, LON, math.nan) == 3  # UNSUPPORTED
    client.fly(1)
    assert any("CHANGE_MODE" in t for t in client.texts)
    r = client.command_int(
        192, (3.0, 1, 0, math.nan), round((LAT + 0.0002) * 1e7), round((LON + 0.0002) * 1e7), ALT + 15
    )
    assert r == 0
    client.fly(30)
    p = client.position()
    assert abs(p.x - 22.2) < 1.5 and abs(p.y - 15.1) < 1.5 and abs(-p.z - 15) < 0.5
    assert mode(client.heartbeat()) == (AUTO, LOITER)


def test_orbit_streams_status_and_refuses_a_too_large_radius(client: Client):
    client.hover(10)
    r = client.command_int(
        34, (6.0, 2.0, math.nan, 0), round((LAT + 0.0001) * 1e7), round(LON * 1e7), ALT + 10
    )
    assert r == 0
    assert mode(client.heartbeat()) == (POSCTL, 1)  # PX4 reports ORBIT as POSCTL / ORBIT
    st = client.wait(lambda m: m.get_type() == "ORBIT_EXECUTION_STATUS")
    assert st.radius == 6.0 and st.x == round((LAT + 0.0001) * 1e7) and abs(st.z - ALT - 10) < 1e-3
    client.fly(30)
    p = client.position()
    assert abs(math.hypot(p.x - 11.1, p.y) - 6.0) < 1.5
    assert client.command(34, 5000, 1, math.nan, 0, math.nan, math.nan, math.nan) == 0
    client.fly(1)
    assert "Orbit radius limit exceeded" in client.texts
    assert mode(client.heartbeat()) == (AUTO, LOITER)


def test_land_start_cancelled_without_one_then_flown_and_condition_yaw_unsupported(client: Client):
    client.wait(lambda m: m.get_type() == "STATUSTEXT" and "Ready" in m.text)
    assert client.upload(MISSION) == 0
    assert client.command(189) == 6  # MAV_RESULT_CANCELLED
    client.fly(1)
    assert "planned mission landing not available" in client.texts
    assert client.command(115, 90, 20, 1, 0) == 3  # CONDITION_YAW: UNSUPPORTED, as PX4 v1.15
    client.fly(1)
    assert any("CONDITION_YAW" in t for t in client.texts)
    land = [(189, 0.0, 0.0, 0.0), (21, LAT + 0.0001, LON, 0.0)]
    assert client.upload(MISSION + land) == 0
    assert client.command(300) == 0
    client.wait(lambda m: m.get_type() == "MISSION_ITEM_REACHED" and m.seq == 1, 120)
    assert client.command(189) == 0
    hb = client.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128, 200)
    assert mode(hb) == (AUTO, SUB_MISSION)
    p = client.position()
    assert abs(p.x - 11.1) < 2.0 and abs(p.y) < 2.0  # the landing item, not item 2 (east)


def test_change_speed_in_hold_limits_a_reposition(client: Client):
    client.hover(10)
    assert client.command(178, 1, 1.5, -1) == 0
    client.command(192, -1, 1, 0, math.nan, LAT + 0.0004, LON, math.nan)
    top = 0.0
    for _ in range(40):
        p = client.position()
        top = max(top, math.hypot(p.vx, p.vy))
    assert 1.0 < top < 2.0


# ---------------------------------------------------------------- MAVSDK


@pytest.fixture
def sitl_port(tmp_path: Path) -> Iterator[int]:
    port = free_udp_port()
    with running_sitl(free_running_argv(port, tmp_path / "log", 10)):
        yield port


def test_mavsdk_goto_location_and_do_orbit(sitl_port: int):
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.action import Action, OrbitYawBehavior
    from mavsdk.plugins.telemetry import FlightMode, Telemetry

    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    sdk.add_any_connection(f"udpin://127.0.0.1:{sitl_port}")
    system = sdk.first_autopilot(15.0)
    assert system is not None
    telemetry, action = Telemetry(system), Action(system)
    eventually(lambda: telemetry.health().is_armable, 20, "armable")
    action.set_takeoff_altitude(8.0)
    action.arm()
    action.takeoff()
    eventually(lambda: telemetry.position().relative_altitude_m > 7.5, 30, "the takeoff")
    action.goto_location(LAT + 0.0002, LON, ALT + 12, 90.0)
    eventually(lambda: telemetry.flight_mode() == FlightMode.HOLD, 5, "hold")
    eventually(
        lambda: (
            abs(telemetry.position().latitude_deg - LAT - 0.0002) < 1e-5
            and abs(telemetry.position().relative_altitude_m - 12) < 0.5
        ),
        40,
        "the goto point",
    )
    eventually(lambda: abs(telemetry.heading().heading_deg - 90.0) < 5, 10, "yaw 90 deg")
    action.do_orbit(5.0, 1.5, OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER, LAT, LON, ALT + 12)
    # MAVSDK reports PX4 ORBIT (POSCTL main mode, ORBIT sub mode) as POSCTL
    eventually(lambda: telemetry.flight_mode() == FlightMode.POSCTL, 5, "orbit mode")
    time.sleep(6.0)

    def on_circle() -> bool:
        p = telemetry.position_velocity_ned().position
        return abs(math.hypot(p.north_m, p.east_m) - 5.0) < 1.5

    eventually(on_circle, 30, "the orbit circle")


# ---------------------------------------------------------------- uavtest run


def test_uavtest_run_flies_speed_goto_orbit_land_start_and_return(repo_root: Path, tmp_path: Path):
    from pyulog import ULog

    from harness.engine_cli import uavtest_run

    out = uavtest_run(repo_root / "examples/navigator-commands.yaml", tmp_path)
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["passed"] == 2
    log = next(tmp_path.rglob("replica-0/flight.ulg"))
    ulog = ULog(str(log))
    status = ulog.get_dataset("vehicle_status").data
    states = [int(s) for i, s in enumerate(status["nav_state"]) if i == 0 or s != status["nav_state"][i - 1]]
    # mission → hold (goto) → orbit → return; disarmed, Hold (PX4's onDisarm: the last mode that
    # may arm, the goto's)
    assert states[-5:] == [3, 4, 21, 5, 4]
    acks = ulog.get_dataset("vehicle_command_ack").data
    results = dict(zip((int(c) for c in acks["command"]), (int(r) for r in acks["result"]), strict=True))
    assert results[178] == 0 and results[192] == 0 and results[34] == 0
    assert results[189] == 6  # DO_LAND_START without a landing sequence: CANCELLED, as PX4
    texts = [m.message for m in ulog.logged_messages]
    assert "planned mission landing not available" in texts and "Disarmed by landing" in texts


def test_uavtest_run_yaw_command_is_an_error_naming_it(repo_root: Path, tmp_path: Path):
    from harness.engine_cli import uavtest_run

    test = tmp_path / "yaw.yaml"
    test.write_text(
        (repo_root / "examples/hover.yaml")
        .read_text()
        .replace("replicas: 3", "replicas: 1")
        .replace(
            "    - {at: 1, action: mode, mode: mission}   # arms and starts the mission, as Aerialist does",
            "    - {at: 1, action: mode, mode: mission}\n    - {at: 12, action: yaw, yaw: {heading: 90}}",
        )
    )
    out = uavtest_run(test, tmp_path / "out")
    assert out.summary is not None, out.stderr[-3000:]
    (r,) = out.summary["results"]
    assert r["verdict"] == "error"
    assert "MAV_CMD_CONDITION_YAW is not supported by PX4 v1.15 either" in r["reason"]


def test_a_plan_with_a_landing_sequence_is_jumped_to_by_land_start(tmp_path: Path):
    """A .plan's DO_LAND_START (189) marks the landing sequence; MAV_CMD_DO_LAND_START from the
    test jumps there mid-mission, and the vehicle lands there instead of flying on (PX4 v1.15)."""
    import yaml

    from harness.engine_cli import uavtest_run

    def item(cmd: int, lat: float | None = None, lon: float | None = None, alt: float | None = None) -> dict:
        params = [0, 0, 0, None, lat, lon, alt]
        return {"type": "SimpleItem", "command": cmd, "frame": 3 if lat is not None else 2, "params": params}

    lat0, lon0 = 47.397742, 8.545594
    north = 100 / 111_320  # degrees of latitude per 100 m
    plan = {
        "fileType": "Plan",
        "version": 1,
        "mission": {
            "items": [
                item(22, lat0, lon0, 10),
                item(16, lat0 + north, lon0, 10),  # 100 m north: never reached
                item(189),
                item(16, lat0 + north / 10, lon0, 10),  # the approach, 10 m north
                item(21, lat0 + north / 10, lon0, 0),
            ],
            "plannedHomePosition": [lat0, lon0, 488],
        },
    }
    test = tmp_path / "land-start.yaml"
    test.write_text(
        yaml.safe_dump(
            {
                "apiVersion": "uavtest.io/v1alpha1",
                "kind": "UavTest",
                "metadata": {"name": "land-start"},
                "spec": {
                    "replicas": 1,
                    "timeout": 200,
                    "mission": {"plan": plan},
                    "commands": [
                        {"at": 1, "action": "mode", "mode": "mission"},
                        {"at": 20, "action": "land_start"},
                    ],
                    "assertions": {"geofence": {"minX": -10, "maxX": 60, "minY": -20, "maxY": 20}},
                },
            }
        )
    )
    out = uavtest_run(test, tmp_path / "out")
    assert out.code == 0, out.stderr[-3000:]
    (r,) = out.summary["results"]
    assert r["verdict"] == "pass"
    traj = next((tmp_path / "out").rglob("replica-0/trajectory.csv")).read_text().splitlines()[1:]
    xs = [float(row.split(",")[1]) for row in traj]
    assert 15 < max(xs) < 60, "it turned back before the far waypoint"
    assert abs(xs[-1] - 10) < 2, "and landed at the landing sequence's point"
