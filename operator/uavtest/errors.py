"""The error hierarchy of uavtest, translated to exit codes at one boundary (the CLI).

Every error a user can act on is a ``UavTestError`` subclass with a message that names
the file, the field, the value and what is allowed (or the missing path).
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Callable
from enum import IntEnum

__all__ = [
    "BadInput",
    "ExitCode",
    "InfrastructureError",
    "MissingFile",
    "UavTestError",
    "run_at_boundary",
]


class ExitCode(IntEnum):
    """Exit codes of every uavtest command."""

    PASS = 0  # every replica passed / the command succeeded
    FAIL = 1  # some replica failed: an assertion did not hold
    BAD_INPUT = 2  # the test file, a referenced file or a CLI argument is wrong
    INFRASTRUCTURE = 3  # only bench errors: simulator crashed, store unreachable, cluster down


class UavTestError(Exception):
    """Base of every error uavtest reports to a user."""

    exit_code: ExitCode = ExitCode.INFRASTRUCTURE


class BadInput(UavTestError):
    """The input is wrong: names where (file, field path), the value and what is allowed."""

    exit_code = ExitCode.BAD_INPUT

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        field: str | None = None,
        value: object = None,
        allowed: str | None = None,
    ) -> None:
        self.file = file
        self.field = field
        self.value = value
        self.allowed = allowed
        self.reason = message
        parts = []
        if file:
            parts.append(str(file))
        if field:
            parts.append(f"field '{field}'")
        where = ": ".join(parts)
        text = f"{where}: {message}" if where else message
        if value is not None:
            text += f" (got {value!r})"
        if allowed:
            text += f"; allowed: {allowed}"
        super().__init__(text)


class MissingFile(BadInput):
    """A file the user named (or a test file references) does not exist."""

    def __init__(self, path: str, *, referenced_from: str | None = None, field: str | None = None) -> None:
        self.path = str(path)
        msg = f"file not found: {path}"
        super().__init__(msg, file=referenced_from, field=field)


class InfrastructureError(UavTestError):
    """The bench failed, not the drone: a process died, a port was taken, a store is unreachable."""

    exit_code = ExitCode.INFRASTRUCTURE


def run_at_boundary(run: Callable[[], object], say: Callable[[str], None]) -> None:
    """The boundary of a command-line entry point: log to stderr at ``UAVTEST_LOG_LEVEL``, run,
    and turn a ``UavTestError`` into ``say("error: ...")`` and its exit code (Ctrl-C: 3)."""
    logging.basicConfig(
        level=os.environ.get("UAVTEST_LOG_LEVEL", "INFO").upper(),
        format="%(levelname)s: %(message)s",
        stream=sys.stderr,
    )
    try:
        run()
    except UavTestError as e:
        say(f"error: {e}")
        sys.exit(int(e.exit_code))
    except KeyboardInterrupt:
        say("interrupted")
        sys.exit(int(ExitCode.INFRASTRUCTURE))
