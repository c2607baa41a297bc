"""Stage 6 from a shared directory: the finished .ulg, never the .part being written."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from uavtest.runner.logdir import LogMissing, wait_for_log


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
