"""The timed commands of a test: inline ``commands`` plus those of ``commandsFile``, by time."""

from __future__ import annotations

from pathlib import Path

from uavtest.spec.commands_csv import read_commands_csv
from uavtest.spec.models import Command, UavTestSpec

__all__ = ["resolved_commands"]


def resolved_commands(spec: UavTestSpec) -> list[Command]:
    """Every command of ``spec`` sorted by vehicle time (stable: equal times keep their order).

    ``commandsFile`` is read relative to the current folder (``load_test`` has inlined it
    already for tests loaded from files).
    """
    commands = list(spec.commands)
    if spec.commands_file is not None:
        commands += read_commands_csv(Path(spec.commands_file))
    return sorted(commands, key=lambda c: c.at)
