"""pymavlink clients of a `uavtest sitl` process over UDP (udpin: the simulator sends first)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink2

PREARM = mavlink2.MAV_SYS_STATUS_PREARM_CHECK


def connect(port: int):
    """A pymavlink connection listening on 127.0.0.1:``port`` as a ground station (255/190),
    MAVLink 2 common dialect, robust parsing."""
    conn = mavutil.mavlink_connection(
        f"udpin:127.0.0.1:{port}", source_system=255, source_component=190, dialect="common"
    )
    conn.mav = mavlink2.MAVLink(conn, srcSystem=255, srcComponent=190)
    conn.mav.robust_parsing = True
    return conn


class LockstepClient:
    """A minimal lockstep client: grants 50 ms of vehicle time whenever the sim waits."""

    deadline_s = 60.0  # wall clock per `wait`

    def __init__(self, port: int) -> None:
        self.conn = connect(port)
        self.t_ms = -1
        self.seen: list = []

    def recv(self, timeout: float = 5.0):
        msg = self.conn.recv_match(blocking=True, timeout=timeout)
        if msg is not None:
            if msg.get_type() == "NAMED_VALUE_INT" and msg.name == "LOCKSTEP":
                self.t_ms = max(self.t_ms, msg.value)
            self.seen.append(msg)
        return msg

    def wait(self, cond: Callable, vehicle_s: float = 300.0, *, grant: bool = True):
        """Receive (granting time in lockstep) until ``cond(msg)``; fails after the limits."""
        wall = time.monotonic() + self.deadline_s
        limit_ms = None
        while time.monotonic() < wall:
            msg = self.recv(1.0)
            if msg is None:
                continue
            if cond(msg):
                return msg
            if limit_ms is None and self.t_ms >= 0:
                limit_ms = self.t_ms + vehicle_s * 1000
            if grant and msg.get_type() == "NAMED_VALUE_INT" and msg.name == "LOCKSTEP":
                if limit_ms is not None and msg.value > limit_ms:
                    break
                self.conn.mav.named_value_int_send(msg.value, b"LOCKSTEP", msg.value + 50)
        raise AssertionError("condition not met in time")

    def command(self, cmd: int, *params: float) -> int:
        p = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, cmd, 0, *p)
        ack = self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd, grant=False)
        return ack.result


class GroundStation:
    """A ground station (255/190) on one free-running vehicle's API link (PX4 SITL or ``uavtest
    sitl`` without lockstep): heartbeats at 1 Hz from a thread; the vehicle's mode, armed state,
    pre-arm bit, relative altitude, STATUSTEXTs (chunks joined) and MISSION_ITEM_REACHED kept up
    to date while it waits (``until``)."""

    def __init__(self, port: int) -> None:
        self.conn = connect(port)
        self.mode: tuple[int, int] | None = None
        self.armed = False
        self.prearm = False
        self.alt = math.nan
        self.texts: list[str] = []
        self.acks: list[tuple[int, int]] = []  # (command, result)
        self.reached: list[int] = []  # MISSION_ITEM_REACHED seqs, in order
        self.max_alt = -math.inf
        self._chunks: dict[int, str] = {}
        self._stop = threading.Event()
        self._beat = threading.Thread(target=self._heartbeats, daemon=True)
        self._beat.start()

    def _heartbeats(self) -> None:
        while not self._stop.is_set():
            self.conn.mav.heartbeat_send(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self._stop.wait(1.0)

    def close(self) -> None:
        self._stop.set()
        self._beat.join(2)
        self.conn.close()

    def _take(self, m) -> None:
        kind = m.get_type()
        if kind == "HEARTBEAT" and m.get_srcComponent() == 1:
            self.mode = ((m.custom_mode >> 16) & 0xFF, (m.custom_mode >> 24) & 0xFF)
            self.armed = bool(m.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)
        elif kind == "COMMAND_ACK":
            self.acks.append((m.command, m.result))
        elif kind == "SYS_STATUS":
            self.prearm = bool(m.onboard_control_sensors_health & PREARM)
        elif kind == "GLOBAL_POSITION_INT":
            self.alt = m.relative_alt / 1000
            self.max_alt = max(self.max_alt, self.alt)
        elif kind == "MISSION_ITEM_REACHED":
            self.reached.append(m.seq)
        elif kind == "STATUSTEXT":
            text = m.text.rstrip("\t")
            if m.id:
                text = self._chunks[m.id] = self._chunks.get(m.id, "") + m.text
                if len(m.text) == 50:  # more chunks follow
                    return
                text = text.rstrip("\t")
            self.texts.append(text)

    def until(self, cond, seconds: float, what: str) -> None:
        end = time.monotonic() + seconds
        while not cond():
            if time.monotonic() > end:
                raise AssertionError(f"timed out waiting for {what}; texts {self.texts[-8:]}")
            m = self.conn.recv_match(blocking=True, timeout=0.5)
            if m is not None:
                self._take(m)

    def command(self, cmd: int, *params: float, settle: float = 0.5) -> int:
        """Send a COMMAND_LONG, wait for its ACK, then ``settle`` seconds (wall clock) for what
        follows it (texts, telemetry); its MAV_RESULT."""
        p = [*params, *[0.0] * (7 - len(params))]
        self.acks.clear()
        self.conn.mav.command_long_send(1, 1, cmd, 0, *p)
        self.until(lambda: any(c == cmd for c, _ in self.acks), 10, f"the ACK of command {cmd}")
        self.settle(settle)
        return next(r for c, r in self.acks if c == cmd)

    def settle(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        self.until(lambda: time.monotonic() > end, seconds + 1, "time")

    def set_mode(self, mode: tuple[int, int]) -> int:
        return self.command(mavlink2.MAV_CMD_DO_SET_MODE, 1, *mode)

    def upload(self, items: list[tuple[int, float, float, float, float]]) -> int:
        """Upload a mission of (command, param4, lat, lon, relative alt) items in
        MAV_FRAME_GLOBAL_RELATIVE_ALT_INT; the MISSION_ACK's result."""
        acks: list[int] = []
        self.conn.mav.mission_count_send(1, 1, len(items), 0)
        end = time.monotonic() + 30
        while not acks:
            if time.monotonic() > end:
                raise AssertionError("the mission upload timed out")
            m = self.conn.recv_match(blocking=True, timeout=0.5)
            if m is None:
                continue
            self._take(m)
            if m.get_type() in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
                cmd, p4, lat, lon, alt = items[m.seq]
                self.conn.mav.mission_item_int_send(
                    1, 1, m.seq, mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, cmd, 0, 1,
                    0, 0, 0, p4, round(lat * 1e7), round(lon * 1e7), alt, 0,
                )  # fmt: skip
            elif m.get_type() == "MISSION_ACK":
                acks.append(m.type)
        return acks[0]
