"""Stage 3: upload the mission with the MAVLink mission protocol (pure state machine).

MISSION_COUNT → the vehicle asks for each item (MISSION_REQUEST_INT, or MISSION_REQUEST from
older stacks) → MISSION_ITEM_INT → MISSION_ACK. The vehicle may ask for an item again (a lost
packet): it is simply sent again. Silence is retried on the wall clock; a refusal (an ACK other
than ACCEPTED) restarts the upload, a bounded number of times.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from enum import Enum

from uavtest.runner.events import (
    Incoming,
    MissionAck,
    MissionCount,
    MissionItemInt,
    MissionRequest,
    Outgoing,
)
from uavtest.runner.px4 import Cmd, MissionResult, result_name
from uavtest.spec.models import Home, MissionItem, MissionItemKind

__all__ = ["FRAME_GLOBAL_RELATIVE_ALT_INT", "FRAME_MISSION", "MissionUploader", "wire_items"]

log = logging.getLogger(__name__)

FRAME_MISSION = 2
FRAME_GLOBAL_RELATIVE_ALT_INT = 6
_NAN = float("nan")


def wire_items(items: Sequence[MissionItem], home: Home) -> list[MissionItemInt]:
    """MISSION_ITEM_INTs for the mission items (global coordinates, altitude relative to home).

    An item without a position (e.g. a land item written without one) takes the previous item's;
    param4 is the item's heading in degrees, NaN without one (PX4: MPC_YAW_MODE picks it).
    """
    out: list[MissionItemInt] = []
    lat, lon, alt = home.lat, home.lon, 0.0
    for seq, item in enumerate(items):
        lat = item.lat if item.lat is not None else lat
        lon = item.lon if item.lon is not None else lon
        alt = item.alt if item.alt is not None else alt
        x, y = round(lat * 1e7), round(lon * 1e7)
        kind = item.kind
        yaw = item.yaw if item.yaw is not None else _NAN
        if kind is MissionItemKind.TAKEOFF:
            wire = MissionItemInt(
                seq, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_TAKEOFF, 0, 0, 0, yaw, x, y, alt
            )
        elif kind is MissionItemKind.WAYPOINT:
            wire = MissionItemInt(
                seq, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_WAYPOINT, item.hold, 0, 0, yaw, x, y, alt
            )
        elif kind is MissionItemKind.LOITER_TIME:
            wire = MissionItemInt(
                seq, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_LOITER_TIME, item.hold, 0, 0, yaw, x, y, alt
            )
        elif kind is MissionItemKind.LAND:
            wire = MissionItemInt(seq, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_LAND, 0, 0, 0, yaw, x, y, 0.0)
        elif kind is MissionItemKind.RETURN:
            wire = MissionItemInt(seq, FRAME_MISSION, Cmd.NAV_RETURN_TO_LAUNCH)
        elif kind is MissionItemKind.LAND_START:
            wire = MissionItemInt(seq, FRAME_MISSION, Cmd.DO_LAND_START)
        elif kind is MissionItemKind.CHANGE_SPEED:
            wire = MissionItemInt(seq, FRAME_MISSION, Cmd.DO_CHANGE_SPEED, 1.0, item.speed or -1.0, -1.0)
        else:  # pragma: no cover - MissionItemKind is closed
            raise ValueError(f"unknown mission item kind {kind}")
        out.append(wire)
    return out


class _Waiting(Enum):
    REQUEST = "request"  # a MISSION_REQUEST(_INT) for the next item
    ACK = "ack"  # the last item went out; the ACK is due


class MissionUploader:
    """Uploads ``items``; ``done`` when the vehicle ACKs ACCEPTED, ``error`` when it never does."""

    def __init__(
        self,
        items: Sequence[MissionItemInt],
        *,
        retry_s: float = 1.0,
        attempts: int = 5,
        uploads: int = 3,
    ) -> None:
        self.items = list(items)
        self.retry_s = retry_s
        self.attempts = attempts
        self.uploads = uploads
        self.done = False
        self.error: str | None = None
        self.upload = 0  # uploads started
        self.resent = 0  # items the vehicle asked for again, or sent again after silence
        self._last: Outgoing | None = None
        self._sent: set[int] = set()
        self._tries = 0
        self._deadline = math.inf
        self._waiting = _Waiting.REQUEST

    @property
    def deadline(self) -> float:
        return self._deadline

    def start(self, wall: float) -> list[Outgoing]:
        return self._begin(wall)

    def _begin(self, wall: float) -> list[Outgoing]:
        self.upload += 1
        self._sent.clear()
        self._waiting = _Waiting.REQUEST
        log.info("mission upload %d: %d items", self.upload, len(self.items))
        return self._send(MissionCount(len(self.items)), wall, fresh=True)

    def _send(self, msg: Outgoing, wall: float, *, fresh: bool) -> list[Outgoing]:
        self._last = msg
        self._tries = 1 if fresh else self._tries + 1
        self._deadline = wall + self.retry_s
        return [msg]

    def _finish(self, error: str | None) -> list[Outgoing]:
        self.done = True
        self.error = error
        self._deadline = math.inf
        return []

    def _refused(self, why: str, wall: float) -> list[Outgoing]:
        if self.upload >= self.uploads:
            return self._finish(f"mission upload refused after {self.upload} attempts: {why}")
        log.warning("mission upload %d failed (%s); starting again", self.upload, why)
        return self._begin(wall)

    def handle(self, msg: Incoming, wall: float) -> list[Outgoing]:
        if self.done:
            return []
        if isinstance(msg, MissionRequest) and msg.mission_type == 0:
            if not 0 <= msg.seq < len(self.items):
                return self._refused(f"vehicle asked for item {msg.seq} of {len(self.items)}", wall)
            again = msg.seq in self._sent
            if again:
                self.resent += 1
                log.info("vehicle asked for mission item %d again", msg.seq)
            self._sent.add(msg.seq)
            self._waiting = _Waiting.ACK if msg.seq == len(self.items) - 1 else _Waiting.REQUEST
            return self._send(self.items[msg.seq], wall, fresh=not again)
        if isinstance(msg, MissionAck) and msg.mission_type == 0:
            if msg.result == MissionResult.ACCEPTED and len(self._sent) == len(self.items):
                log.info("mission accepted (%d items)", len(self.items))
                return self._finish(None)
            if msg.result == MissionResult.ACCEPTED:
                return self._refused(
                    f"ACCEPTED after only {len(self._sent)} of {len(self.items)} items", wall
                )
            return self._refused(f"MISSION_ACK {result_name(MissionResult, msg.result)}", wall)
        return []

    def tick(self, wall: float) -> list[Outgoing]:
        if self.done or wall < self._deadline or self._last is None:
            return []
        if self._tries >= self.attempts:
            waiting = (
                "the MISSION_ACK"
                if self._waiting is _Waiting.ACK
                else f"a request for item {len(self._sent)} of {len(self.items)}"
            )
            return self._refused(f"vehicle silent for {self._tries} tries waiting for {waiting}", wall)
        self.resent += 1
        log.warning("mission upload: no answer, sending %s again", type(self._last).__name__)
        return self._send(self._last, wall, fresh=False)
