"""Stage 6 from a shared directory: the finished .ulg, never the .part being written."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from uavtest.runner.logdir import LogMissing, has_log, wait_for_log


def test_the_newest_finished_log_is_taken(tmp_path: Path) -> None:
    old = tmp_path / "old.ulg"
    old.write_bytes(b"old")
    os.utime(old, (1000, 1000))
    (tmp_path / "flight.ulg").write_bytes(b"new")
    (tmp_path / "next.ulg.part").write_bytes(b"partial")
    assert wait_for_log(tmp_path, since=2000, timeout_s=1).name == "flight.ulg"


def test_the_runner_waits_for_the_rename(tmp_path: Path) -> None:
    part = tmp_path / "2024-01-01_00_00_00.ulg.part"
    part.write_bytes(b"ULog")
    started = threading.Event()

    def close_log() -> None:
        started.wait(5)
        part.rename(tmp_path / "2024-01-01_00_00_00.ulg")

    t = threading.Thread(target=close_log)
    t.start()
    started.set()
    try:
        assert wait_for_log(tmp_path, timeout_s=10).name == "2024-01-01_00_00_00.ulg"
    finally:
        t.join()


def test_an_unfinished_log_is_named_in_the_error(tmp_path: Path) -> None:
    (tmp_path / "seed-7.ulg.part").write_bytes(b"ULog")
    with pytest.raises(LogMissing, match=r"did not finish seed-7\.ulg\.part"):
        wait_for_log(tmp_path, timeout_s=0.05)


def test_no_log_at_all_is_a_bench_error(tmp_path: Path) -> None:
    with pytest.raises(LogMissing, match=r"no \.ulg in"):
        wait_for_log(tmp_path / "missing", timeout_s=0.05)


def test_a_px4_log_in_a_dated_folder_is_taken_once_it_stops_growing(tmp_path: Path) -> None:
    dated = tmp_path / "log" / "2024-05-01"
    dated.mkdir(parents=True)
    log = dated / "12_00_00.ulg"
    log.write_bytes(b"ULog" * 100)
    assert wait_for_log(tmp_path / "log", timeout_s=10, settle_s=0.1) == log


def test_a_px4_log_that_keeps_growing_is_not_taken(tmp_path: Path) -> None:
    dated = tmp_path / "2024-05-01"
    dated.mkdir()
    log = dated / "12_00_00.ulg"
    stop = threading.Event()

    def keep_writing() -> None:
        with log.open("ab") as f:
            while not stop.is_set():
                f.write(b"x" * 64)
                f.flush()
                stop.wait(0.01)

    t = threading.Thread(target=keep_writing)
    t.start()
    try:
        with pytest.raises(LogMissing, match="still being written"):
            wait_for_log(tmp_path, timeout_s=0.5, settle_s=0.3)
    finally:
        stop.set()
        t.join()


def test_has_log_sees_a_log_being_written_and_ignores_older_ones(tmp_path: Path) -> None:
    assert not has_log(tmp_path / "missing")
    assert not has_log(tmp_path)
    old = tmp_path / "log" / "2026-01-01" / "old.ulg"
    old.parent.mkdir(parents=True)
    old.write_bytes(b"ULog")
    os.utime(old, (1000.0, 1000.0))
    assert has_log(tmp_path) and not has_log(tmp_path, since=2000.0)
    (tmp_path / "flight.ulg.part").write_bytes(b"ULog")  # the built-in simulator's, still open
    assert has_log(tmp_path, since=2000.0)
