"""A `uavtest sitl` process for one test: started, and stopped however the test ends."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path


def free_running_argv(port: int, log_dir: Path, speed_factor: float) -> list[str]:
    """`uavtest sitl` running free at ``speed_factor`` with its API link on ``port`` (for MAVSDK)."""
    return [
        *(sys.executable, "-m", "uavtest.cli", "sitl", "--speed-factor", str(speed_factor)),
        *("--api-port", str(port), "--api-local-port", "0", "--gcs-local-port", "0"),
        *("--log-dir", str(log_dir)),
    ]


def stop_process(
    proc: subprocess.Popen, *, graceful: bool = True, timeout: float = 10.0, sig: int = signal.SIGTERM
) -> None:
    """End ``proc`` if it still runs: ``sig`` (SIGTERM) and ``timeout`` s to exit, then SIGKILL
    (``graceful=False``: SIGKILL at once)."""
    if proc.poll() is not None:
        return
    if graceful:
        proc.send_signal(sig)
        try:
            proc.wait(timeout)
            return
        except subprocess.TimeoutExpired:
            pass
    proc.kill()
    proc.wait()


@contextmanager
def running_sitl(
    argv: Sequence[str], *, env: Mapping[str, str] | None = None, graceful: bool = True
) -> Iterator[subprocess.Popen]:
    """Run ``argv`` (a `uavtest sitl` command line) for the ``with`` block; yields the Popen and
    stops it on the way out (see `stop_process`)."""
    proc = subprocess.Popen(list(argv), env=None if env is None else dict(env))
    try:
        yield proc
    finally:
        stop_process(proc, graceful=graceful)


def eventually(condition: Callable[[], bool], seconds: float, what: str) -> None:
    """Poll ``condition`` every 50 ms; AssertionError when it is still false after ``seconds``."""
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)
