"""Where each replica of a run is, from its Job and pods (pure).

An index is *finished* when the Job says so (``completedIndexes`` / ``failedIndexes``) or when the
Job itself ended (e.g. ``DeadlineExceeded``: unfinished indexes are then bench errors). Until
aggregation reads ``result.json``, the verdict of a finished index comes from the runner's exit
code, which the Job's ``podFailurePolicy`` already sorted: a completed index passed (exit 0); a
failed index failed (its last runner exit was 1) or ended in a bench error (anything else).
"""

from __future__ import annotations

from collections.abc import Iterable
from enum import StrEnum

from pydantic import BaseModel, ConfigDict

from uavtest.controller.jobs import RUNNER_EXIT_BAD_INPUT, RUNNER_EXIT_FAIL
from uavtest.controller.views import JobView, PodView

__all__ = ["Progress", "ReplicaProgress", "ReplicaState", "progress_of"]


class ReplicaState(StrEnum):
    PENDING = "pending"
    RUNNING = "running"
    PASSED = "pass"
    FAILED = "fail"
    ERROR = "error"


FINISHED = frozenset({ReplicaState.PASSED, ReplicaState.FAILED, ReplicaState.ERROR})


class ReplicaProgress(BaseModel):
    model_config = ConfigDict(frozen=True)

    index: int
    state: ReplicaState
    reason: str = ""
    attempts: int = 0  # pods created for this index so far
    duration: float | None = None  # seconds the runner ran, when it has finished


class Progress(BaseModel):
    """Every replica's state, and whether the run as a whole has finished flying."""

    model_config = ConfigDict(frozen=True)

    replicas: list[ReplicaProgress]
    finished: bool  # every index finished, or the Job ended
    finish_reason: str = ""  # "", "AllIndexesFinished", "DeadlineExceeded", "JobMissing"
    finish_message: str = ""

    def count(self, state: ReplicaState) -> int:
        return sum(r.state == state for r in self.replicas)


def _latest_by_index(pods: Iterable[PodView]) -> tuple[dict[int, PodView], dict[int, int]]:
    latest: dict[int, PodView] = {}
    attempts: dict[int, int] = {}
    for pod in pods:
        attempts[pod.index] = attempts.get(pod.index, 0) + 1
        current = latest.get(pod.index)
        if current is None or (pod.created, pod.name) > (current.created, current.name):
            latest[pod.index] = pod
    return latest, attempts


def _seconds_between(start: str | None, end: str | None) -> float | None:
    from datetime import datetime

    if not start or not end:
        return None
    try:
        a = datetime.fromisoformat(start.replace("Z", "+00:00"))
        b = datetime.fromisoformat(end.replace("Z", "+00:00"))
    except ValueError:
        return None
    return max((b - a).total_seconds(), 0.0)


def _failed_index(pod: PodView | None) -> tuple[ReplicaState, str]:
    if pod is None or pod.runner_exit is None:
        return ReplicaState.ERROR, "replica failed with no runner exit code (pod lost)"
    if pod.runner_exit == RUNNER_EXIT_FAIL:
        return ReplicaState.FAILED, ""
    if pod.runner_exit == RUNNER_EXIT_BAD_INPUT:
        return ReplicaState.ERROR, "runner rejected the test (exit 2)"
    why = f" ({pod.runner_reason})" if pod.runner_reason else ""
    return ReplicaState.ERROR, f"runner exit {pod.runner_exit}{why} on every attempt"


def _open_index(pod: PodView | None) -> ReplicaState:
    """An index the Job has not finished: running while its pod runs, or ended and awaits the Job's
    bookkeeping (Succeeded, or Failed with a verdict code); pending before, or when it will be retried."""
    if pod is None or pod.deleting:
        return ReplicaState.PENDING
    if pod.phase == "Running":
        return ReplicaState.RUNNING
    if pod.phase == "Succeeded" or (
        pod.phase == "Failed" and pod.runner_exit in (RUNNER_EXIT_FAIL, RUNNER_EXIT_BAD_INPUT)
    ):
        return ReplicaState.RUNNING
    return ReplicaState.PENDING


def progress_of(
    replicas: int, job: JobView | None, pods: Iterable[PodView], *, job_deleted: bool = False
) -> Progress:
    """Each index's state. ``job_deleted``: the Job was deleted (no Job is then an end, not a wait)."""
    latest, attempts = _latest_by_index(pods)
    if job is None:
        lost = job_deleted
        states = [
            ReplicaProgress(
                index=i,
                state=ReplicaState.ERROR if lost else ReplicaState.PENDING,
                reason="the Job was deleted before this replica finished" if lost else "",
            )
            for i in range(replicas)
        ]
        return Progress(
            replicas=states,
            finished=lost,
            finish_reason="JobMissing" if lost else "",
            finish_message="the replica Job disappeared" if lost else "",
        )
    out = []
    for i in range(replicas):
        pod = latest.get(i)
        duration = _seconds_between(pod.started_at, pod.finished_at) if pod else None
        if i in job.completed_indexes:
            state, reason = ReplicaState.PASSED, ""
        elif i in job.failed_indexes:
            state, reason = _failed_index(pod)
        elif job.terminal is not None:
            why = job.terminal_reason or job.terminal
            state, reason = ReplicaState.ERROR, f"the Job ended ({why}) before this replica finished"
        else:
            state, reason = _open_index(pod), ""
        out.append(
            ReplicaProgress(
                index=i, state=state, reason=reason, attempts=attempts.get(i, 0), duration=duration
            )
        )
    finished = job.terminal is not None or all(r.state in FINISHED for r in out)
    if not finished:
        return Progress(replicas=out, finished=False)
    if job.terminal_reason == "DeadlineExceeded":
        return Progress(
            replicas=out,
            finished=True,
            finish_reason="DeadlineExceeded",
            finish_message=job.terminal_message or "the Job's activeDeadlineSeconds passed",
        )
    return Progress(replicas=out, finished=True, finish_reason="AllIndexesFinished")
