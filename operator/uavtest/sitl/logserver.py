"""PX4's MAVLink log protocol over the simulator's finished flight logs.

The same answers PX4's ``mavlink_log_handler`` gives, so a ground station (the runner without a
shared log folder, QGC's log download) fetches our ``.ulg`` as it fetches PX4's:

- ``LOG_REQUEST_LIST(start, end)`` → one ``LOG_ENTRY`` per log in the range; ids are 0-based in
  the order the logs were written, ``last_log_num`` is the last id of the range. With no log a
  single ``LOG_ENTRY`` with ``num_logs`` 0.
- ``LOG_REQUEST_DATA(id, ofs, count)`` → ``LOG_DATA`` chunks of up to 90 bytes from ``ofs``, at
  most ``count`` bytes and no further than the end of the file; a chunk shorter than 90 bytes
  (possibly empty) ends the stream. An unknown id is ignored, as PX4 does.
- ``LOG_REQUEST_END`` stops the stream.

The logs are what is in the log folder (``log_folder``), as PX4's log handler lists its
``log/`` directory: logs left by earlier runs too, ordered by date, each ``LOG_ENTRY.time_utc``
the log's date (the ``YYYY-MM-DD/HH_MM_SS.ulg`` of a PX4 log, else the file's modification
time). Only closed logs are listed: the one being written (``.ulg.part``) is not a log yet.
The data is streamed in batches (``next_batch``) so the I/O loop can pace it as PX4 paces
its stream: a burst of a whole
log would overflow the client's UDP buffer.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import BinaryIO

from uavtest.sitl.mav import Msg

__all__ = ["CHUNK", "LogServer", "log_folder", "log_time_utc"]

log = logging.getLogger(__name__)

CHUNK = 90  # LOG_DATA.data


def log_time_utc(path: Path) -> int:
    """The log's date (Unix s): from a PX4 ``YYYY-MM-DD/HH_MM_SS.ulg`` name (UTC), else its mtime."""
    try:
        stamp = datetime.strptime(f"{path.parent.name} {path.stem}", "%Y-%m-%d %H_%M_%S")
        return int(stamp.replace(tzinfo=UTC).timestamp())
    except ValueError:
        return int(path.stat().st_mtime)


def log_folder(directory: Path) -> Callable[[], list[Path]]:
    """The finished ``.ulg`` files under ``directory`` (PX4's dated subfolders too), oldest first."""

    def logs() -> list[Path]:
        if not directory.is_dir():
            return []
        found = [(log_time_utc(p), str(p), p) for p in directory.rglob("*.ulg") if p.is_file()]
        return [p for _, _, p in sorted(found)]

    return logs


class LogServer:
    """Answers the log protocol; ``streaming`` while LOG_DATA is left to send."""

    def __init__(self, logs: Callable[[], Sequence[Path]], *, batch: int = 32) -> None:
        self._logs = logs
        self.batch = batch
        self._file: BinaryIO | None = None
        self._id = -1
        self._ofs = 0
        self._remaining = 0
        self._streaming = False

    @property
    def streaming(self) -> bool:
        return self._streaming

    def handle(self, msg: Msg) -> list[Msg] | None:
        """The replies to a log-protocol message; None for any other message."""
        if msg.name == "LOG_REQUEST_LIST":
            return self._list(int(msg.get("start", 0)), int(msg.get("end", 0xFFFF)))
        if msg.name == "LOG_REQUEST_DATA":
            self._request(int(msg.get("id", 0)), int(msg.get("ofs", 0)), int(msg.get("count", 0)))
            return []
        if msg.name == "LOG_REQUEST_END":
            self.close()
            return []
        return None

    def _list(self, start: int, end: int) -> list[Msg]:
        logs = list(self._logs())
        if not logs:
            return [Msg("LOG_ENTRY", {"id": 0, "num_logs": 0, "last_log_num": 0, "size": 0, "time_utc": 0})]
        first = min(start, len(logs) - 1)
        last = min(end, len(logs) - 1)
        return [
            Msg(
                "LOG_ENTRY",
                {
                    "id": i,
                    "num_logs": len(logs),
                    "last_log_num": last,
                    "size": logs[i].stat().st_size,
                    "time_utc": log_time_utc(logs[i]),
                },
            )
            for i in range(first, last + 1)
        ]

    def _request(self, log_id: int, ofs: int, count: int) -> None:
        logs = list(self._logs())
        if not 0 <= log_id < len(logs):
            log.warning("log %d requested, but there are %d logs", log_id, len(logs))
            return
        if log_id != self._id or self._file is None:
            self.close()
            self._file = open(logs[log_id], "rb")  # noqa: SIM115 - kept open while the client downloads
            self._id = log_id
        size = logs[log_id].stat().st_size
        self._ofs = ofs
        self._remaining = min(max(size - ofs, 0), count)
        self._streaming = True

    def next_batch(self) -> list[Msg]:
        """Up to ``batch`` LOG_DATA messages of the current stream (none when not streaming)."""
        out: list[Msg] = []
        while self._streaming and self._file is not None and len(out) < self.batch:
            self._file.seek(self._ofs)
            data = self._file.read(min(CHUNK, self._remaining))
            out.append(
                Msg(
                    "LOG_DATA",
                    {"id": self._id, "ofs": self._ofs, "count": len(data), "data": data.ljust(CHUNK, b"\0")},
                )
            )
            self._ofs += len(data)
            self._remaining -= len(data)
            if len(data) < CHUNK or self._remaining == 0:
                self._streaming = False
        return out

    def close(self) -> None:
        self._streaming = False
        if self._file is not None:
            self._file.close()
            self._file = None
        self._id = -1
