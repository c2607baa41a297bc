"""The UDP/pymavlink edge: the only module of the runner that touches pymavlink or a socket.

``MavlinkCodec`` turns datagrams into ``uavtest.runner.events`` and events into MAVLink 2 bytes.
It reads the message id from each frame's header and decodes only the messages the runner uses
(a simulator streams attitude, SYS_STATUS and more that nobody here reads: skipping them is most
of the receive loop's cost). ``UdpLink`` binds ``udpin:HOST:PORT`` like MAVSDK and QGroundControl
do and answers to wherever the vehicle's packets come from.

pymavlink's dialect module is imported directly, never ``mavutil`` (which sets the dialect and
environment globally at import).
"""

from __future__ import annotations

import errno
import logging
import select
import socket
from collections.abc import Callable, Iterable
from typing import Any

from pymavlink.dialects.v20 import common as mavlink2
from pymavlink.generator import mavcrc

from uavtest.errors import BadInput, InfrastructureError
from uavtest.mavlink_numbers import MavFrame
from uavtest.runner.events import (
    Attitude,
    CommandAck,
    CommandInt,
    CommandLong,
    ExtendedSysState,
    GcsHeartbeat,
    GlobalPosition,
    Heartbeat,
    HomePosition,
    Incoming,
    LocalPosition,
    LockstepAnnounce,
    LockstepGrant,
    LogData,
    LogEntry,
    LogRequestData,
    LogRequestEnd,
    LogRequestList,
    ManualControl,
    MissionAck,
    MissionCount,
    MissionItemInt,
    MissionItemReached,
    MissionRequest,
    ObstacleDistance,
    Outgoing,
    ParamRequestRead,
    ParamSet,
    ParamValue,
    PositionTargetGlobal,
    PositionTargetLocal,
    StatusText,
    SysStatus,
    VehicleTime,
)

__all__ = ["LOCKSTEP_NAME", "MavlinkCodec", "UdpLink", "parse_endpoint"]

log = logging.getLogger(__name__)

LOCKSTEP_NAME = "LOCKSTEP"
DATAGRAM_BYTES = 1400  # what one outgoing datagram may hold (PX4 reads datagrams of up to ~1500)

_STX_V2 = 0xFD


def _crc_slow(data: bytes, crc: int) -> int:
    acc = mavcrc.x25crc()
    acc.crc = crc
    acc.accumulate(data)
    return int(acc.crc)


#: CRC-16/MCRF4XX: fastcrc's when installed (as pymavlink uses it), else pymavlink's pure Python
_crc = mavcrc.mcrf4xx or _crc_slow
_STX_V1 = 0xFE


def _heartbeat(m: Any) -> Heartbeat:
    return Heartbeat(
        m.get_srcSystem(),
        m.get_srcComponent(),
        m.type,
        m.autopilot,
        m.base_mode,
        m.custom_mode,
        m.system_status,
    )


def _named_value_int(m: Any) -> LockstepAnnounce | None:
    return LockstepAnnounce(m.value) if m.name == LOCKSTEP_NAME else None


#: message id → converter from the pymavlink message to an event (None: not for us)
_DECODERS: dict[int, Callable[[Any], Incoming | None]] = {
    0: _heartbeat,
    1: lambda m: SysStatus(m.onboard_control_sensors_health),
    2: lambda m: VehicleTime(m.time_boot_ms),  # SYSTEM_TIME
    22: lambda m: ParamValue(m.param_id, m.param_value, m.param_type, m.param_index, m.param_count),
    32: lambda m: LocalPosition(m.time_boot_ms, m.x, m.y, m.z),
    33: lambda m: GlobalPosition(m.time_boot_ms, m.lat, m.lon, m.relative_alt),
    40: lambda m: MissionRequest(m.seq, getattr(m, "mission_type", 0)),  # MISSION_REQUEST (deprecated)
    46: lambda m: MissionItemReached(m.seq),
    47: lambda m: MissionAck(m.type, getattr(m, "mission_type", 0)),
    51: lambda m: MissionRequest(m.seq, getattr(m, "mission_type", 0)),  # MISSION_REQUEST_INT
    77: lambda m: CommandAck(m.command, m.result),
    118: lambda m: LogEntry(m.id, m.num_logs, m.last_log_num, m.size),
    120: lambda m: LogData(m.id, m.ofs, bytes(m.data[: m.count])),
    242: lambda m: HomePosition(m.latitude, m.longitude, m.altitude),
    245: lambda m: ExtendedSysState(m.landed_state),
    252: _named_value_int,
    253: lambda m: StatusText(m.severity, m.text),
}


