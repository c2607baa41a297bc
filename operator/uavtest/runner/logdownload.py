"""Stage 6 over MAVLink: download the newest log from the vehicle (pure state machines).

LOG_REQUEST_LIST → LOG_ENTRY (one per log) → LOG_REQUEST_DATA for the newest → LOG_DATA chunks of
up to 90 bytes → LOG_REQUEST_END. Chunks lost on the way are asked for again from the first hole;
a download that stops making progress for ``attempts`` retries is a bench error.

``LogDownloader`` runs inside the runner core's log stage; ``LogFetch`` runs it on its own after
the flight (the runner's fallback when the shared log directory got no log: a PX4 image that
writes its log somewhere the runner cannot see): it waits for the vehicle's heartbeat first.
"""

from __future__ import annotations

import logging
import math

from uavtest.runner.events import (
    GcsHeartbeat,
    Heartbeat,
    Incoming,
    LogData,
    LogEntry,
    LogRequestData,
    LogRequestEnd,
    LogRequestList,
    Outgoing,
)
from uavtest.runner.px4 import Autopilot, MavType

__all__ = ["CHUNK", "LogDownloader", "LogFetch"]

log = logging.getLogger(__name__)

CHUNK = 90  # LOG_DATA payload


def _is_vehicle(msg: Incoming) -> bool:
    """A heartbeat of the vehicle, not of a ground station or companion computer."""
    return (
        isinstance(msg, Heartbeat)
        and msg.autopilot != Autopilot.INVALID
        and msg.type not in (MavType.GCS, MavType.ONBOARD_CONTROLLER)
    )


class LogDownloader:
    """``done`` with ``data`` (the log's bytes), or ``error``."""

    def __init__(self, *, retry_s: float = 1.0, attempts: int = 10) -> None:
        self.retry_s = retry_s
        self.attempts = attempts
        self.done = False
        self.error: str | None = None
        self.data: bytes | None = None
        self.log_id: int | None = None
        self.size = 0
        self.rerequests = 0
        self._entries: dict[int, LogEntry] = {}
        self._buf = bytearray()
        self._have = bytearray()
        self._missing = 0
        self._tries = 0
        self._deadline = math.inf

    @property
    def deadline(self) -> float:
        return self._deadline

    def start(self, wall: float) -> list[Outgoing]:
        self._tries = 1
        self._deadline = wall + self.retry_s
        return [LogRequestList()]

    def _finish(self, error: str | None) -> list[Outgoing]:
        self.done = True
        self.error = error
        self._deadline = math.inf
        return [LogRequestEnd()]

    def _choose(self, entry: LogEntry, wall: float) -> list[Outgoing]:
        self._entries[entry.id] = entry
        if entry.num_logs == 0:
            return self._finish("the vehicle has no log to download")
        if len(self._entries) < entry.num_logs and entry.id != entry.last_log_num:
            return []
        newest = self._entries.get(entry.last_log_num) or self._entries[max(self._entries)]
        self.log_id, self.size = newest.id, newest.size
        if self.size == 0:
            return self._finish(f"log {newest.id} on the vehicle is empty")
        chunks = math.ceil(self.size / CHUNK)
        self._buf = bytearray(self.size)
        self._have = bytearray(chunks)
        self._missing = chunks
        log.info("downloading log %d (%d bytes)", self.log_id, self.size)
        self._tries = 1
        self._deadline = wall + self.retry_s
        return [LogRequestData(self.log_id, 0, 0xFFFFFFFF)]

    def handle(self, msg: Incoming, wall: float) -> list[Outgoing]:
        if self.done:
            return []
        if isinstance(msg, LogEntry) and self.log_id is None:
            return self._choose(msg, wall)
        if isinstance(msg, LogData) and self.log_id is not None and msg.id == self.log_id:
            i = msg.ofs // CHUNK
            if msg.ofs % CHUNK or i >= len(self._have) or not msg.data:
                return []
            end = min(msg.ofs + len(msg.data), self.size)
            self._buf[msg.ofs : end] = msg.data[: end - msg.ofs]
            if not self._have[i]:
                self._have[i] = 1
                self._missing -= 1
            self._tries = 1
            self._deadline = wall + self.retry_s
            if self._missing == 0:
                self.data = bytes(self._buf)
                log.info(
                    "log %d downloaded (%d bytes, %d re-requests)", self.log_id, self.size, self.rerequests
                )
                return self._finish(None)
        return []

    def tick(self, wall: float) -> list[Outgoing]:
        if self.done or wall < self._deadline:
            return []
        if self._tries >= self.attempts:
            if self.log_id is None:
                return self._finish(f"no LOG_ENTRY after {self._tries} LOG_REQUEST_LISTs")
            got = self.size - self._missing * CHUNK
            return self._finish(f"log download stalled at about {max(got, 0)} of {self.size} bytes")
        self._tries += 1
        self.rerequests += 1
        self._deadline = wall + self.retry_s
        if self.log_id is None:
            return [LogRequestList()]
        first = self._have.index(0)
        return [LogRequestData(self.log_id, first * CHUNK, self.size - first * CHUNK)]


class LogFetch:
    """Download the newest log from a vehicle that is already running: ``done`` with ``data``, or ``error``.

    Waits up to ``connect_timeout_s`` (wall) for a vehicle heartbeat, then downloads; a GCS
    heartbeat goes out every second meanwhile (PX4 keeps a link with a ground station alive)."""

    def __init__(self, *, connect_timeout_s: float = 10.0, retry_s: float = 1.0, attempts: int = 10) -> None:
        self.connect_timeout_s = connect_timeout_s
        self.downloader = LogDownloader(retry_s=retry_s, attempts=attempts)
        self.connected = False
        self._connect_deadline = math.inf
        self._next_heartbeat = 0.0

    @property
    def done(self) -> bool:
        return self.downloader.done

    @property
    def data(self) -> bytes | None:
        return self.downloader.data

    @property
    def error(self) -> str | None:
        return self.downloader.error

    def start(self, wall: float) -> list[Outgoing]:
        self._connect_deadline = wall + self.connect_timeout_s
        return []

    def handle(self, msg: Incoming, wall: float) -> list[Outgoing]:
        if self.done:
            return []
        if not self.connected:
            if not _is_vehicle(msg):
                return []
            self.connected = True
            self._next_heartbeat = wall + 1.0
            return [GcsHeartbeat(), *self.downloader.start(wall)]
        return self.downloader.handle(msg, wall)

    def tick(self, wall: float) -> list[Outgoing]:
        if self.done:
            return []
        if not self.connected:
            if wall >= self._connect_deadline:
                self.downloader.done = True
                self.downloader.error = f"no vehicle heartbeat within {self.connect_timeout_s:g} s"
            return []
        out: list[Outgoing] = []
        if wall >= self._next_heartbeat:
            self._next_heartbeat = wall + 1.0
            out.append(GcsHeartbeat())
        return out + self.downloader.tick(wall)
