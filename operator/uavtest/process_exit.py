"""How uavtest's command-line processes end: without the interpreter's teardown.

By the time a command returns it has closed its files and stored or printed its result. What
the interpreter's teardown still does after that is free every module's objects one by one:
numpy, pydantic, pymavlink, rich and matplotlib, about 0.45 s of a 4 s ``uavtest run`` on a
2-core machine and tens of milliseconds on a replica's clock. ``end_process`` does what a
normal exit owes the user first (waits for non-daemon threads as the interpreter does, runs the
exit handlers: logging, multiprocessing's children, temporary directories; flushes the standard
streams), then ends the process with ``os._exit``.

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
    """What a normal exit does before the teardown, then exit with ``code``: wait for the
    non-daemon threads and run the exit handlers (``logging.shutdown`` among them)."""
    main = threading.main_thread()
    for thread in threading.enumerate():
        if thread is not main and not thread.daemon:
            thread.join()
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
