"""`uavtest sitl` as a real process, driven over real UDP by a pymavlink client in lockstep."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink2
from pyulog import ULog

from harness.mavlink_client import LockstepClient
from harness.net import free_udp_port
from harness.sitl import running_sitl
from uavtest.engine.replica import sitl_command
from uavtest.sitl.params import decode_param_value, encode_param_value
from uavtest.spec.loaders import load_test
from uavtest.spec.mission import mission_items

pytestmark = pytest.mark.integration


@pytest.fixture
def sitl(tmp_path: Path, shared_data: Path) -> Iterator[tuple[LockstepClient, subprocess.Popen, Path]]:
    port = free_udp_port()
    log_dir = tmp_path / "log"
    test = shared_data / "competition" / "snippets" / "case_studies" / "mission2.yaml"
    client = LockstepClient(port)
    argv = sitl_command(sys.executable, test, 5, api_port=port, gcs_port=free_udp_port(), log_dir=log_dir)
    try:
        with running_sitl(argv, env={**os.environ, "PYTHONUNBUFFERED": "1"}, graceful=False) as proc:
            yield client, proc, log_dir
    finally:
        client.conn.close()


def upload(client: LockstepClient, items: list[tuple[int, int, float, float, float, float]]) -> int:
    """Upload (command, frame, param1, lat, lon, alt) items; returns the MISSION_ACK type."""
    mav = client.conn.mav
    mav.mission_count_send(1, 1, len(items), 0)
    while True:
        msg = client.wait(lambda m: m.get_type() in ("MISSION_REQUEST_INT", "MISSION_ACK"), grant=False)
        if msg.get_type() == "MISSION_ACK":
            return msg.type
        cmd, frame, p1, lat, lon, alt = items[msg.seq]
        mav.mission_item_int_send(
            1, 1, msg.seq, frame, cmd, 0, 1, p1, 0, 0, math.nan, round(lat * 1e7), round(lon * 1e7), alt, 0
        )


def test_protocols_and_a_mission_flown_to_completion(sitl, shared_data: Path):
    client, proc, log_dir = sitl
    hb = client.wait(lambda m: m.get_type() == "HEARTBEAT", grant=False)
    assert hb.autopilot == mavlink2.MAV_AUTOPILOT_PX4 and hb.type == mavlink2.MAV_TYPE_QUADROTOR
    assert ((hb.custom_mode >> 16) & 0xFF, (hb.custom_mode >> 24) & 0xFF) == (4, 3)  # AUTO LOITER
    client.wait(lambda m: m.get_type() == "NAMED_VALUE_INT" and m.name == "LOCKSTEP", grant=False)

    # parameters: a float, an INT32 (byte-wise), an unknown one
    mav = client.conn.mav
    mav.param_set_send(1, 1, b"NAV_ACC_RAD", 0.5, mavlink2.MAV_PARAM_TYPE_REAL32)
    v = client.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "NAV_ACC_RAD", grant=False)
    assert v.param_value == 0.5
    mav.param_set_send(1, 1, b"NAV_RCL_ACT", encode_param_value(3, 6), mavlink2.MAV_PARAM_TYPE_INT32)
    v = client.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "NAV_RCL_ACT", grant=False)
    assert v.param_type == mavlink2.MAV_PARAM_TYPE_INT32 and decode_param_value(v.param_value, 6) == 3
    # a name PX4 v1.15 lacks: no PARAM_VALUE for the set nor the read, like PX4 v1.15
    # (mavlink_parameters.cpp: console error only); the next message's answer comes first
    mark = len(client.seen)
    mav.param_set_send(1, 1, b"UAVTEST_X", 7.5, mavlink2.MAV_PARAM_TYPE_REAL32)
    mav.param_request_read_send(1, 1, b"UAVTEST_X", -1)
    mav.param_request_read_send(1, 1, b"MIS_TAKEOFF_ALT", -1)
    client.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "MIS_TAKEOFF_ALT", grant=False)
    deadline = time.monotonic() + 0.5
    while time.monotonic() < deadline:
        client.recv(0.1)
    assert not [m for m in client.seen[mark:] if m.get_type() == "PARAM_VALUE" and m.param_id == "UAVTEST_X"]
    # a PX4 parameter the vehicle does not model: PX4 has it, so it is read, stored and echoed
    mav.param_request_read_send(1, 1, b"EKF2_GPS_DELAY", -1)
    v = client.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "EKF2_GPS_DELAY", grant=False)
    assert v.param_value == 110.0 and v.param_type == mavlink2.MAV_PARAM_TYPE_REAL32
    mav.param_set_send(1, 1, b"EKF2_GPS_DELAY", 90.0, mavlink2.MAV_PARAM_TYPE_REAL32)
    v = client.wait(
        lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "EKF2_GPS_DELAY" and m.param_value == 90.0,
        grant=False,
    )

    # an unsupported command is answered, never ignored
    assert client.command(31010) == mavlink2.MAV_RESULT_UNSUPPORTED

    # mission: upload, download, clear, upload again
    spec = load_test(shared_data / "competition" / "snippets" / "case_studies" / "mission2.yaml").spec
    cmds = {"takeoff": 22, "waypoint": 16, "land": 21}
    items = [(cmds[i.kind.value], 6, 0.0, i.lat, i.lon, i.alt or 0.0) for i in mission_items(spec)]
    assert upload(client, [(31000, 6, 0, 47.39, 8.54, 5)]) == mavlink2.MAV_MISSION_UNSUPPORTED
    assert upload(client, items) == mavlink2.MAV_MISSION_ACCEPTED
    mav.mission_request_list_send(1, 1, 0)
    count = client.wait(lambda m: m.get_type() == "MISSION_COUNT", grant=False)
    assert count.count == 3
    mav.mission_request_int_send(1, 1, 1, 0)
    item = client.wait(lambda m: m.get_type() == "MISSION_ITEM_INT", grant=False)
    assert (item.seq, item.command, item.x) == (1, 16, round(items[1][3] * 1e7))
    mav.mission_clear_all_send(1, 1, 0)
    ack = client.wait(lambda m: m.get_type() == "MISSION_ACK", grant=False)
    assert ack.type == mavlink2.MAV_MISSION_ACCEPTED
    mav.mission_request_list_send(1, 1, 0)
    assert client.wait(lambda m: m.get_type() == "MISSION_COUNT", grant=False).count == 0
    assert upload(client, items) == mavlink2.MAV_MISSION_ACCEPTED

    # fly it: ready, arm, mission mode, until landed and disarmed
    client.wait(lambda m: m.get_type() == "SYS_STATUS" and m.onboard_control_sensors_health & 0x10000000)
    assert client.command(400, 1) == mavlink2.MAV_RESULT_ACCEPTED
    assert client.command(176, 1, 4, 4) == mavlink2.MAV_RESULT_ACCEPTED
    client.wait(lambda m: m.get_type() == "EXTENDED_SYS_STATE" and m.landed_state == 2)  # in air
    client.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128)  # disarmed
    reached = sorted({m.seq for m in client.seen if m.get_type() == "MISSION_ITEM_REACHED"})
    assert reached == [0, 1, 2]
    client.wait(
        lambda m: m.get_type() == "EXTENDED_SYS_STATE" and m.landed_state == 1, vehicle_s=2
    )  # on ground

    # the log of that flight is closed and complete; SIGTERM ends the process cleanly
    deadline = time.monotonic() + 10
    while not (log_dir / "seed5-1.ulg").exists() and time.monotonic() < deadline:
        client.recv(0.2)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(10) == 0
    ulog = ULog(str(log_dir / "seed5-1.ulg"))
    names = {d.name for d in ulog.data_list}
    assert {
        "vehicle_local_position",
        "vehicle_status",
        "vehicle_land_detected",
        "vehicle_command",
        "mission_result",
        "position_setpoint_triplet",
        "vehicle_global_position",
        "home_position",
    } <= names
    assert ulog.initial_parameters["NAV_ACC_RAD"] == 0.5  # from the test's params file, at boot
    changed = [(name, value) for _, name, value in ulog.changed_parameters]
    assert ("EKF2_GPS_DELAY", 90.0) in changed and "UAVTEST_X" not in {n for n, _ in changed}


def test_sigterm_closes_an_open_log(sitl):
    client, proc, log_dir = sitl
    client.wait(lambda m: m.get_type() == "STATUSTEXT" and "Ready" in m.text)
    assert list(log_dir.glob("*.ulg.part"))
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(10) == 0
    (log,) = log_dir.glob("*.ulg")
    assert not list(log_dir.glob("*.part"))
    assert ULog(str(log)).get_dataset("vehicle_local_position").data["x"].size > 10


def _fly_over_udp(shared_data: Path, tmp_path: Path, seed: int) -> tuple[list, bytes]:
    port = free_udp_port()
    log_dir = tmp_path / f"log{seed}-{port}"
    test = shared_data / "competition" / "snippets" / "case_studies" / "mission1.yaml"
    client = LockstepClient(port)
    proc = subprocess.Popen(sitl_command(sys.executable, test, seed, api_port=port, log_dir=log_dir))
    try:
        spec = load_test(test).spec
        cmds = {"takeoff": 22, "waypoint": 16, "land": 21}
        client.wait(lambda m: m.get_type() == "HEARTBEAT", grant=False)  # udpin: learn the sim's address
        for name, value in spec.vehicle.params.items():
            ptype = 6 if isinstance(value, int) else 9
            raw = encode_param_value(value, ptype)
            client.conn.mav.param_set_send(1, 1, name.encode(), raw, ptype)
            client.wait(lambda m, n=name: m.get_type() == "PARAM_VALUE" and m.param_id == n, grant=False)
        items = [(cmds[i.kind.value], 6, 0.0, i.lat, i.lon, i.alt or 0.0) for i in mission_items(spec)]
        assert upload(client, items) == 0
        client.wait(lambda m: m.get_type() == "STATUSTEXT" and "Ready" in m.text)
        assert client.command(400, 1) == 0
        assert client.command(176, 1, 4, 4) == 0
        client.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128)
        positions = [
            (m.time_boot_ms, m.x, m.y, m.z) for m in client.seen if m.get_type() == "LOCAL_POSITION_NED"
        ]
        deadline = time.monotonic() + 10
        while not list(log_dir.glob("*.ulg")) and time.monotonic() < deadline:
            client.recv(0.2)
        (log,) = log_dir.glob("*.ulg")
        return positions, log.read_bytes()
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        client.conn.close()


def test_lockstep_over_udp_is_deterministic(shared_data: Path, tmp_path: Path):
    a_pos, a_log = _fly_over_udp(shared_data, tmp_path, seed=11)
    b_pos, b_log = _fly_over_udp(shared_data, tmp_path, seed=11)
    assert len(a_pos) > 300  # 10 Hz for the whole flight
    assert a_pos == b_pos
    ua, ub = ULog(__import__("io").BytesIO(a_log)), ULog(__import__("io").BytesIO(b_log))
    xa = ua.get_dataset("vehicle_local_position").data
    xb = ub.get_dataset("vehicle_local_position").data
    assert (xa["x"] == xb["x"]).all() and (xa["timestamp"] == xb["timestamp"]).all()
