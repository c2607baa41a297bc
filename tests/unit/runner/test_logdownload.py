"""Stage 6 over MAVLink: the newest log, whole, even when chunks get lost."""

from __future__ import annotations

import os

from uavtest.runner.events import (
    GcsHeartbeat,
    Heartbeat,
    LogData,
    LogEntry,
    LogRequestData,
    LogRequestEnd,
    LogRequestList,
)
from uavtest.runner.logdownload import CHUNK, LogDownloader, LogFetch

LOG = os.urandom(1000)  # 12 chunks, the last one short


def chunks(log_id: int, skip: set[int] = frozenset()) -> list[LogData]:  # type: ignore[assignment]
    return [
        LogData(log_id, ofs, LOG[ofs : ofs + CHUNK])
        for i, ofs in enumerate(range(0, len(LOG), CHUNK))
        if i not in skip
    ]


def test_the_newest_log_is_downloaded_whole() -> None:
    d = LogDownloader()
    assert d.start(0.0) == [LogRequestList()]
    assert d.handle(LogEntry(0, 2, 1, 500), 0.0) == []
    assert d.handle(LogEntry(1, 2, 1, len(LOG)), 0.0) == [LogRequestData(1, 0, 0xFFFFFFFF)]
    out = []
    for c in chunks(1):
        out += d.handle(c, 0.1)
    assert out == [LogRequestEnd()]
    assert d.done and d.error is None and d.data == LOG


def test_lost_chunks_are_asked_for_again_from_the_first_hole() -> None:
    d = LogDownloader(retry_s=1.0)
    d.start(0.0)
    d.handle(LogEntry(0, 1, 0, len(LOG)), 0.0)
    for c in chunks(0, skip={3, 7}):
        d.handle(c, 0.1)
    assert not d.done
    assert d.tick(1.2) == [LogRequestData(0, 3 * CHUNK, len(LOG) - 3 * CHUNK)]
    d.handle(chunks(0)[3], 1.3)
    assert d.tick(2.4) == [LogRequestData(0, 7 * CHUNK, len(LOG) - 7 * CHUNK)]
    d.handle(chunks(0)[7], 2.5)
    assert d.done and d.data == LOG and d.rerequests == 2


def test_a_vehicle_without_logs_or_that_stops_sending_is_an_error() -> None:
    d = LogDownloader()
    d.start(0.0)
    d.handle(LogEntry(0, 0, 0, 0), 0.0)
    assert d.done and d.error == "the vehicle has no log to download"
    d = LogDownloader(retry_s=1.0, attempts=2)
    d.start(0.0)
    d.handle(LogEntry(0, 1, 0, len(LOG)), 0.0)
    d.handle(chunks(0)[0], 0.1)
    d.tick(1.2)
    d.tick(2.3)
    assert d.done and d.error is not None and "stalled" in d.error and d.data is None


def vehicle_heartbeat(type_: int = 2, autopilot: int = 12) -> Heartbeat:
    return Heartbeat(
        sysid=1, compid=1, type=type_, autopilot=autopilot, base_mode=0, custom_mode=0, system_status=3
    )


def test_after_the_flight_the_fetch_waits_for_the_vehicle_then_downloads() -> None:
    f = LogFetch(connect_timeout_s=5.0)
    assert f.start(0.0) == []
    assert f.handle(vehicle_heartbeat(type_=6, autopilot=8), 0.1) == []  # another ground station
    assert f.tick(1.0) == []  # nothing is sent before the vehicle spoke
    assert f.handle(vehicle_heartbeat(), 1.2) == [GcsHeartbeat(), LogRequestList()]
    assert f.handle(LogEntry(0, 1, 0, len(LOG)), 1.3) == [LogRequestData(0, 0, 0xFFFFFFFF)]
    assert f.tick(2.25) == [GcsHeartbeat()]  # the link stays alive while the download runs
    out = []
    for c in chunks(0):
        out += f.handle(c, 2.4)
    assert out == [LogRequestEnd()]
    assert f.done and f.error is None and f.data == LOG


def test_a_fetch_without_a_vehicle_ends_in_an_error() -> None:
    f = LogFetch(connect_timeout_s=5.0)
    f.start(0.0)
    assert f.tick(4.9) == [] and not f.done
    f.tick(5.0)
    assert f.done and f.data is None
    assert f.error == "no vehicle heartbeat within 5 s"
