"""Starting a replica's processes: a plain exec, or a fork of a warm ``uavtest`` process.

A ``uavtest runner`` or ``uavtest sitl`` process spends most of its start-up importing numpy,
pydantic and pymavlink — about as long as flying a whole competition mission in lockstep. The
``WarmLauncher`` starts one multiprocessing fork server that has imported them once; each
``python -m uavtest.engine.entry ...`` command (the replica processes' own entry point, see
``uavtest.engine.entry``) is then a fresh process forked from it, in its own session, with its own
stdin/stdout/stderr, running exactly the same entry point with the same arguments. Anything
else (PX4's binary, test doubles) is exec'd with ``subprocess``. Both kinds of process are
handled through the ``Started`` protocol (a subset of ``Popen``).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import multiprocessing.connection
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path
from typing import Protocol

__all__ = [
    "ENTRY_MODULE",
    "PRELOAD",
    "ExecLauncher",
    "Launcher",
    "Started",
    "WarmLauncher",
    "is_uavtest_cli",
    "start_exec",
]

# What a warm process imports before forking: the hot path of both replica processes.
# Not uavtest.cli: when the engine runs as ``python -m uavtest.cli``, each child re-runs that
# module as ``__mp_main__`` and runpy warns if it is already imported.
PRELOAD = [
    "typer",
    "uavtest.engine.entry",
    "uavtest.engine.launch",
    "uavtest.runner.main",
    "uavtest.sitl.main",
    "uavtest.engine.prefork",  # last: what the imports leave for each process to do once
]
ENTRY_MODULE = "uavtest.engine.entry"  # what a warm process runs (never uavtest.cli)


PR_SET_PDEATHSIG = 1  # linux/prctl.h

#: multiprocessing's bookkeeping of a process's children is not meant for threads: every
#: ``WarmLauncher`` of this process (one per test flown side by side) starts and reaps under it
_CHILDREN_LOCK = threading.Lock()


class Started(Protocol):
    """A started process: ``subprocess.Popen`` or a forked warm process."""

    @property
    def pid(self) -> int: ...

    def poll(self) -> int | None: ...

    def wait(self, timeout: float | None = None) -> int: ...


class Launcher(Protocol):
    """Starts one command with stdout / stderr appended to files."""

    def start(
        self,
        argv: list[str],
        *,
        stdout: Path | None,
        stderr: Path,
        cwd: Path | None = None,
        env: dict[str, str] | None = None,
    ) -> Started: ...


def _open_append(path: Path | None) -> int:
    if path is None:
        return os.open(os.devnull, os.O_WRONLY)
    return os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)


def start_exec(
    argv: list[str],
    *,
    stdout: Path | None,
    stderr: Path,
    cwd: Path | None = None,
    env: dict[str, str] | None = None,
) -> Started:
    """exec ``argv`` in its own session; stdout/stderr appended to the files (None: discarded)."""
    out, err = _open_append(stdout), _open_append(stderr)
    try:
        return subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=err,
            cwd=cwd,
            env=env,
            start_new_session=True,
        )
    finally:
        os.close(out)
        os.close(err)


class ExecLauncher:
    """Every command exec'd with ``subprocess`` (cold start-up each time).

    ``environ``: the environment of the uavtest processes it starts (``engine.bytecode``); None
    inherits this one. Other commands (PX4) get their own ``env`` or inherit.
    """

    def __init__(self, environ: dict[str, str] | None = None) -> None:
        self._environ = environ

    def start(
        self,
        argv: list[str],
        *,
        stdout: Path | None,
        stderr: Path,
        cwd: Path | None = None,
        env: dict[str, str] | None = None,
    ) -> Started:
        if env is None and self._environ is not None and is_uavtest_cli(argv):
            env = self._environ
        return start_exec(argv, stdout=stdout, stderr=stderr, cwd=cwd, env=env)


def is_uavtest_cli(argv: list[str]) -> bool:
    """``[python, -m, uavtest.engine.entry, ...]``: a command a warm process can run."""
    return len(argv) >= 3 and argv[1:3] == ["-m", ENTRY_MODULE]


def _die_with_parent() -> None:
    """Linux: SIGTERM this process when its parent (the fork server) ends.

    The fork server ends when the engine does, even when the engine is killed, so no
    simulator is left waiting for lockstep grants that will never come.
    """
    if sys.platform.startswith("linux"):
        import ctypes

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    # Each child inherits the fork server's "engine alive" pipe end; the server only notices
    # the engine is gone once no one holds it, so a replica process must not keep it open.
    from multiprocessing import forkserver

    server = getattr(forkserver, "_forkserver", None)
    alive = getattr(server, "_forkserver_alive_fd", None)
    if isinstance(alive, int):
        with contextlib.suppress(OSError):
            os.close(alive)
        server._forkserver_alive_fd = None  # type: ignore[union-attr]


def _run_cli(args: list[str], stdout: str | None, stderr: str, cwd: str | None) -> None:
    """In the forked process: own session and files, then the replica entry point."""
    os.setsid()
    _die_with_parent()
    fds = (
        os.open(os.devnull, os.O_RDONLY),
        _open_append(Path(stdout) if stdout else None),
        _open_append(Path(stderr)),
    )
    for target, fd in enumerate(fds):
        os.dup2(fd, target)
        os.close(fd)
    if cwd:
        os.chdir(cwd)
    sys.argv = ["uavtest", *args]
    from uavtest.engine.entry import main

    main()


class _Forked:
    """A forked warm process seen as a ``Popen``: pid, poll, wait (TimeoutExpired on timeout).

    Its exit status arrives once, over a pipe from the fork server; reading it (``poll``) is
    serialized with the launcher's lock, because ``Process.start`` polls every child too.
    """

    def __init__(
        self, process: multiprocessing.process.BaseProcess, argv: list[str], lock: threading.Lock
    ) -> None:
        self._process = process
        self._lock = lock
        self.args = argv
        pid = process.pid
        assert pid is not None
        self.pid = pid

    @property
    def returncode(self) -> int | None:
        return self.poll()

    def poll(self) -> int | None:
        with self._lock:
            return self._process.exitcode

    def wait(self, timeout: float | None = None) -> int:
        multiprocessing.connection.wait([self._process.sentinel], timeout)
        code = self.poll()
        if code is None:
            raise subprocess.TimeoutExpired(self.args, timeout or 0.0)
        return code


class WarmLauncher:
    """Forks ``uavtest`` CLI commands from a fork server that has imported the hot path once.

    The fork server starts with the first command (one import, ~1 s) and ends with this
    process. Commands that are not ``python -m uavtest.engine.entry`` are exec'd.
    """

    def __init__(self, preload: list[str] | None = None) -> None:
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload(list(PRELOAD if preload is None else preload))
        self._lock = _CHILDREN_LOCK

    def warm(self) -> None:
        """Start the fork server now (it imports in the background) instead of at the first fork."""
        import multiprocessing.forkserver

        multiprocessing.forkserver.ensure_running()

    def start(
        self,
        argv: list[str],
        *,
        stdout: Path | None,
        stderr: Path,
        cwd: Path | None = None,
        env: dict[str, str] | None = None,
    ) -> Started:
        if env is not None or not is_uavtest_cli(argv):
            return start_exec(argv, stdout=stdout, stderr=stderr, cwd=cwd, env=env)
        process = self._context.Process(
            target=_run_cli,
            args=(argv[3:], str(stdout) if stdout else None, str(stderr), str(cwd) if cwd else None),
            daemon=False,
        )
        with self._lock:  # multiprocessing's bookkeeping of children is not meant for threads
            process.start()
        return _Forked(process, argv, self._lock)