def _fast(
    cls: Any, build: Callable[[tuple[Any, ...]], Incoming | None]
) -> tuple[Any, int, int, Callable[..., Any]]:
    return cls.unpacker, cls.unpacker.size, cls.crc_extra, build


#: the messages of every lockstep step (and SYS_STATUS, 1 Hz of vehicle time), unpacked straight
#: from the payload with pymavlink's own struct layout and CRC extra (a full pymavlink decode costs
#: several times more)
_FAST: dict[int, tuple[Any, int, int, Callable[..., Any]]] = {
    32: _fast(mavlink2.MAVLink_local_position_ned_message, lambda f: LocalPosition(f[0], f[1], f[2], f[3])),
    30: _fast(mavlink2.MAVLink_attitude_message, lambda f: Attitude(f[0], f[3])),  # time_boot_ms, yaw
    33: _fast(mavlink2.MAVLink_global_position_int_message, lambda f: GlobalPosition(f[0], f[1], f[2], f[4])),
    1: _fast(mavlink2.MAVLink_sys_status_message, lambda f: SysStatus(f[2])),  # sensors health
    252: _fast(
        mavlink2.MAVLink_named_value_int_message,
        lambda f: LockstepAnnounce(f[1]) if f[2].rstrip(b"\0") == b"LOCKSTEP" else None,
    ),
}


_EXTRA = [bytes((i,)) for i in range(256)]


