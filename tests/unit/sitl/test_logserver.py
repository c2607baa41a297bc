"""The MAVLink log protocol over the simulator's finished logs, with PX4's answers."""

from __future__ import annotations

from pathlib import Path

from uavtest.sitl.logserver import CHUNK, LogServer
from uavtest.sitl.mav import Msg


def server(tmp_path: Path, *sizes: int) -> tuple[LogServer, list[bytes]]:
    files, contents = [], []
    for i, size in enumerate(sizes):
        data = bytes((i * 7 + k) % 251 for k in range(size))
        path = tmp_path / f"seed0-{i + 1}.ulg"
        path.write_bytes(data)
        files.append(path)
        contents.append(data)
    return LogServer(lambda: files, batch=4), contents


def drain(s: LogServer) -> list[Msg]:
    out: list[Msg] = []
    while s.streaming:
        batch = s.next_batch()
        assert 0 < len(batch) <= s.batch
        out += batch
    return out


def test_no_log_yet_is_one_entry_saying_none(tmp_path: Path) -> None:
    s, _ = server(tmp_path)
    [entry] = s.handle(Msg("LOG_REQUEST_LIST", {"start": 0, "end": 0xFFFF})) or []
    assert entry.name == "LOG_ENTRY" and entry.get("num_logs") == 0


def test_logs_are_listed_with_zero_based_ids_and_their_sizes(tmp_path: Path) -> None:
    s, _ = server(tmp_path, 1000, 250)
    entries = s.handle(Msg("LOG_REQUEST_LIST", {"start": 0, "end": 0xFFFF})) or []
    assert [(e.get("id"), e.get("num_logs"), e.get("last_log_num"), e.get("size")) for e in entries] == [
        (0, 2, 1, 1000),
        (1, 2, 1, 250),
    ]
    only_last = s.handle(Msg("LOG_REQUEST_LIST", {"start": 1, "end": 1})) or []
    assert [e.get("id") for e in only_last] == [1]


def test_a_whole_log_streams_in_90_byte_chunks_ending_with_a_short_one(tmp_path: Path) -> None:
    s, contents = server(tmp_path, 1000, 250)
    assert s.handle(Msg("LOG_REQUEST_DATA", {"id": 1, "ofs": 0, "count": 0xFFFFFFFF})) == []
    chunks = drain(s)
    assert [c.get("ofs") for c in chunks] == [0, 90, 180]
    assert [c.get("count") for c in chunks] == [90, 90, 70]
    assert b"".join(c.get("data")[: c.get("count")] for c in chunks) == contents[1]
    assert all(len(c.get("data")) == CHUNK and c.get("id") == 1 for c in chunks)


def test_a_hole_is_served_from_its_offset_for_its_count_only(tmp_path: Path) -> None:
    s, contents = server(tmp_path, 1000)
    s.handle(Msg("LOG_REQUEST_DATA", {"id": 0, "ofs": 450, "count": 180}))
    chunks = drain(s)
    assert [(c.get("ofs"), c.get("count")) for c in chunks] == [(450, 90), (540, 90)]
    assert chunks[1].get("data") == contents[0][540:630]
    s.handle(Msg("LOG_REQUEST_DATA", {"id": 0, "ofs": 2000, "count": 90}))  # past the end
    assert [c.get("count") for c in drain(s)] == [0]


def test_an_unknown_log_is_ignored_and_log_request_end_stops_the_stream(tmp_path: Path) -> None:
    s, _ = server(tmp_path, 1000)
    assert s.handle(Msg("LOG_REQUEST_DATA", {"id": 5, "ofs": 0, "count": 90})) == []
    assert not s.streaming
    s.handle(Msg("LOG_REQUEST_DATA", {"id": 0, "ofs": 0, "count": 1000}))
    assert len(s.next_batch()) == 4 and s.streaming
    assert s.handle(Msg("LOG_REQUEST_END")) == []
    assert not s.streaming and s.next_batch() == []
    assert s.handle(Msg("HEARTBEAT")) is None  # not the log protocol: the vehicle's


def test_the_log_list_is_the_log_folder_with_real_dates(tmp_path):
    """As PX4's log handler: every finished log in the folder (earlier runs, PX4's dated
    subfolders), oldest first, LOG_ENTRY.time_utc the log's date; a .part is not listed."""
    import os
    from datetime import UTC, datetime

    from uavtest.sitl.logserver import LogServer, log_folder
    from uavtest.sitl.mav import Msg

    px4 = tmp_path / "2025-03-04" / "10_20_30.ulg"
    px4.parent.mkdir()
    px4.write_bytes(b"U" * 10)
    earlier = tmp_path / "seed1-1.ulg"
    earlier.write_bytes(b"U" * 20)
    os.utime(earlier, (1_763_000_000, 1_763_000_000))
    (tmp_path / "seed2-1.ulg.part").write_bytes(b"U")
    entries = LogServer(log_folder(tmp_path)).handle(Msg("LOG_REQUEST_LIST", {"start": 0, "end": 0xFFFF}))
    assert [(e.fields["id"], e.fields["size"], e.fields["num_logs"]) for e in entries] == [
        (0, 10, 2),
        (1, 20, 2),
    ]
    assert entries[0].fields["time_utc"] == int(datetime(2025, 3, 4, 10, 20, 30, tzinfo=UTC).timestamp())
    assert entries[1].fields["time_utc"] == 1_763_000_000
    empty = LogServer(log_folder(tmp_path / "absent")).handle(Msg("LOG_REQUEST_LIST", {"start": 0, "end": 9}))
    assert empty[0].fields["num_logs"] == 0
