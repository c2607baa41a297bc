"""pymavlink clients of a `uavtest sitl` process over UDP (udpin: the simulator sends first)."""

from __future__ import annotations

import time
from collections.abc import Callable

from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink2


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