class MavlinkCodec:
    """MAVLink 2 bytes ⇄ runner events, as system ``sysid``/``compid`` (a ground station)."""

    def __init__(self, sysid: int = 255, compid: int = 190) -> None:
        self._tx = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self._rx = mavlink2.MAVLink(None)
        self._rx.robust_parsing = True
        self.target_system = 1
        self.target_component = 1
        self.frames = 0  # frames seen
        self.decoded = 0  # frames decoded (the rest were skipped by id)
        self.bad = 0  # frames that failed to decode (CRC, truncation)

    def decode(self, datagram: bytes) -> list[Incoming]:
        """The events in one UDP datagram (one or more MAVLink frames)."""
        out: list[Incoming] = []
        n = len(datagram)
        pos = 0
        while pos + 8 <= n:
            stx = datagram[pos]
            if stx == _STX_V2:
                length = 12 + datagram[pos + 1] + (13 if datagram[pos + 2] & 1 else 0)
                msgid = datagram[pos + 7] | datagram[pos + 8] << 8 | datagram[pos + 9] << 16
            elif stx == _STX_V1:
                length = 8 + datagram[pos + 1]
                msgid = datagram[pos + 5]
            else:  # not a frame start: resynchronise on the next byte
                pos += 1
                continue
            self.frames += 1
            fast = _FAST.get(msgid) if stx == _STX_V2 and length == 12 + datagram[pos + 1] else None
            if fast is not None and pos + length <= n:
                unpacker, size, crc_extra, build = fast
                plen = datagram[pos + 1]
                end = pos + 10 + plen
                crc = _crc(_EXTRA[crc_extra], _crc(datagram[pos + 1 : end], 0xFFFF))
                if crc == datagram[end] | datagram[end + 1] << 8:
                    payload = datagram[pos + 10 : end]
                    if plen < size:  # MAVLink 2 drops trailing zero bytes
                        payload += bytes(size - plen)
                    event = build(unpacker.unpack(payload[:size]))
                    if event is not None:
                        self.decoded += 1
                        out.append(event)
                else:
                    self.bad += 1
                pos += length
                continue
            convert = _DECODERS.get(msgid)
            if convert is not None and pos + length <= n:
                try:
                    msg = self._rx.decode(bytearray(datagram[pos : pos + length]))
                except Exception as e:  # pymavlink raises MAVError and struct errors on bad frames
                    self.bad += 1
                    log.debug("dropped a bad MAVLink frame (id %d): %s", msgid, e)
                else:
                    event = convert(msg)
                    if event is not None:
                        self.decoded += 1
                        if msgid == 0 and event.autopilot != 8:  # type: ignore[union-attr]
                            self.target_system, self.target_component = event.sysid, event.compid  # type: ignore[union-attr]
                        out.append(event)
            pos += length
        return out

    def encode(self, msg: Outgoing) -> bytes:
        """MAVLink 2 bytes of one outgoing event, addressed to the vehicle."""
        mav, ts, tc = self._tx, self.target_system, self.target_component
        if isinstance(msg, LockstepGrant):
            m = mav.named_value_int_encode(msg.seen_ms, LOCKSTEP_NAME.encode(), msg.until_ms)
        elif isinstance(msg, ManualControl):
            m = mav.manual_control_encode(ts, msg.x, msg.y, msg.z, msg.r, 0)
        elif isinstance(msg, ObstacleDistance):
            m = mav.obstacle_distance_encode(
                msg.time_usec, msg.sensor_type, list(msg.distances), round(msg.increment),
                msg.min_cm, msg.max_cm, msg.increment, msg.angle_offset, msg.frame,
            )  # fmt: skip
        elif isinstance(msg, GcsHeartbeat):
            m = mav.heartbeat_encode(6, 8, 0, 0, 4)  # MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID, MAV_STATE_ACTIVE
        elif isinstance(msg, CommandLong):
            m = mav.command_long_encode(ts, tc, msg.command, msg.confirmation, *msg.params)
        elif isinstance(msg, CommandInt):
            m = mav.command_int_encode(
                ts, tc, msg.frame, msg.command, 0, 0, *msg.params, msg.x, msg.y, msg.z
            )  # current 0, autocontinue 0
        elif isinstance(msg, PositionTargetLocal):
            m = mav.set_position_target_local_ned_encode(
                msg.time_ms, ts, tc, MavFrame.LOCAL_NED, msg.type_mask,
                msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz, 0, 0, 0, msg.yaw, msg.yaw_rate,
            )  # fmt: skip
        elif isinstance(msg, PositionTargetGlobal):
            m = mav.set_position_target_global_int_encode(
                msg.time_ms, ts, tc, MavFrame.GLOBAL_RELATIVE_ALT_INT, msg.type_mask,
                msg.lat, msg.lon, msg.alt, msg.vx, msg.vy, msg.vz, 0, 0, 0, msg.yaw, msg.yaw_rate,
            )  # fmt: skip
        elif isinstance(msg, ParamRequestRead):
            m = mav.param_request_read_encode(ts, tc, msg.name.encode(), -1)
        elif isinstance(msg, ParamSet):
            m = mav.param_set_encode(ts, tc, msg.name.encode(), msg.value, msg.param_type)
        elif isinstance(msg, MissionCount):
            m = mav.mission_count_encode(ts, tc, msg.count, 0)
        elif isinstance(msg, MissionItemInt):
            m = mav.mission_item_int_encode(
                ts, tc, msg.seq, msg.frame, msg.command, msg.current, msg.autocontinue,
                msg.param1, msg.param2, msg.param3, msg.param4, msg.x, msg.y, msg.z, 0,
            )  # fmt: skip
        elif isinstance(msg, LogRequestList):
            m = mav.log_request_list_encode(ts, tc, msg.start, msg.end)
        elif isinstance(msg, LogRequestData):
            m = mav.log_request_data_encode(ts, tc, msg.id, msg.ofs, msg.count)
        elif isinstance(msg, LogRequestEnd):
            m = mav.log_request_end_encode(ts, tc)
        else:  # pragma: no cover - Outgoing is closed
            raise TypeError(f"cannot encode {type(msg).__name__}")
        return m.pack(mav)


