"""A UavTest's status from its children (pure): ``status_from(test, job, pods, ...) -> UavTestStatus``.

While replicas fly, the counts come from the Job and its pods (see ``progress``); once every index
has finished, the operator aggregates the run and ``status_from(..., summary=...)`` gives the final
status from ``summary.json``'s numbers. Conditions (metav1 shape) GitOps tools wait on:

============  ==========================================  =========================================
type          while running                               final
============  ==========================================  =========================================
Complete      False ReplicasPending / ReplicasRunning /   True Aggregated
              Aggregating / StoreUnavailable
Succeeded     Unknown (same reason)                       True AllReplicasPassed, or False with the
                                                          reason of Failed
Failed        Unknown (same reason)                       True ReplicasFailed / BenchErrors /
                                                          OnlyBenchErrors, or False AllReplicasPassed
Flaky         Unknown (same reason)                       True FlakyReplicas / False StableReplicas
============  ==========================================  =========================================

``phase`` is derived from these (and maps to the exit codes of ``uavtest run``: Succeeded 0,
Failed 1, Error 3). ``lastTransitionTime`` of a condition changes only when its status flips.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from datetime import UTC, datetime
from typing import Any, Protocol

from pydantic import ValidationError

from uavtest.analysis.flakiness import flakiness as flakiness_of
from uavtest.analysis.models import RunSummary, Verdict
from uavtest.controller.names import ConditionReason, ConditionType, Phase, Reason
from uavtest.controller.progress import FINISHED, Progress, ReplicaState, progress_of
from uavtest.controller.views import JobView, PodView, RunView
from uavtest.engine.outcome import exit_code, run_warnings, summary_line
from uavtest.errors import ExitCode
from uavtest.spec.status import (
    Artifacts,
    Condition,
    ConditionStatus,
    ReplicaStatus,
    ReplicaVerdict,
    UavTestStatus,
    compact_results,
)
from uavtest.store.layout import AVERAGE, PLOT, SUMMARY, aggregate_key, run_prefix

__all__ = [
    "artifacts_for",
    "awaiting_aggregation",
    "is_final",
    "kstatus_conditions",
    "phase_of",
    "run_counts",
    "run_status",
    "set_condition",
    "status_from",
]

_STATE_VERDICT = {
    ReplicaState.PASSED: ReplicaVerdict.PASS,
    ReplicaState.FAILED: ReplicaVerdict.FAIL,
    ReplicaState.ERROR: ReplicaVerdict.ERROR,
}


def _condition(status: Mapping[str, Any], type_: str) -> Mapping[str, Any] | None:
    for cond in status.get("conditions") or []:
        if cond.get("type") == type_:
            return cond
    return None


def is_final(status: Mapping[str, Any]) -> bool:
    """The run is over and aggregated: ``Complete`` is True."""
    cond = _condition(status, ConditionType.COMPLETE)
    return cond is not None and cond.get("status") == ConditionStatus.TRUE


def awaiting_aggregation(status: Mapping[str, Any]) -> bool:
    """Every index finished, aggregate/ not written yet (or the store was unreachable last time)."""
    cond = _condition(status, ConditionType.COMPLETE)
    return (
        cond is not None
        and cond.get("status") == ConditionStatus.FALSE
        and cond.get("reason") in {Reason.AGGREGATING, Reason.STORE_UNAVAILABLE}
    )


def set_condition(
    conditions: list[Condition],
    type_: str,
    status: ConditionStatus,
    reason: str,
    message: str,
    *,
    generation: int,
    now: datetime,
) -> list[Condition]:
    """``conditions`` with ``type_`` set; its lastTransitionTime kept unless its status flips."""
    old = next((c for c in conditions if c.type == type_), None)
    since = old.last_transition_time if old is not None and old.status == status else now
    new = Condition(
        type=type_,
        status=status,
        reason=reason,
        message=message,
        observed_generation=generation,
        last_transition_time=since,
    )
    return [*(c for c in conditions if c.type != type_), new]


def kstatus_conditions(
    conditions: list[Condition],
    passed: bool | None,
    reason: str,
    message: str,
    *,
    generation: int,
    now: datetime,
) -> list[Condition]:
    """``Ready`` / ``Reconciling`` / ``Stalled`` as kstatus (Flux, ``kstatus``) reads them.

    ``passed`` None: in progress (Reconciling True → InProgress); True: Ready True, the others False
    (→ Current); False: Stalled True (→ Failed). Reconciling and Stalled are "abnormal-true": they
    are False, not absent, when the run is not in that state.
    """
    true, false = ConditionStatus.TRUE, ConditionStatus.FALSE
    for type_, status in (
        (ConditionType.READY, true if passed else false),
        (ConditionType.RECONCILING, true if passed is None else false),
        (ConditionType.STALLED, true if passed is False else false),
    ):
        conditions = set_condition(conditions, type_, status, reason, message, generation=generation, now=now)
    return conditions


def artifacts_for(store_url: str, test: RunView, *, with_trajectories: bool) -> Artifacts:
    """URIs of the run's prefix and aggregate files in the store."""
    base = store_url.rstrip("/")

    def uri(key: str) -> str:
        return f"{base}/{key}"

    prefix = uri(run_prefix(test.namespace, test.test, test.run_id))
    return Artifacts(
        store=prefix,
        summary=uri(aggregate_key(test.namespace, test.test, test.run_id, SUMMARY)),
        average=uri(aggregate_key(test.namespace, test.test, test.run_id, AVERAGE))
        if with_trajectories
        else None,
        plot=uri(aggregate_key(test.namespace, test.test, test.run_id, PLOT)) if with_trajectories else None,
    )


