"""Stage 6 from a shared directory: the simulator's finished ``.ulg`` (I/O edge).

The simulator writes ``<name>.ulg.part`` and renames it to ``<name>.ulg`` when the log closes
(disarm after arming, or SIGTERM); the runner waits for the rename, with a deadline.
"""

from __future__ import annotations

import time
from pathlib import Path

from uavtest.errors import InfrastructureError

__all__ = ["LogMissing", "wait_for_log"]


class LogMissing(InfrastructureError):
    """The flight's log did not appear: a bench fault."""


def _newest(paths: list[Path]) -> Path | None:
    stamped = []
    for p in paths:
        try:
            stamped.append((p.stat().st_mtime, p.name, p))
        except FileNotFoundError:  # renamed or removed under our feet
            continue
    return max(stamped)[2] if stamped else None


def wait_for_log(log_dir: Path, *, since: float = 0.0, timeout_s: float = 10.0, poll_s: float = 0.02) -> Path:
    """The newest finished ``.ulg`` in ``log_dir`` modified at or after ``since`` (epoch seconds).

    Waits up to ``timeout_s`` for it; raises LogMissing naming what was (not) found.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        if log_dir.is_dir():
            done = [p for p in log_dir.glob("*.ulg") if _mtime(p) >= since]
            newest = _newest(done)
            if newest is not None:
                return newest
        if time.monotonic() >= deadline:
            break
        time.sleep(poll_s)
    parts = sorted(p.name for p in log_dir.glob("*.ulg.part")) if log_dir.is_dir() else []
    if parts:
        raise LogMissing(
            f"log missing: the simulator did not finish {parts[-1]} in {log_dir} within {timeout_s:g} s"
        )
    raise LogMissing(f"log missing: no .ulg in {log_dir} after {timeout_s:g} s")


def _mtime(p: Path) -> float:
    try:
        return p.stat().st_mtime
    except FileNotFoundError:
        return -1.0
