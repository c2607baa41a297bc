"""Stage 6 from a shared directory: the flight's finished ``.ulg`` (I/O edge).

The built-in simulator writes ``<dir>/<name>.ulg.part`` and renames it to ``<name>.ulg`` when the
log closes (disarm after arming, or SIGTERM): a ``.ulg`` directly in the directory is complete.
PX4 writes ``<dir>/<date>/<time>.ulg`` in place and closes it at disarm: a log in a subdirectory
counts as finished once its size has stopped changing for ``settle_s``.
"""

from __future__ import annotations

import time
from pathlib import Path

from uavtest.errors import InfrastructureError

__all__ = ["LogMissing", "has_log", "wait_for_log"]


class LogMissing(InfrastructureError):
    """The flight's log did not appear: a bench fault."""


def _stat(p: Path) -> tuple[float, int] | None:
    try:
        st = p.stat()
    except FileNotFoundError:  # renamed or removed under our feet
        return None
    return st.st_mtime, st.st_size


def _newest(log_dir: Path, since: float) -> tuple[Path, int] | None:
    best: tuple[float, str, Path, int] | None = None
    for p in log_dir.rglob("*.ulg"):
        st = _stat(p)
        if st is None or st[0] < since:
            continue
        if best is None or (st[0], p.name) > best[:2]:
            best = (st[0], p.name, p, st[1])
    return (best[2], best[3]) if best else None


def has_log(log_dir: Path, *, since: float = 0.0) -> bool:
    """Whether anything under ``log_dir`` is (becoming) a flight log: a ``.ulg`` or ``.ulg.part``
    modified at or after ``since``. PX4 creates its log at arming, the built-in simulator its
    ``.part`` at start: after a flight that armed, False means the log went somewhere else."""
    if not log_dir.is_dir():
        return False
    for pattern in ("*.ulg", "*.ulg.part"):
        for p in log_dir.rglob(pattern):
            st = _stat(p)
            if st is not None and st[0] >= since:
                return True
    return False


def wait_for_log(
    log_dir: Path,
    *,
    since: float = 0.0,
    timeout_s: float = 10.0,
    poll_s: float = 0.02,
    settle_s: float = 0.5,
) -> Path:
    """The newest finished ``.ulg`` under ``log_dir`` modified at or after ``since`` (epoch seconds).

    Waits up to ``timeout_s`` for it; raises LogMissing naming what was (not) found.
    """
    deadline = time.monotonic() + timeout_s
    growing: tuple[Path, int, float] | None = None  # a PX4 log being watched: path, size, since when
    while True:
        found = _newest(log_dir, since) if log_dir.is_dir() else None
        if found is not None:
            path, size = found
            if path.parent == log_dir:
                return path  # renamed from .part: complete
            now = time.monotonic()
            if growing is None or growing[0] != path or growing[1] != size:
                growing = (path, size, now)
            elif now - growing[2] >= settle_s:
                return path
        if time.monotonic() >= deadline:
            break
        time.sleep(poll_s)
    if growing is not None:
        raise LogMissing(f"log missing: {growing[0]} was still being written after {timeout_s:g} s")
    parts = sorted(p.name for p in log_dir.glob("*.ulg.part")) if log_dir.is_dir() else []
    if parts:
        raise LogMissing(
            f"log missing: the simulator did not finish {parts[-1]} in {log_dir} within {timeout_s:g} s"
        )
    raise LogMissing(f"log missing: no .ulg in {log_dir} after {timeout_s:g} s")