def parse_endpoint(endpoint: str) -> tuple[str, int]:
    """``udpin:HOST:PORT`` (also ``udp:``) → (host, port)."""
    scheme, _, rest = endpoint.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme not in {"udpin", "udp"} or not host or not port.isdigit() or not 0 <= int(port) < 65536:
        raise BadInput(
            "not a MAVLink endpoint the runner can listen on",
            field="connect",
            value=endpoint,
            allowed="udpin:HOST:PORT, e.g. udpin:127.0.0.1:14540",
        )
    return host, int(port)


class UdpLink:
    """A bound UDP socket that speaks MAVLink to whoever sent the last datagram."""

    def __init__(self, endpoint: str, codec: MavlinkCodec | None = None) -> None:
        self.endpoint = endpoint
        self.host, self.port = parse_endpoint(endpoint)
        self.codec = codec or MavlinkCodec()
        self.peer: tuple[str, int] | None = None
        self.sent = 0
        self.received = 0
        self._sock: socket.socket | None = None

    def open(self) -> UdpLink:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
            sock.bind((self.host, self.port))
        except OSError as e:
            sock.close()
            if e.errno == errno.EADDRINUSE:
                raise InfrastructureError(
                    f"port {self.port} is taken: cannot listen on {self.endpoint} "
                    "(another runner, PX4 client or ground station holds it)"
                ) from e
            raise InfrastructureError(f"cannot listen on {self.endpoint}: {e.strerror or e}") from e
        sock.setblocking(False)
        self._sock = sock
        self.port = sock.getsockname()[1]  # the real one when 0 (any) was asked for
        return self

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def __enter__(self) -> UdpLink:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def receive(self, timeout: float) -> list[Incoming]:
        """Events from every datagram waiting now, or from the first to arrive within ``timeout``."""
        sock = self._sock
        assert sock is not None, "open() the link first"
        out: list[Incoming] = []
        recv = sock.recvfrom
        while True:
            try:
                data, addr = recv(65535)
            except BlockingIOError:
                if out or timeout <= 0:
                    return out
                ready, _, _ = select.select([sock], [], [], timeout)
                if not ready:
                    return out
                timeout = 0.0
                continue
            except ConnectionRefusedError:  # ICMP from a previous send: the peer's port closed
                continue
            self.received += 1
            self.peer = addr
            out.extend(self.codec.decode(data))

    def send(self, messages: Iterable[Outgoing]) -> None:
        """Send to the vehicle, packed into as few datagrams as fit ``DATAGRAM_BYTES`` (in order);
        dropped (with a debug line) until the vehicle has spoken."""
        sock = self._sock
        assert sock is not None, "open() the link first"
        if self.peer is None:
            return
        encode = self.codec.encode
        batch = bytearray()
        for msg in messages:
            frame = encode(msg)
            if batch and len(batch) + len(frame) > DATAGRAM_BYTES:
                self._sendto(sock, batch)
                batch = bytearray()
            batch += frame
        if batch:
            self._sendto(sock, batch)

    def _sendto(self, sock: socket.socket, datagram: bytearray) -> None:
        try:
            sock.sendto(datagram, self.peer)  # type: ignore[arg-type]
            self.sent += 1
        except OSError as e:  # the simulator is gone; the core notices its silence
            log.debug("send %d bytes to %s failed: %s", len(datagram), self.peer, e)
