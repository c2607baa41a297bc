"""What the UavTest handlers delegate to: start the runs a test needs; summarise and trim its runs.

The decisions are ``runs``' pure functions; here are the API calls. Runs are created under
deterministic names (409 Conflict: it exists), then the test's status records what was acted on
(``specHash``, ``lastRerun``, ``lastScheduleTime``, ``observedGeneration``), so an operator
restarted between the two creates nothing twice and skips nothing.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from typing import Any

import kopf

from uavtest.controller import names
from uavtest.controller.reconcile import Runtime
from uavtest.controller.runs import build_run, planned_runs, runs_to_delete, test_status_from
from uavtest.controller.status import kstatus_conditions
from uavtest.controller.views import RunView, TestView, test_view
from uavtest.spec.status import Condition, ConditionReason, TestStatus

__all__ = ["SCHEDULER_FIELDS", "ensure_runs", "sync_test"]

# status fields the run scheduling owns; the summary never writes them (a stale copy would undo them)
SCHEDULER_FIELDS = ("specHash", "lastRerun", "lastScheduleTime", "observedGeneration")


def _conditions(status: Mapping[str, Any]) -> list[Condition]:
    try:
        return list(TestStatus.model_validate(status).conditions)
    except ValueError:
        return []


def ensure_runs(
    rt: Runtime, body: Mapping[str, Any], logger: logging.Logger, *, schedule: bool = False
) -> None:
    """Create the runs the test needs now (a new spec, a re-run request, a due schedule)."""
    test = test_view(body)
    plans = planned_runs(test, body.get("spec") or {}, schedule=schedule)
    patch: dict[str, Any] = {}
    for plan in plans:
        if rt.kube.create_run(test.namespace, build_run(body, plan)):
            logger.info(f"created UavTestRun {plan.name} ({plan.trigger.value})")
            kopf.event(  # type: ignore[arg-type]
                body,
                type="Normal",
                reason=names.EventReason.RUN_CREATED,
                message=f"UavTestRun {plan.name} ({plan.trigger.value})",
            )
        patch.update(plan.status_patch)
    if test.status.get("observedGeneration") != test.generation:
        patch["observedGeneration"] = test.generation
    if plans:  # until the run shows up in the summary: in progress, not the previous run's verdict
        message = f"run {plans[-1].name} started"
        conds = kstatus_conditions(
            _conditions(test.status),
            None,
            ConditionReason.RUN_IN_PROGRESS,
            message,
            generation=test.generation,
            now=datetime.now(UTC),
        )
        patch["conditions"] = TestStatus(conditions=conds).dump()["conditions"]
        patch["message"] = message
    if patch:
        rt.kube.patch_test_status(test.namespace, test.name, patch)


def sync_test(rt: Runtime, test: TestView, runs: Sequence[RunView], logger: logging.Logger) -> None:
    """Write the test's summary of ``runs`` when it changed; delete runs beyond the history limits."""
    status = test_status_from(test, runs)
    summary = {k: v for k, v in status.dump().items() if k not in SCHEDULER_FIELDS}
    book = rt.books.get((test.namespace, f"{names.KIND}/{test.name}"))
    with book.lock:
        previous = book.status
        if previous is None:
            previous = {k: v for k, v in test.status.items() if k not in SCHEDULER_FIELDS}
        if previous != summary and rt.kube.patch_test_status(test.namespace, test.name, summary):
            book.status = summary
    doomed = runs_to_delete(test, runs)
    for name in doomed:
        if rt.kube.delete_run(test.namespace, name):
            logger.info(f"deleted UavTestRun {name}: beyond the history limits")
