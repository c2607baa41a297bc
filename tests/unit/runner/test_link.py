"""The pymavlink edge: bytes ⇄ events, checked against pymavlink itself, and the UDP socket."""

from __future__ import annotations

import socket

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from uavtest.errors import BadInput, InfrastructureError
from uavtest.runner.events import (
    Attitude,
    CommandAck,
    CommandLong,
    Heartbeat,
    LocalPosition,
    LockstepAnnounce,
    LockstepGrant,
    LogData,
    ManualControl,
    MissionItemInt,
    MissionRequest,
    ObstacleDistance,
    ParamSet,
    ParamValue,
    StatusText,
    SysStatus,
)
from uavtest.runner.link import MavlinkCodec, UdpLink, parse_endpoint

VEHICLE = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
PREARM = mavlink2.MAV_SYS_STATUS_PREARM_CHECK


def frame(msg: mavlink2.MAVLink_message) -> bytes:
    return bytes(msg.pack(VEHICLE))


def test_vehicle_messages_become_events() -> None:
    codec = MavlinkCodec()
    data = b"".join(
        [
            frame(VEHICLE.heartbeat_encode(2, 12, 129, 4 << 16 | 4 << 24, 4)),
            frame(VEHICLE.local_position_ned_encode(1234, 1.5, -2.0, -10.0, 0, 0, 0)),
            frame(VEHICLE.attitude_encode(1234, 0.1, 0.2, 0.3, 0, 0, 0)),  # the heading only
            frame(VEHICLE.vfr_hud_encode(1.0, 1.0, 90, 50, 10.0, 0.0)),  # not for the runner: skipped
            frame(VEHICLE.param_value_encode(b"NAV_ACC_RAD", 2.0, 9, 100, 5)),
            frame(VEHICLE.mission_request_int_encode(255, 190, 3, 0)),
            frame(VEHICLE.mission_request_encode(255, 190, 4, 0)),
            frame(VEHICLE.command_ack_encode(400, 0)),
            frame(VEHICLE.named_value_int_encode(1250, b"LOCKSTEP", 1250)),
            frame(VEHICLE.named_value_int_encode(1250, b"OTHER", 7)),
            frame(VEHICLE.statustext_encode(4, b"Takeoff detected")),
            frame(VEHICLE.log_data_encode(3, 180, 4, b"\x01\x02\x03\x04".ljust(90, b"\0"))),
            frame(VEHICLE.sys_status_encode(0, 0, PREARM | 32, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)),
        ]
    )
    events = codec.decode(data)
    assert events == [
        Heartbeat(1, 1, 2, 12, 129, 4 << 16 | 4 << 24, 4),
        LocalPosition(1234, 1.5, -2.0, -10.0),
        Attitude(1234, pytest.approx(0.3)),
        ParamValue("NAV_ACC_RAD", 2.0, 9, 5, 100),
        MissionRequest(3),
        MissionRequest(4),
        CommandAck(400, 0),
        LockstepAnnounce(1250),
        StatusText(4, "Takeoff detected"),
        LogData(3, 180, b"\x01\x02\x03\x04"),
        SysStatus(PREARM | 32),
    ]
    assert events[0].armed  # type: ignore[union-attr]
    assert events[-1].ready_to_arm and not SysStatus(32).ready_to_arm  # type: ignore[union-attr]
    assert codec.frames == 13 and codec.decoded == 11


def test_a_corrupt_frame_is_dropped_and_the_next_one_still_decodes() -> None:
    codec = MavlinkCodec()
    bad = bytearray(frame(VEHICLE.command_ack_encode(400, 0)))
    bad[-1] ^= 0xFF  # CRC
    bad_position = bytearray(frame(VEHICLE.local_position_ned_encode(5, 1.0, 2.0, 3.0, 0, 0, 0)))
    bad_position[12] ^= 0x01  # a payload bit flipped on the way
    good = frame(VEHICLE.command_ack_encode(176, 0))
    assert codec.decode(bytes(bad) + bytes(bad_position) + good) == [CommandAck(176, 0)]
    assert codec.bad == 2


