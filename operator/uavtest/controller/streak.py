"""How many runs of a test in a row have failed: the count behind "a test failing N runs in a row".

Kept runs alone cannot answer it (history limits trim failed and passed runs apart), so the
test's status carries the count and the newest run it has counted; each status update adds the
runs that finished since, in completion order. A failed run adds one, a passing run resets the
count to 0, a run that ended in bench errors (``Error``: nothing was judged) leaves it unchanged.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from datetime import datetime

from uavtest.spec.status import Phase

__all__ = ["Finished", "failure_streak"]


@dataclass(frozen=True, slots=True)
class Finished:
    """A finished run: its name, when it completed and how it ended."""

    name: str
    completed: datetime
    phase: Phase


def failure_streak(
    finished: Iterable[Finished], streak: int, counted: tuple[datetime, str] | None
) -> tuple[int, tuple[datetime, str] | None]:
    """The failure streak after the runs that finished after ``counted`` (completion time, name),
    and the newest run now counted."""
    key = counted
    for run in sorted(finished, key=lambda r: (r.completed, r.name)):
        if counted is not None and (run.completed, run.name) <= counted:
            continue
        if run.phase == Phase.FAILED:
            streak += 1
        elif run.phase == Phase.SUCCEEDED:
            streak = 0
        key = (run.completed, run.name)
    return streak, key
