"""The Kubernetes Events a finished run posts on its UavTest (pure: summary → events)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict

from uavtest.analysis.models import RunSummary, Verdict
from uavtest.controller.names import EventReason, Phase
from uavtest.engine.outcome import summary_line

__all__ = ["MAX_ERROR_EVENTS", "EventSpec", "events_for"]

MAX_ERROR_EVENTS = 5  # one ReplicaError event per errored replica, at most this many, then one in total


class EventSpec(BaseModel):
    model_config = ConfigDict(frozen=True)

    type: Literal["Normal", "Warning"]
    reason: str
    message: str


def events_for(summary: RunSummary, phase: Phase) -> list[EventSpec]:
    """TestPassed or TestFailed, FlakyTest when flaky, ReplicaError for replicas with bench errors."""
    line = summary_line(summary)
    out: list[EventSpec] = []
    if phase == Phase.SUCCEEDED:
        out.append(EventSpec(type="Normal", reason=EventReason.TEST_PASSED, message=line))
    else:
        out.append(
            EventSpec(type="Warning", reason=EventReason.TEST_FAILED, message=f"{phase.value}: {line}")
        )
    if summary.flaky:
        out.append(
            EventSpec(
                type="Warning",
                reason=EventReason.FLAKY_TEST,
                message=(
                    f"flakiness {summary.flakiness:.2f}: {summary.passed} passed, {summary.failed} failed"
                ),
            )
        )
    errors = [r for r in summary.results if r.verdict == Verdict.ERROR]
    for r in errors[:MAX_ERROR_EVENTS]:
        out.append(
            EventSpec(
                type="Warning",
                reason=EventReason.REPLICA_ERROR,
                message=f"replica {r.index} (seed {r.seed}): {r.reason or 'bench error'}"[:1024],
            )
        )
    if len(errors) > MAX_ERROR_EVENTS:
        out.append(
            EventSpec(
                type="Warning",
                reason=EventReason.REPLICA_ERROR,
                message=f"{len(errors) - MAX_ERROR_EVENTS} more replicas ended in bench errors",
            )
        )
    return out
