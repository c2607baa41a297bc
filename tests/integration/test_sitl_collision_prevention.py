"""Collision Prevention over real UDP: `uavtest sitl` as a process with a wall in its world, a
pymavlink client flying position mode full forward at it (MANUAL_CONTROL, lockstep). With
PX4 v1.15's CP (CP_DIST, MPC_POS_MODE 0, the simulated range sensor) the vehicle stops about
CP_DIST short and streams OBSTACLE_DISTANCE / DISTANCE_SENSOR; without it, it collides."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import yaml
from pyulog import ULog

from harness.mavlink_client import connect
from harness.net import free_udp_port
from harness.sitl import stop_process
from uavtest.engine.replica import sitl_command

pytestmark = pytest.mark.integration

LOITER, POSCTL = (4, 3), (3, 0)
DEADLINE_S = 60.0
WALL_FACE_X = 24.0  # the wall's near face, metres North of home


class Pilot:
    """A pymavlink client of one lockstep `uavtest sitl` process, streaming sticks at 50 Hz."""

    def __init__(self, tmp_path: Path, vehicle: dict[str, object]) -> None:
        spec = {
            "apiVersion": "uavtest.io/v1alpha1",
            "kind": "UavTest",
            "metadata": {"name": "cp"},
            "spec": {
                "vehicle": vehicle,
                "world": {
                    "obstacles": [
                        {"size": {"l": 2, "w": 20, "h": 30}, "position": {"x": WALL_FACE_X + 1, "y": 0}}
                    ]
                },
                "mission": {"takeoffAltitude": 10, "waypoints": []},
            },
        }
        tmp_path.mkdir(parents=True, exist_ok=True)
        test = tmp_path / "cp.yaml"
        test.write_text(yaml.safe_dump(spec))
        port = free_udp_port()
        self.log_dir = tmp_path / "log"
        self.conn = connect(port)
        self.proc = subprocess.Popen(
            sitl_command(
                sys.executable, test, 7, api_port=port, gcs_port=free_udp_port(), log_dir=self.log_dir
            ),
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
        )
        self.sticks = (0, 0, 500, 0)
        self.mode = (0, 0)
        self.armed = False
        self.x = 0.0
        self.max_x = -math.inf
        self.texts: list[str] = []
        self.seen: dict[str, list] = {}

    def close(self) -> None:
        stop_process(self.proc, graceful=False)
        self.conn.close()

    def command(self, cmd: int, *params: float) -> int:
        p = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, cmd, 0, *p)
        ack = self.fly(lambda m: m is not None and m.get_type() == "COMMAND_ACK" and m.command == cmd, 5)
        return ack.result

    def fly(self, until: Callable, vehicle_s: float = 120.0):
        """Grant vehicle time in 50 ms steps, sending the sticks each step, until ``until(msg)``."""
        wall = time.monotonic() + DEADLINE_S
        start = None
        while time.monotonic() < wall:
            msg = self.conn.recv_match(blocking=True, timeout=1.0)
            if msg is None:
                continue
            kind = msg.get_type()
            self.seen.setdefault(kind, []).append(msg)
            if kind == "HEARTBEAT" and msg.get_srcSystem() == 1:
                self.mode = ((msg.custom_mode >> 16) & 0xFF, (msg.custom_mode >> 24) & 0xFF)
                self.armed = bool(msg.base_mode & 128)
            elif kind == "LOCAL_POSITION_NED":
                self.x = msg.x
                self.max_x = max(self.max_x, msg.x)
            elif kind == "STATUSTEXT":
                self.texts.append(msg.text)
            if until(msg):
                return msg
            if kind == "NAMED_VALUE_INT" and msg.name == "LOCKSTEP":
                start = msg.value if start is None else start
                assert msg.value - start < vehicle_s * 1000, "condition not met in vehicle time"
                self.conn.mav.manual_control_send(1, *self.sticks, 0)
                self.conn.mav.named_value_int_send(msg.value, b"LOCKSTEP", msg.value + 50)
        raise AssertionError("condition not met in time")

    def take_off_and_push_north(self) -> None:
        self.fly(lambda m: any("Ready" in t for t in self.texts), 10)
        assert self.command(400, 1) == 0
        self.command(22, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 10)
        self.fly(
            lambda m: (
                self.mode == LOITER and self.armed and m.get_type() == "LOCAL_POSITION_NED" and m.z < -9
            ),
            40,
        )
        assert self.command(176, 1, 3, 0) == 0  # position mode
        self.fly(lambda m: self.mode == POSCTL, 5)
        self.sticks = (1000, 0, 500, 0)  # full forward: MPC_VEL_MANUAL (10 m/s) North


@pytest.fixture
def pilot(tmp_path: Path) -> Iterator[Callable[..., Pilot]]:
    made: list[Pilot] = []

    def make(**vehicle: object) -> Pilot:
        p = Pilot(tmp_path / f"p{len(made)}", vehicle)
        made.append(p)
        return p

    yield make
    for p in made:
        p.close()


def test_position_mode_at_a_wall_stops_cp_dist_short(pilot) -> None:
    p = pilot(avoidance="collision-prevention", params={"CP_DIST": 2.0, "MPC_POS_MODE": 0})
    p.take_off_and_push_north()
    start = len(p.seen.get("NAMED_VALUE_INT", []))
    p.fly(lambda m: len(p.seen.get("NAMED_VALUE_INT", [])) - start > 25 * 20, 30)  # 25 s pushing
    assert not any("crash" in t for t in p.texts), p.texts
    assert p.armed and p.mode == POSCTL
    closest = WALL_FACE_X - p.max_x
    # CP_DIST 2 less the braking overshoot: about 1 m, 1.1 m since the velocity loop's D term
    # (MPC_XY_VEL_D_ACC on the measured deceleration, as PX4's PositionControl) softens braking
    assert 0.8 < closest < 2.0, closest
    assert WALL_FACE_X - p.x == pytest.approx(2.0, abs=0.5)  # held there, stick still pushed
    od = p.seen["OBSTACLE_DISTANCE"][-1]  # CP's map (obstacle_distance_fused), 10-degree bins
    assert od.frame == 12 and od.increment_f == 10.0 and len(od.distances) == 72
    assert od.distances[0] == pytest.approx(200, abs=50) and od.distances[40] == 65535
    ds = p.seen["DISTANCE_SENSOR"][-1]
    assert ds.orientation == 0 and ds.max_distance == 1200 and ds.current_distance < 300
    p.proc.terminate()
    p.proc.wait(10)
    (log,) = p.log_dir.glob("*.ulg")
    ulog = ULog(str(log))
    assert {"obstacle_distance", "obstacle_distance_fused", "collision_constraints"} <= {
        d.name for d in ulog.data_list
    }


def test_without_collision_prevention_it_collides(pilot) -> None:
    p = pilot(avoidance="collision-prevention")  # the sensor, but CP_DIST -1 (PX4's default): off
    p.take_off_and_push_north()
    p.fly(lambda m: any("crash" in t for t in p.texts), 30)
    assert "OBSTACLE_DISTANCE" not in p.seen  # CP not running: PX4 publishes no fused map
    assert "DISTANCE_SENSOR" in p.seen
