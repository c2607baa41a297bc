"""A UavTest and its runs (pure): which UavTestRun to create, which to delete, the test's summary.

Like CronJob and Job: the UavTest is the long-lived test; each run is a ``UavTestRun`` it owns.
Runs are created under deterministic names, so an operator that restarts at any point creates
nothing twice (the API server answers 409 for a name that exists) and skips nothing (the test's
status says what was acted on last):

==============  ==============================  ==================================================
trigger         name                            started when
==============  ==============================  ==================================================
create /        ``<test>-g<generation>``        the flown spec's hash differs from
spec-change                                     ``status.specHash`` (a changed ``schedule`` or
                                                history limit alone starts nothing)
rerun           ``<test>-r<sha256(value)[:8]>`` ``uavtest.io/rerun`` differs from
                                                ``status.lastRerun``
schedule        ``<test>-s<unix minute>``       the newest cron time ≤ now is later than
                                                ``status.lastScheduleTime`` (and the test's
                                                creation): one run per missed window, never two
==============  ==============================  ==================================================

History: finished runs beyond ``successfulRunsHistoryLimit`` (passed) and
``failedRunsHistoryLimit`` (failed or error) are deleted, oldest first; running runs are kept.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from pydantic import ValidationError

from uavtest.controller import names
from uavtest.controller.status import is_final, kstatus_conditions, run_counts, run_status
from uavtest.controller.streak import Finished, failure_streak
from uavtest.controller.views import RunView, TestView
from uavtest.spec.status import (
    ConditionReason,
    LastRun,
    Phase,
    TestStatus,
)

__all__ = [
    "RUN_SPEC_EXCLUDES",
    "PlannedRun",
    "build_run",
    "due_schedule_time",
    "planned_runs",
    "runs_to_delete",
    "spec_hash",
    "test_status_from",
]

# spec fields that say when and how long to keep runs, not what a run flies
RUN_SPEC_EXCLUDES = ("schedule", "successfulRunsHistoryLimit", "failedRunsHistoryLimit")
_NAME_HEAD = 52  # test names are at most 63; keep run names short and readable


def _plain(value: Any) -> Any:
    """JSON numbers as the API server hands them back: 120.0 and 120 are the same spec."""
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def spec_hash(spec: Mapping[str, Any]) -> str:
    """A short hash of what a run flies: the spec without schedule and history limits."""
    flown = {k: _plain(v) for k, v in spec.items() if k not in RUN_SPEC_EXCLUDES}
    return hashlib.sha256(json.dumps(flown, sort_keys=True).encode()).hexdigest()[:16]


def _head(test: str) -> str:
    return test[:_NAME_HEAD].rstrip("-")


def generation_run_name(test: str, generation: int) -> str:
    return f"{_head(test)}-g{generation}"


def rerun_name(test: str, value: str) -> str:
    return f"{_head(test)}-r{hashlib.sha256(value.encode()).hexdigest()[:8]}"


def schedule_run_name(test: str, when: datetime) -> str:
    return f"{_head(test)}-s{int(when.timestamp()) // 60}"


def _parse_time(text: str | None) -> datetime | None:
    if not text:
        return None
    try:
        when = datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    except ValueError:
        return None
    return when if when.tzinfo else when.replace(tzinfo=UTC)


def due_schedule_time(schedule: str, since: datetime, now: datetime) -> datetime | None:
    """The newest time of ``schedule`` in (since, now], or None: the run to start now, if any.

    Windows missed while the operator was down collapse into the newest one (CronJob's
    ``concurrencyPolicy`` aside, it also starts at most one late run).
    """
    from cronsim import CronSim

    latest = next(CronSim(schedule, now.astimezone(UTC), reverse=True), None)
    if latest is None or latest <= since:
        return None
    return latest


@dataclass(frozen=True)
class PlannedRun:
    """A run to create and the test status fields that record it was acted on."""

    name: str
    trigger: names.Trigger
    status_patch: dict[str, Any]
    scheduled: datetime | None = None


def planned_runs(
    test: TestView, spec: Mapping[str, Any], *, now: datetime | None = None, schedule: bool = False
) -> list[PlannedRun]:
    """The runs ``test`` needs now (``schedule``: also look at its cron schedule)."""
    status = test.status
    out: list[PlannedRun] = []
    digest = spec_hash(spec)
    if status.get("specHash") != digest:
        trigger = names.Trigger.CREATE if not status.get("specHash") else names.Trigger.SPEC_CHANGE
        out.append(
            PlannedRun(
                generation_run_name(test.name, test.generation),
                trigger,
                {"specHash": digest, "observedGeneration": test.generation},
            )
        )
    if test.rerun and test.rerun != status.get("lastRerun"):
        out.append(
            PlannedRun(rerun_name(test.name, test.rerun), names.Trigger.RERUN, {"lastRerun": test.rerun})
        )
    if schedule and test.schedule:
        now = now or datetime.now(UTC)
        since = _parse_time(status.get("lastScheduleTime")) or _parse_time(test.created) or now
        due = due_schedule_time(test.schedule, since, now)
        if due is not None:
            out.append(
                PlannedRun(
                    schedule_run_name(test.name, due),
                    names.Trigger.SCHEDULE,
                    {"lastScheduleTime": due.isoformat().replace("+00:00", "Z")},
                    scheduled=due,
                )
            )
    return out


def build_run(test_body: Mapping[str, Any], planned: PlannedRun) -> dict[str, Any]:
    """The UavTestRun manifest: owned by the test, with a frozen copy of the spec it flies."""
    import kopf

    meta = test_body.get("metadata", {})
    spec = dict(test_body.get("spec") or {})
    run_spec: dict[str, Any] = {
        "testName": meta["name"],
        "testGeneration": int(meta.get("generation") or 1),
        "trigger": planned.trigger.value,
        "testSpec": spec,
    }
    if planned.scheduled is not None:
        run_spec["scheduledTime"] = planned.scheduled.isoformat().replace("+00:00", "Z")
    run: dict[str, Any] = {
        "apiVersion": names.API_VERSION,
        "kind": names.RUN_KIND,
        "metadata": {
            "name": planned.name,
            "labels": {names.LABEL_TEST: meta["name"], names.LABEL_MANAGED_BY: names.MANAGER},
        },
        "spec": run_spec,
    }
    kopf.adopt(run, owner=test_body, strict=True)  # type: ignore[arg-type]
    return run


def _newest_first(runs: Iterable[RunView]) -> list[RunView]:
    return sorted(runs, key=lambda r: (r.created, r.name), reverse=True)


def runs_to_delete(test: TestView, runs: Iterable[RunView]) -> list[str]:
    """Names of finished runs beyond the history limits, oldest last kept: passed and failed apart."""
    kept = {"ok": 0, "bad": 0}
    limit = {"ok": test.successful_limit, "bad": test.failed_limit}
    doomed = []
    for run in _newest_first(runs):
        if not is_final(run.status):
            continue
        kind = "ok" if run.status.get("phase") == Phase.SUCCEEDED else "bad"
        kept[kind] += 1
        if kept[kind] > limit[kind]:
            doomed.append(run.name)
    return doomed


def _last_run(run: RunView) -> LastRun:
    st = run_status(run)
    return LastRun(
        name=run.name,
        phase=st.phase,
        trigger=run.trigger,
        **run_counts(st),
        completion_time=st.completion_time,
        summary=st.artifacts.summary,
    )


def test_status_from(test: TestView, runs: Sequence[RunView], *, now: datetime | None = None) -> TestStatus:
    """The UavTest's status from its kept runs: newest run, counts, flaky-rate, kstatus conditions.

    Fields the run scheduling writes (specHash, lastRerun, lastScheduleTime, observedGeneration)
    are carried over from the current status unchanged.
    """
    now = now or datetime.now(UTC)
    try:
        previous = TestStatus.model_validate(test.status)
    except ValidationError:
        previous = TestStatus()
    ordered = _newest_first(runs)
    finished = [r for r in ordered if is_final(r.status)]
    statuses = {r.name: run_status(r) for r in ordered}
    succeeded = sum(1 for r in finished if statuses[r.name].phase == Phase.SUCCEEDED)
    flaky = sum(1 for r in finished if statuses[r.name].flaky)
    last = _last_run(ordered[0]) if ordered else previous.last_run
    gen = previous.observed_generation or test.generation
    if last is None:
        passed: bool | None = None
        reason, message = ConditionReason.NO_RUN, "no run yet"
    elif last.phase in (Phase.PENDING, Phase.RUNNING):
        passed, reason = None, ConditionReason.RUN_IN_PROGRESS
        message = f"run {last.name} is {last.phase.value.lower()}"
    elif last.phase == Phase.SUCCEEDED:
        passed, reason, message = True, ConditionReason.RUN_PASSED, f"run {last.name} passed"
    else:
        passed = False
        reason = ConditionReason.RUN_FAILED if last.phase == Phase.FAILED else ConditionReason.RUN_ERROR
        message = f"run {last.name} {'failed' if last.phase == Phase.FAILED else 'ended in bench errors'}"
    conds = kstatus_conditions(list(previous.conditions), passed, reason, message, generation=gen, now=now)
    counted = (
        (previous.streak_time, previous.streak_run)
        if previous.streak_time is not None and previous.streak_run is not None
        else None
    )
    streak, counted = failure_streak(
        (
            Finished(r.name, st.completion_time, st.phase)
            for r in finished
            if (st := statuses[r.name]).completion_time is not None
        ),
        previous.failed_in_a_row,
        counted,
    )
    return previous.model_copy(
        update={
            "phase": last.phase if last is not None else Phase.PENDING,
            "last_run": last,
            "runs": len(ordered),
            "active": len(ordered) - len(finished),
            "succeeded": succeeded,
            "failed": len(finished) - succeeded,
            "flaky_runs": flaky,
            "flaky_rate": flaky / len(finished) if finished else None,
            "failed_in_a_row": streak,
            "streak_time": counted[0] if counted else None,
            "streak_run": counted[1] if counted else None,
            "message": message,
            "conditions": conds,
        }
    )


test_status_from.__test__ = False  # type: ignore[attr-defined]