def phase_of(summary: RunSummary) -> tuple[Phase, str]:
    """Final phase and reason, matching ``uavtest run``'s exit code (0 / 1 / 3)."""
    code = exit_code(summary)
    if code == ExitCode.PASS:
        return Phase.SUCCEEDED, ConditionReason.ALL_PASSED
    if code == ExitCode.FAIL:
        return Phase.FAILED, ConditionReason.SOME_FAILED
    if summary.passed == 0:
        return Phase.ERROR, ConditionReason.ONLY_ERRORS
    return Phase.ERROR, Reason.BENCH_ERRORS


def run_status(run: RunView) -> UavTestStatus:
    """The run's ``.status`` as the model; an empty status when it has none or it is unreadable."""
    try:
        return UavTestStatus.model_validate(run.status)
    except ValidationError:
        return UavTestStatus()


class _Counts(Protocol):
    passed: int
    failed: int
    errors: int
    flakiness: float | None
    flaky: bool


def run_counts(outcome: _Counts) -> dict[str, Any]:
    """A run's counters (passed, failed, errors, flakiness, flaky) from its summary or status, as
    keyword arguments for the status models that repeat them (``UavTestStatus``, ``LastRun``)."""
    return {
        "passed": outcome.passed,
        "failed": outcome.failed,
        "errors": outcome.errors,
        "flakiness": outcome.flakiness,
        "flaky": outcome.flaky,
    }


def _parse_time(text: str | None) -> datetime | None:
    if not text:
        return None
    try:
        return datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return None


def _running_status(
    test: RunView,
    progress: Progress,
    previous: UavTestStatus,
    job: JobView | None,
    *,
    store_url: str,
    now: datetime,
    aggregation_error: str | None,
) -> UavTestStatus:
    passed = progress.count(ReplicaState.PASSED)
    failed = progress.count(ReplicaState.FAILED)
    errors = progress.count(ReplicaState.ERROR)
    running = progress.count(ReplicaState.RUNNING)
    pending = progress.count(ReplicaState.PENDING)
    if aggregation_error is not None:
        reason, message = Reason.STORE_UNAVAILABLE, f"aggregation will be retried: {aggregation_error}"
    elif progress.finished:
        reason = Reason.AGGREGATING
        message = progress.finish_message or "every replica finished; aggregating"
    elif running:
        reason, message = ConditionReason.RUNNING, f"{running} running, {pending} pending"
    else:
        reason, message = ConditionReason.PENDING, f"{pending} pending"
    gen = test.generation
    conds = list(previous.conditions)
    conds = set_condition(
        conds, ConditionType.COMPLETE, ConditionStatus.FALSE, reason, message, generation=gen, now=now
    )
    for type_ in (ConditionType.SUCCEEDED, ConditionType.FAILED, ConditionType.FLAKY):
        conds = set_condition(conds, type_, ConditionStatus.UNKNOWN, reason, message, generation=gen, now=now)
    conds = kstatus_conditions(conds, None, reason, message, generation=gen, now=now)
    finished = [
        ReplicaStatus(
            index=r.index,
            seed=test.seed + r.index,
            verdict=_STATE_VERDICT[r.state],
            reason=r.reason[:256],
        )
        for r in progress.replicas
        if r.state in FINISHED
    ]
    results, omitted = compact_results(finished)
    started = running + passed + failed + errors > 0 or progress.finished
    f = flakiness_of(passed, failed)
    return UavTestStatus(
        phase=Phase.RUNNING if started else Phase.PENDING,
        replicas=test.replicas,
        pending=pending,
        running=running,
        passed=passed,
        failed=failed,
        errors=errors,
        flakiness=f,
        flaky=f is not None and 0.0 < f < 1.0,
        run_id=test.run_id,
        start_time=_parse_time(job.start_time if job else None) or previous.start_time,
        observed_generation=gen,
        message=f"{passed} passed · {failed} failed · {errors} error · {running} running · {pending} pending",
        artifacts=Artifacts(store=artifacts_for(store_url, test, with_trajectories=False).store),
        conditions=conds,
        results=results,
        results_omitted=omitted,
    )


