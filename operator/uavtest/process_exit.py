"""How uavtest's command-line processes end: without the interpreter's teardown.

By the time a command returns it has closed its files and stored or printed its result. What
the interpreter's teardown still does after that is free every module's objects one by one:
numpy, pydantic, pymavlink, rich and matplotlib, about 0.45 s of a 4 s ``uavtest run`` on a
2-core machine and tens of milliseconds on a replica's clock. ``end_process`` does what a
normal exit owes the user first (runs the exit handlers: logging, multiprocessing's children,
temporary directories; flushes the standard streams), then ends the process with ``os._exit``;
while a non-daemon thread still runs it leaves the exit to the interpreter, which waits for it.

Only process entry points end this way: the console script (``uavtest.cli.script``) with
``run_then_end``; a replica's runner and simulator (``uavtest.engine.entry.main``) with
``flush_and_exit`` after ``logging.shutdown`` alone, as they did since stop 40: nothing of theirs
waits on a thread or an exit handler. Code run in-process (tests, a caller's ``main()``) sees
``SystemExit`` as always.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import sys
import threading
from collections.abc import Callable
from typing import NoReturn

__all__ = ["end_process", "exit_status", "flush_and_exit", "run_then_end"]


def exit_status(code: object) -> int:
    """``sys.exit``'s argument as the process's status: None 0, a message 1 (printed), else int."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1


def flush_and_exit(code: int) -> NoReturn:
    """Flush the standard streams and exit with ``code`` at once."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):
            stream.flush()
    os._exit(code)


def end_process(code: int) -> NoReturn:
    """Run the exit handlers (``logging.shutdown`` among them), flush, and exit with ``code``.

    While another non-daemon thread still runs, a normal exit instead (``SystemExit``): the
    interpreter first tells executors to stop their idle workers, then waits for every such
    thread, which a process ending here could only imitate with the threading module's internals.
    """
    main = threading.main_thread()
    if any(t is not main and not t.daemon and t.is_alive() for t in threading.enumerate()):
        sys.exit(code)
    atexit._run_exitfuncs()
    flush_and_exit(code)


def run_then_end(main: Callable[[], object]) -> NoReturn:
    """Run an entry point that ends by ``SystemExit`` or by returning, then ``end_process``."""
    try:
        main()
        code = 0
    except SystemExit as e:
        code = exit_status(e.code)
    end_process(code)
