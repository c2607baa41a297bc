"""Offboard over real UDP: `uavtest sitl` driven by pymavlink (lockstep) and by MAVSDK's Offboard
plugin (free running), and the example `examples/offboard-square.yaml` flown by `uavtest run`.

What PX4 v1.15 does and these assert: a setpoint stream before the switch (else the switch is
TEMPORARILY_REJECTED with "Switching to Offboard is currently not available"), the vehicle flies
to the setpoint, and when the stream stops for COM_OF_LOSS_T the COM_OBL_RC_ACT failsafe acts.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import yaml
from pymavlink.dialects.v20 import common as mavlink2

from harness.engine_cli import uavtest_run
from harness.mavlink_client import connect
from harness.net import free_udp_port
from harness.sitl import eventually, free_running_argv, running_sitl
from uavtest.engine.replica import sitl_command
from uavtest.sitl.params import encode_param_value

pytestmark = pytest.mark.integration

REPO = Path(__file__).resolve().parents[2]
DEADLINE_S = 60.0
POS_ONLY = 0x0DF8  # x y z and yaw (MAVSDK set_position_ned's mask)


class Client:
    """A lockstep pymavlink client that can stream SET_POSITION_TARGET_LOCAL_NED with each grant.

    Not harness.mavlink_client.LockstepClient: it sends the setpoint with each grant, keeps the last
    LOCAL_POSITION_NED and starts the vehicle-time limit at the first LOCKSTEP it sees."""

    def __init__(self, port: int) -> None:
        self.conn = connect(port)
        self.t_ms = -1
        self.seen: list = []
        self.setpoint: tuple[float, float, float] | None = None
        self.last = None  # the last LOCAL_POSITION_NED

    def texts(self) -> list[str]:
        return [m.text for m in self.seen if m.get_type() == "STATUSTEXT"]

    def wait(self, cond: Callable, vehicle_s: float = 120.0, *, grant: bool = True):
        wall = time.monotonic() + DEADLINE_S
        limit_ms = None
        while time.monotonic() < wall:
            msg = self.conn.recv_match(blocking=True, timeout=1.0)
            if msg is None:
                continue
            self.seen.append(msg)
            kind = msg.get_type()
            if kind == "LOCAL_POSITION_NED":
                self.last = msg
            if cond(msg):
                return msg
            if kind == "NAMED_VALUE_INT" and msg.name == "LOCKSTEP":
                self.t_ms = max(self.t_ms, msg.value)
                if limit_ms is None:
                    limit_ms = self.t_ms + vehicle_s * 1000
                if grant:
                    if msg.value > limit_ms:
                        break
                    if self.setpoint is not None:
                        x, y, z = self.setpoint
                        self.conn.mav.set_position_target_local_ned_send(
                            msg.value, 1, 1, 1, POS_ONLY, x, y, z, 0, 0, 0, 0, 0, 0, 0, 0
                        )
                    self.conn.mav.named_value_int_send(msg.value, b"LOCKSTEP", msg.value + 50)
        raise AssertionError("condition not met in time")

    def fly(self, seconds: float) -> None:
        end = max(self.t_ms, 0) + seconds * 1000
        self.wait(lambda m: self.t_ms >= end, vehicle_s=seconds + 5)

    def command(self, cmd: int, *params: float) -> int:
        p = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, cmd, 0, *p)
        return self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd, grant=False).result

    def mode(self) -> tuple[int, int]:
        hb = self.wait(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcSystem() == 1)
        return (hb.custom_mode >> 16) & 0xFF, (hb.custom_mode >> 24) & 0xFF


@pytest.fixture
def client(tmp_path: Path) -> Iterator[Client]:
    test = tmp_path / "offboard.yaml"
    test.write_text(
        yaml.safe_dump(
            {
                "apiVersion": "uavtest.io/v1alpha1",
                "kind": "UavTest",
                "metadata": {"name": "of"},
                "spec": {
                    "commands": [{"at": 1, "action": "arm"}]
                },  # the simulator only reads world and params
            }
        )
    )
    port = free_udp_port()
    c = Client(port)
    argv = sitl_command(
        sys.executable, test, 3, api_port=port, gcs_port=free_udp_port(), log_dir=tmp_path / "log"
    )
    try:
        with running_sitl(argv, env={**os.environ, "PYTHONUNBUFFERED": "1"}):
            c.wait(lambda m: m.get_type() == "SYS_STATUS" and m.onboard_control_sensors_health & 0x10000000)
            yield c
    finally:
        c.conn.close()


def test_offboard_without_setpoints_is_refused(client: Client):
    assert client.command(400, 1) == mavlink2.MAV_RESULT_ACCEPTED
    assert client.command(176, 1, 6, 0) == mavlink2.MAV_RESULT_TEMPORARILY_REJECTED
    client.fly(0.5)
    assert "Switching to Offboard is currently not available" in client.texts()
    assert client.mode() == (4, 3)  # still AUTO.LOITER


def test_stream_switch_fly_then_lose_the_stream_lands(client: Client):
    mav = client.conn.mav
    mav.param_set_send(1, 1, b"COM_OBL_RC_ACT", encode_param_value(4, 6), mavlink2.MAV_PARAM_TYPE_INT32)
    client.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "COM_OBL_RC_ACT", grant=False)
    client.setpoint = (0.0, 0.0, -5.0)
    client.fly(0.5)
    assert client.command(176, 1, 6, 0) == mavlink2.MAV_RESULT_ACCEPTED  # disarmed: accepted
    assert client.command(400, 1) == mavlink2.MAV_RESULT_ACCEPTED  # arms in offboard, takes off
    client.fly(10)
    assert client.mode() == (6, 0)
    assert client.last.z == pytest.approx(-5.0, abs=0.4)
    client.setpoint = (8.0, 4.0, -6.0)
    client.fly(10)
    p = client.last
    assert (p.x, p.y, p.z) == (
        pytest.approx(8.0, abs=0.4),
        pytest.approx(4.0, abs=0.4),
        pytest.approx(-6.0, abs=0.4),
    )
    # the stream stops: within COM_OF_LOSS_T (1 s) still offboard, then the failsafe lands
    client.setpoint = None
    client.fly(0.5)
    assert "Failsafe activated" not in client.texts()  # (mode() would fly on to the next heartbeat)
    client.fly(1.0)
    assert "Failsafe activated" in client.texts()
    assert client.mode() == (4, 6)  # AUTO.LAND
    client.wait(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcSystem() == 1 and not m.base_mode & 128)
    # landed where it was; the estimated altitude ends up to ~2 m off the ground, as PX4 SIH's does
    # (EKF2's drift in flight and its shift after touchdown: z -1.65..+2.12 m in 40 PX4 flights)
    assert math.hypot(client.last.x - 8.0, client.last.y - 4.0) < 1.0 and abs(client.last.z) < 2.2


@contextlib.contextmanager
def _mavsdk_armed(tmp_path: Path) -> Iterator[tuple]:
    """A free-running built-in vehicle at speed factor 5 and MAVSDK connected to it over UDP,
    armable: (telemetry, action, offboard)."""
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.action import Action
    from mavsdk.plugins.offboard import Offboard
    from mavsdk.plugins.telemetry import Telemetry

    port = free_udp_port()
    with running_sitl(free_running_argv(port, tmp_path / "log", 5)):
        sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        sdk.add_any_connection(f"udpin://127.0.0.1:{port}")
        system = sdk.first_autopilot(15.0)
        assert system is not None
        telemetry, action, offboard = Telemetry(system), Action(system), Offboard(system)
        eventually(lambda: telemetry.health().is_armable, 20, "armable")
        yield telemetry, action, offboard


def test_mavsdk_offboard_square(tmp_path: Path):
    mavsdk = pytest.importorskip("mavsdk")
    from mavsdk.plugins.offboard import OffboardError, PositionNedYaw

    assert mavsdk
    with _mavsdk_armed(tmp_path) as (telemetry, action, offboard):
        action.arm()
        # MAVSDK refuses start() before a setpoint; the vehicle refuses offboard without a stream
        with pytest.raises(OffboardError):
            offboard.start()
        offboard.set_position_ned(PositionNedYaw(0.0, 0.0, -4.0, 0.0))
        offboard.start()
        eventually(lambda: telemetry.position_velocity_ned().position.down_m < -3.6, 30, "the climb")
        for north, east in ((6.0, 0.0), (6.0, 6.0), (0.0, 6.0), (0.0, 0.0)):
            offboard.set_position_ned(PositionNedYaw(north, east, -4.0, 0.0))

            def there(n: float = north, e: float = east) -> bool:
                p = telemetry.position_velocity_ned().position
                return math.hypot(p.north_m - n, p.east_m - e) < 0.5

            eventually(there, 30, f"the corner {north}, {east}")
        offboard.stop()  # PX4: leaves offboard for Hold
        action.land()
        eventually(lambda: not telemetry.armed(), 40, "landed and disarmed")


def test_mavsdk_offboard_yaw_and_yawspeed_turn_as_px4_sih_does(tmp_path: Path):
    """MAVSDK's offboard yaw (degrees) and body yawspeed (degrees/s) over real UDP. PX4 v1.15 has
    no flight task in offboard: a yaw goes to the attitude controller as it is (MC_YAW_P, up to
    MC_YAWRATE_MAX), a yawspeed alone is fed forward to the rate loop. PX4 SIH, flown here with the
    same setpoints through uavtest (README, "PX4's yaw chain"), turned a 120 degree step within 5
    degrees in about 2 s, and 45.8 degrees in the first 2 s of 30 degrees/s (100.8 after 4 s); the
    unit tests hold the built-in vehicle to those numbers, this one to MAVSDK's units and signs."""
    mavsdk = pytest.importorskip("mavsdk")
    from mavsdk.plugins.offboard import PositionNedYaw, VelocityBodyYawspeed

    assert mavsdk
    with _mavsdk_armed(tmp_path) as (telemetry, action, offboard):
        action.arm()
        offboard.set_position_ned(PositionNedYaw(0.0, 0.0, -4.0, 0.0))
        offboard.start()
        eventually(lambda: telemetry.position_velocity_ned().position.down_m < -3.6, 30, "the climb")

        def heading() -> float:
            return telemetry.attitude_euler().yaw_deg

        def off(target: float) -> float:
            return abs((heading() - target + 180.0) % 360.0 - 180.0)

        eventually(lambda: off(0.0) < 3.0, 10, "north")
        offboard.set_position_ned(PositionNedYaw(0.0, 0.0, -4.0, 120.0))
        eventually(lambda: off(120.0) < 5.0, 4, "a 120 degree step within 5 degrees")
        eventually(lambda: off(120.0) < 2.0, 10, "held at 120")
        # 30 degrees/s clockwise (MAVSDK's yawspeed_deg_s, positive to the right): it turns that
        # way, past 200 degrees, and a yawspeed of 0 stops it
        offboard.set_velocity_body(VelocityBodyYawspeed(0.0, 0.0, 0.0, 30.0))
        eventually(lambda: off(210.0) < 10.0, 20, "turning clockwise through 210 degrees")
        offboard.set_velocity_body(VelocityBodyYawspeed(0.0, 0.0, 0.0, 0.0))
        eventually(lambda: abs(telemetry.attitude_angular_velocity_body().yaw_rad_s) < 0.02, 10, "stopped")
        offboard.stop()
        action.land()
        eventually(lambda: not telemetry.armed(), 40, "landed and disarmed")


def test_example_offboard_square_passes_inside_its_fence(tmp_path: Path):
    """examples/offboard-square.yaml: every replica passes, the path inside the fence box."""
    out = uavtest_run(REPO / "examples" / "offboard-square.yaml", tmp_path / "out", "--replicas", "2")
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None
    results = out.summary["results"]
    assert [r["verdict"] for r in results] == ["pass", "pass"]
    for r in results:
        assert r["metrics"]["geofence_violation"] == 0.0
        assert r["metrics"]["max_altitude"] == pytest.approx(5.0, abs=0.4)
    (run,) = (tmp_path / "out" / "local" / "offboard-square").iterdir()
    for i in range(2):
        rows = (run / f"replica-{i}" / "trajectory.csv").read_text().splitlines()[1:]
        xs = [float(r.split(",")[1]) for r in rows]
        ys = [float(r.split(",")[2]) for r in rows]
        assert max(xs) > 9.5 and max(ys) > 9.5  # it flew the square, not just hovered
        assert min(xs) > -3 and max(xs) < 13 and min(ys) > -3 and max(ys) < 13
        assert json.loads((run / f"replica-{i}" / "result.json").read_text())["verdict"] == "pass"