def _final_status(
    test: RunView,
    progress: Progress,
    previous: UavTestStatus,
    job: JobView | None,
    summary: RunSummary,
    *,
    store_url: str,
    now: datetime,
) -> UavTestStatus:
    phase, reason = phase_of(summary)
    gen = test.generation
    line = summary_line(summary)
    ok = phase == Phase.SUCCEEDED
    flaky_note = f"flakiness {summary.flakiness:.2f}" if summary.flakiness is not None else "no valid replica"
    flaky_reason = ConditionReason.FLAKY if summary.flaky else ConditionReason.STABLE
    true, false = ConditionStatus.TRUE, ConditionStatus.FALSE
    conds = list(previous.conditions)
    for ctype, cstatus, creason, message in (
        (ConditionType.COMPLETE, true, Reason.AGGREGATED, line),
        (ConditionType.SUCCEEDED, true if ok else false, reason, line),
        (ConditionType.FAILED, false if ok else true, reason, line),
        (ConditionType.FLAKY, true if summary.flaky else false, flaky_reason, flaky_note),
    ):
        conds = set_condition(conds, ctype, cstatus, creason, message, generation=gen, now=now)
    conds = kstatus_conditions(conds, ok, reason, line, generation=gen, now=now)
    why = {r.index: r.reason for r in progress.replicas if r.reason}
    entries = []
    for r in summary.results:
        reason_text = r.reason
        if r.verdict == Verdict.ERROR and r.index in why and why[r.index] not in reason_text:
            reason_text = f"{why[r.index]}; {reason_text}" if reason_text else why[r.index]
        entries.append(
            ReplicaStatus(
                index=r.index,
                seed=max(r.seed, 0),
                verdict=ReplicaVerdict(r.verdict.value),
                min_distance=r.metrics.min_obstacle_distance if r.metrics else None,
                min_distance_2d=r.metrics.min_obstacle_distance_2d if r.metrics else None,
                points=r.metrics.competition_points if r.metrics else None,
                reason=reason_text[:256],
            )
        )
    results, omitted = compact_results(entries)
    return UavTestStatus(
        phase=phase,
        replicas=summary.replicas,
        pending=0,
        running=0,
        **run_counts(summary),
        run_id=test.run_id,
        start_time=_parse_time(job.start_time if job else None) or previous.start_time,
        completion_time=previous.completion_time or now,
        observed_generation=gen,
        message=line,
        artifacts=artifacts_for(store_url, test, with_trajectories=summary.passed + summary.failed > 0),
        conditions=conds,
        results=results,
        results_omitted=omitted,
        warnings=run_warnings(summary),
    )


def status_from(
    test: RunView,
    job: JobView | None,
    pods: Iterable[PodView],
    *,
    store_url: str,
    job_deleted: bool = False,
    summary: RunSummary | None = None,
    aggregation_error: str | None = None,
    now: datetime | None = None,
) -> UavTestStatus:
    """The status of ``test`` given its Job and pods, and the run's summary once aggregated.

    ``job_deleted``: the run's Job was deleted (the run then ends: unfinished replicas are errors).
    ``aggregation_error``: the last aggregation could not reach the store.
    A final status (Complete True) is returned unchanged unless a summary is given.
    """
    now = now or datetime.now(UTC)
    previous = run_status(test)
    progress = progress_of(test.replicas, job, pods, job_deleted=job_deleted)
    if summary is not None:
        return _final_status(test, progress, previous, job, summary, store_url=store_url, now=now)
    if is_final(test.status):
        return previous
    return _running_status(
        test, progress, previous, job, store_url=store_url, now=now, aggregation_error=aggregation_error
    )
