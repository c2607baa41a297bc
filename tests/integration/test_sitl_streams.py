"""`uavtest sitl` as a real process: telemetry per link at PX4 v1.15's rates, per-link
SET_MESSAGE_INTERVAL, the new messages, SYSTEM_TIME, the log list, capabilities and the
UNSUPPORTED path, seen by real clients (pymavlink; MAVSDK 4) over UDP."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from harness.mavlink_client import connect
from harness.net import free_udp_port
from harness.sitl import running_sitl

pytestmark = pytest.mark.integration

SPEED = 2.0


def collect(conn, wall_s: float) -> list:
    out, end = [], time.monotonic() + wall_s
    while time.monotonic() < end:
        m = conn.recv_match(blocking=True, timeout=0.2)
        if m is not None and m.get_type() != "BAD_DATA":
            out.append(m)
    return out


def wait_for(conn, cond: Callable, wall_s: float = 20.0):
    end = time.monotonic() + wall_s
    while time.monotonic() < end:
        m = conn.recv_match(blocking=True, timeout=0.2)
        if m is not None and cond(m):
            return m
    raise AssertionError("not received in time")


def rates(msgs: list) -> dict[str, float]:
    """Messages per second of vehicle time (time_boot_ms of the ATTITUDE stream spans it)."""
    t = [m.time_boot_ms for m in msgs if m.get_type() == "ATTITUDE"]
    span = (t[-1] - t[0]) / 1000.0
    return {name: n / span for name, n in Counter(m.get_type() for m in msgs).items()}


@pytest.fixture
def sim(tmp_path: Path) -> Iterator[tuple[int, int, Path]]:
    api, gcs = free_udp_port(), free_udp_port()
    log_dir = tmp_path / "log"
    earlier = log_dir / "2024-05-06" / "07_08_09.ulg"  # a PX4 log already in the folder
    earlier.parent.mkdir(parents=True)
    earlier.write_bytes(b"ULog\x01\x12\x35" + bytes(200))
    env = {k: v for k, v in os.environ.items() if k != "UAVTEST_SITL_UTC"}
    argv = [
        *(sys.executable, "-m", "uavtest.cli", "sitl", "--speed-factor", str(SPEED)),
        *("--api-port", str(api), "--gcs-port", str(gcs), "--api-local-port", "0"),
        *("--gcs-local-port", "0", "--log-dir", str(log_dir)),
    ]
    with running_sitl(argv, env={**env, "PYTHONUNBUFFERED": "1"}):
        yield api, gcs, earlier


def test_links_stream_their_modes_from_boot_and_intervals_are_per_link(sim):
    api_port, gcs_port, _ = sim
    gcs = connect(gcs_port)  # a ground station that only listens: never sends a byte
    wait_for(gcs, lambda m: m.get_type() == "GLOBAL_POSITION_INT")  # streams before any client spoke
    got = rates(collect(gcs, 3.0))
    assert got["ATTITUDE"] == pytest.approx(50, rel=0.15)  # px4-rc.mavlink: -r 50 on the GCS link
    assert got["GLOBAL_POSITION_INT"] == pytest.approx(50, rel=0.15)
    assert got["VFR_HUD"] == pytest.approx(4, rel=0.3)  # NORMAL
    assert 0.3 < got["ALTITUDE"] < 2.0 and 0.3 < got["SCALED_PRESSURE"] < 2.0
    assert "HIGHRES_IMU" not in got and "ODOMETRY" not in got  # ONBOARD only

    api = connect(api_port)  # now: nothing piled up in its socket buffer meanwhile
    api.mav.heartbeat_send(6, 8, 0, 0, 0)
    collect(api, 0.3)
    got = rates(collect(api, 2.0))
    assert got["HIGHRES_IMU"] == pytest.approx(50, rel=0.15)  # ONBOARD
    assert got["ODOMETRY"] == pytest.approx(30, rel=0.15)
    assert got["ALTITUDE"] == pytest.approx(10, rel=0.2)

    # SET_MESSAGE_INTERVAL on the API link: ALTITUDE off there, the GCS link keeps 1 Hz
    api.mav.command_long_send(1, 1, 511, 0, 141, -1, 0, 0, 0, 0, 0)
    ack = wait_for(api, lambda m: m.get_type() == "COMMAND_ACK" and m.command == 511)
    assert ack.result == 0
    api.mav.command_long_send(1, 1, 510, 0, 141, 0, 0, 0, 0, 0, 0)
    interval = wait_for(api, lambda m: m.get_type() == "MESSAGE_INTERVAL")
    assert (interval.message_id, interval.interval_us) == (141, 0)
    collect(api, 0.3)
    assert "ALTITUDE" not in Counter(m.get_type() for m in collect(api, 2.0))
    assert Counter(m.get_type() for m in collect(gcs, 2.5))["ALTITUDE"] >= 3


def test_new_messages_system_time_log_list_capabilities_and_unsupported(sim):
    api_port, _, earlier = sim
    api = connect(api_port)
    api.mav.heartbeat_send(6, 8, 0, 0, 0)
    msgs = {m.get_type(): m for m in collect(api, 1.5)}
    alt, aq, att = msgs["ALTITUDE"], msgs["ATTITUDE_QUATERNION"], msgs["ATTITUDE"]
    assert abs(alt.altitude_relative) < 0.5 and alt.altitude_amsl == pytest.approx(488.0, abs=1.0)
    assert math.fsum(q * q for q in (aq.q1, aq.q2, aq.q3, aq.q4)) == pytest.approx(1.0, abs=1e-5)
    yaw = math.atan2(2 * (aq.q1 * aq.q4 + aq.q2 * aq.q3), 1 - 2 * (aq.q3**2 + aq.q4**2))
    assert yaw == pytest.approx(att.yaw, abs=0.05)
    assert msgs["HIGHRES_IMU"].zacc == pytest.approx(-9.81, abs=0.05)  # standing on the ground
    assert 900 < msgs["SCALED_PRESSURE"].press_abs < 1013.25

    st = wait_for(api, lambda m: m.get_type() == "SYSTEM_TIME")
    assert abs(st.time_unix_usec / 1e6 - time.time()) < 60  # the host clock, not 1970

    api.mav.command_long_send(1, 1, 520, 0, 1, 0, 0, 0, 0, 0, 0)
    caps = wait_for(api, lambda m: m.get_type() == "AUTOPILOT_VERSION").capabilities
    assert caps & 4 and caps & 8192 and not caps & 32 and not caps & 64  # MISSION_INT, MAVLINK2; no FTP

    api.mav.command_long_send(1, 1, 183, 0, 1, 1500, 0, 0, 0, 0, 0)  # DO_SET_SERVO
    ack = wait_for(api, lambda m: m.get_type() == "COMMAND_ACK" and m.command == 183)
    assert ack.result == 3  # UNSUPPORTED, never DENIED
    chunks = [wait_for(api, lambda m: m.get_type() == "STATUSTEXT")]
    chunks.append(wait_for(api, lambda m: m.get_type() == "STATUSTEXT" and m.id == chunks[0].id))
    assert "".join(c.text for c in chunks) == "MAV_CMD_DO_SET_SERVO not supported by the built-in simulator"
    api.mav.command_long_send(1, 1, 176, 0, 1, 4, 8, 0, 0, 0, 0)  # follow-me
    ack = wait_for(api, lambda m: m.get_type() == "COMMAND_ACK" and m.command == 176)
    assert ack.result == 3

    api.mav.log_request_list_send(1, 1, 0, 0xFFFF)
    entry = wait_for(api, lambda m: m.get_type() == "LOG_ENTRY")
    assert (entry.num_logs, entry.size) == (1, earlier.stat().st_size)
    assert time.strftime("%Y-%m-%d %H_%M_%S", time.gmtime(entry.time_utc)) == "2024-05-06 07_08_09"


def test_mavsdk_reads_the_new_telemetry(sim):
    mavsdk = pytest.importorskip("mavsdk")
    from mavsdk.plugins.telemetry import Telemetry

    api_port, _, _ = sim
    sdk = mavsdk.Mavsdk(mavsdk.Configuration.create_with_component_type(mavsdk.ComponentType.GROUND_STATION))
    sdk.add_any_connection(f"udpin://127.0.0.1:{api_port}")
    system = sdk.first_autopilot(15.0)
    assert system is not None
    telemetry = Telemetry(system)
    end = time.monotonic() + 20
    while True:
        try:
            odom, q, press = (
                telemetry.odometry(),
                telemetry.attitude_quaternion(),
                telemetry.scaled_pressure(),
            )
            if press.absolute_pressure_hpa > 0:
                break
        except Exception:
            if time.monotonic() > end:
                raise
        time.sleep(0.1)
    assert abs(odom.position_body.z_m) < 0.5 and abs(odom.position_body.x_m) < 0.5
    assert math.fsum(c * c for c in (q.w, q.x, q.y, q.z)) == pytest.approx(1.0, abs=1e-4)
    assert 900 < press.absolute_pressure_hpa < 1013.25
    epoch = telemetry.unix_epoch_time()
    assert abs(epoch / 1e6 - time.time()) < 60


def test_with_gcs_quiet_the_gcs_link_streams_only_once_a_station_spoke(tmp_path: Path) -> None:
    """The engine's parallel replicas start `--gcs-quiet`: no telemetry into 14550 unasked."""
    api, gcs = free_udp_port(), free_udp_port()
    listener = connect(gcs)
    proc = subprocess.Popen(
        [
            *(sys.executable, "-m", "uavtest.cli", "sitl", "--speed-factor", str(SPEED), "--gcs-quiet"),
            *("--api-port", str(api), "--gcs-port", str(gcs), "--api-local-port", "0"),
            *("--gcs-local-port", "0", "--log-dir", str(tmp_path / "log")),
        ],
    )
    try:
        quiet = collect(listener, 3.0)
        assert quiet, "the heartbeat still reaches a listening station"
        assert {m.get_type() for m in quiet} <= {"HEARTBEAT", "STATUSTEXT"}
        listener.mav.heartbeat_send(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        spoken = collect(listener, 2.0)
        assert {"ATTITUDE", "GLOBAL_POSITION_INT"} <= {m.get_type() for m in spoken}
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        listener.close()