def test_trailing_zeros_dropped_by_mavlink2_are_restored() -> None:
    codec = MavlinkCodec()
    data = frame(VEHICLE.local_position_ned_encode(7, 1.0, 0.0, 0.0, 0, 0, 0))
    assert data[1] < 28  # the zero velocities were truncated on the wire
    assert codec.decode(data) == [LocalPosition(7, 1.0, 0.0, 0.0)]


def test_outgoing_events_are_what_pymavlink_reads_addressed_to_the_vehicle() -> None:
    codec = MavlinkCodec(sysid=255, compid=190)
    codec.decode(frame(VEHICLE.heartbeat_encode(2, 12, 0, 0, 3)))  # learn the target
    reader = mavlink2.MAVLink(None)
    item = MissionItemInt(2, 6, 16, 1.0, 0, 0, 0, 473977420, 85455940, 10.0)
    msgs = [
        reader.decode(bytearray(codec.encode(m)))
        for m in (
            LockstepGrant(1000, 1050),
            ParamSet("NAV_ACC_RAD", 2.0, 9),
            item,
            CommandLong(400, (1, 0, 0, 0, 0, 0, 0), confirmation=2),
            ManualControl(500, -1000, 500, 0),
            ObstacleDistance(2_000_000, (250, 65535) + (1201,) * 70, 20, 1200, 5.0, 0.0, 12),
        )
    ]
    grant, pset, mitem, cmd, manual, scan = msgs
    assert (grant.get_type(), grant.name, grant.time_boot_ms, grant.value) == (
        "NAMED_VALUE_INT",
        "LOCKSTEP",
        1000,
        1050,
    )
    assert (pset.param_id, pset.param_value, pset.param_type, pset.target_system) == (
        "NAV_ACC_RAD",
        2.0,
        9,
        1,
    )
    assert (mitem.seq, mitem.frame, mitem.command, mitem.x, mitem.z, mitem.mission_type) == (
        2,
        6,
        16,
        473977420,
        10.0,
        0,
    )
    assert (cmd.command, cmd.confirmation, cmd.param1, cmd.target_system) == (400, 2, 1.0, 1)
    assert (manual.x, manual.y, manual.z, manual.r, manual.target) == (500, -1000, 500, 0, 1)
    # OBSTACLE_DISTANCE as PX4's mavlink_receiver reads it: increment_f wins over increment
    assert scan.get_type() == "OBSTACLE_DISTANCE" and scan.time_usec == 2_000_000
    assert list(scan.distances[:3]) == [250, 65535, 1201] and len(scan.distances) == 72
    assert (scan.increment, scan.increment_f, scan.min_distance, scan.max_distance, scan.frame) == (
        5,
        5.0,
        20,
        1200,
        12,
    )
    assert all(m.get_srcSystem() == 255 for m in msgs)


@pytest.mark.parametrize(
    "endpoint", ["tcp:127.0.0.1:5760", "udpin:127.0.0.1", "udpin::14540", "udpin:h:99999"]
)
def test_endpoints_the_runner_cannot_listen_on_are_bad_input(endpoint: str) -> None:
    with pytest.raises(BadInput):
        parse_endpoint(endpoint)


def test_a_taken_port_is_a_bench_error_naming_the_port() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as holder:
        holder.bind(("127.0.0.1", 0))
        port = holder.getsockname()[1]
        with pytest.raises(InfrastructureError, match=f"port {port} is taken"):
            UdpLink(f"udpin:127.0.0.1:{port}").open()


def test_the_link_answers_to_where_the_vehicle_speaks_from() -> None:
    with UdpLink("udpin:127.0.0.1:0") as link, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as vehicle:
        port = link.port
        vehicle.bind(("127.0.0.1", 0))
        vehicle.settimeout(5)
        link.send([LockstepGrant(0, 50)])  # nobody to talk to yet: dropped
        vehicle.sendto(frame(VEHICLE.named_value_int_encode(0, b"LOCKSTEP", 0)), ("127.0.0.1", port))
        assert link.receive(5.0) == [LockstepAnnounce(0)]
        link.send([LockstepGrant(0, 50)])
        data, _ = vehicle.recvfrom(1024)
        grant = mavlink2.MAVLink(None).decode(bytearray(data))
        assert (grant.name, grant.value) == ("LOCKSTEP", 50)
