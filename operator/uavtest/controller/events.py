"""The Kubernetes Events a finished run posts on its UavTest (pure: summary → events)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict

from uavtest.analysis.models import RunSummary, Verdict
from uavtest.controller.names import EventReason, Phase
from uavtest.engine.outcome import run_warnings, summary_line

__all__ = ["MAX_LISTED", "EventSpec", "events_for"]

MAX_LISTED = 3  # one ReplicaError event per run lists the first few errored replicas and their reasons


class EventSpec(BaseModel):
    model_config = ConfigDict(frozen=True)

    type: Literal["Normal", "Warning"]
    reason: str
    message: str


def events_for(summary: RunSummary, phase: Phase) -> list[EventSpec]:
    """TestPassed or TestFailed, FlakyTest when flaky, one ReplicaError when replicas had bench errors,
    one SimulatorLimits when the simulator could not simulate part of the test."""
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
    if errors:
        listed = [
            f"replica {r.index} (seed {r.seed}): {r.reason or 'bench error'}" for r in errors[:MAX_LISTED]
        ]
        more = f"; and {len(errors) - MAX_LISTED} more" if len(errors) > MAX_LISTED else ""
        message = f"{len(errors)} of {summary.replicas} replicas had bench errors: {'; '.join(listed)}{more}"
        out.append(EventSpec(type="Warning", reason=EventReason.REPLICA_ERROR, message=message[:1024]))
    limits = run_warnings(summary)
    if limits:
        out.append(
            EventSpec(type="Warning", reason=EventReason.SIMULATOR_LIMITS, message="; ".join(limits)[:1024])
        )
    return out
