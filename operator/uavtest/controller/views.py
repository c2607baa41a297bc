"""Small typed views of the objects the operator watches, parsed from their raw bodies (pure).

The kopf indexes hold these views, not whole bodies: a 2,000-pod run keeps a few hundred bytes
per pod in memory. Everything the status needs is here; nothing else is kept.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ConfigDict

from uavtest.controller import names
from uavtest.controller.jobs import run_id_for

__all__ = [
    "JobView",
    "PodView",
    "RunView",
    "TestView",
    "job_view",
    "parse_indexes",
    "pod_view",
    "run_view",
    "test_view",
]


class _View(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class RunView(_View):
    """A UavTestRun as the status logic needs it (``name`` is the run's, ``test`` its UavTest's)."""

    namespace: str
    name: str
    test: str
    uid: str
    run_id: str
    generation: int
    replicas: int
    seed: int
    trigger: str | None = None
    created: str = ""
    has_spec: bool = True  # spec.testSpec is there (a run created by hand may leave it out)
    status: dict[str, Any]


class TestView(_View):
    """A UavTest as the run scheduling and the metrics need it (not its flight spec)."""

    __test__ = False  # not a pytest class

    namespace: str
    name: str
    uid: str
    generation: int
    created: str
    schedule: str | None
    successful_limit: int
    failed_limit: int
    rerun: str | None  # the uavtest.io/rerun annotation
    status: dict[str, Any]


class JobView(_View):
    """An Indexed Job's progress."""

    namespace: str
    name: str
    test: str
    run_id: str
    completions: int
    completed_indexes: frozenset[int]
    failed_indexes: frozenset[int]
    active: int
    ready: int
    start_time: str | None
    completion_time: str | None
    terminal: str | None  # "Complete" or "Failed" once the Job is finished
    terminal_reason: str  # e.g. "DeadlineExceeded", "FailedIndexes"
    terminal_message: str


class PodView(_View):
    """One replica pod: which index, where it is, and how its runner ended."""

    name: str
    test: str
    run_id: str
    index: int
    phase: str  # Pending, Running, Succeeded, Failed, Unknown
    created: str  # creationTimestamp: the newest pod of an index is its current attempt
    deleting: bool
    runner_exit: int | None
    runner_reason: str  # e.g. "Completed", "Error", "OOMKilled"
    started_at: str | None
    finished_at: str | None


def parse_indexes(text: str | None) -> frozenset[int]:
    """A Job's ``completedIndexes`` / ``failedIndexes``: ``"1,3-5,7"`` → {1, 3, 4, 5, 7}."""
    out: set[int] = set()
    for part in (text or "").split(","):
        part = part.strip()
        if not part:
            continue
        lo, _, hi = part.partition("-")
        out.update(range(int(lo), int(hi or lo) + 1))
    return frozenset(out)


def _labels(body: Mapping[str, Any]) -> Mapping[str, str]:
    return body.get("metadata", {}).get("labels") or {}


def run_view(body: Mapping[str, Any]) -> RunView:
    meta = body.get("metadata", {})
    run_spec = body.get("spec") or {}
    spec = run_spec.get("testSpec") or {}
    return RunView(
        namespace=meta.get("namespace") or "default",
        name=meta["name"],
        test=str(run_spec.get("testName") or meta["name"]),
        uid=meta["uid"],
        run_id=run_id_for(meta["uid"]),
        generation=int(meta.get("generation") or 1),
        replicas=int(spec.get("replicas") or 1),
        seed=int(spec.get("seed") or 0),
        trigger=run_spec.get("trigger"),
        created=meta.get("creationTimestamp") or "",
        has_spec="testSpec" in run_spec,
        status=dict(body.get("status") or {}),
    )


def test_view(body: Mapping[str, Any]) -> TestView:
    meta = body.get("metadata", {})
    spec = body.get("spec") or {}
    return TestView(
        namespace=meta.get("namespace") or "default",
        name=meta["name"],
        uid=meta.get("uid") or "",
        generation=int(meta.get("generation") or 1),
        created=meta.get("creationTimestamp") or "",
        schedule=spec.get("schedule"),
        successful_limit=int(spec.get("successfulRunsHistoryLimit", 3)),
        failed_limit=int(spec.get("failedRunsHistoryLimit", 3)),
        rerun=(meta.get("annotations") or {}).get(names.RERUN_ANNOTATION),
        status=dict(body.get("status") or {}),
    )


test_view.__test__ = False  # type: ignore[attr-defined]


def job_view(body: Mapping[str, Any]) -> JobView:
    meta = body.get("metadata", {})
    labels = _labels(body)
    spec = body.get("spec") or {}
    status = body.get("status") or {}
    terminal = None
    reason = message = ""
    for cond in status.get("conditions") or []:
        if cond.get("type") in {"Complete", "Failed"} and cond.get("status") == "True":
            terminal = cond["type"]
            reason = cond.get("reason") or ""
            message = cond.get("message") or ""
    return JobView(
        namespace=meta.get("namespace") or "default",
        name=meta["name"],
        test=labels.get(names.LABEL_TEST, ""),
        run_id=labels.get(names.LABEL_RUN, ""),
        completions=int(spec.get("completions") or 0),
        completed_indexes=parse_indexes(status.get("completedIndexes")),
        failed_indexes=parse_indexes(status.get("failedIndexes")),
        active=int(status.get("active") or 0),
        ready=int(status.get("ready") or 0),
        start_time=status.get("startTime"),
        completion_time=status.get("completionTime"),
        terminal=terminal,
        terminal_reason=reason,
        terminal_message=message,
    )


def _pod_index(body: Mapping[str, Any]) -> int | None:
    meta = body.get("metadata", {})
    raw = _labels(body).get(names.JOB_INDEX_LABEL) or (meta.get("annotations") or {}).get(
        names.JOB_INDEX_ANNOTATION
    )
    try:
        return int(raw) if raw is not None else None
    except ValueError:
        return None


def pod_view(body: Mapping[str, Any]) -> PodView | None:
    """The view of a replica pod; None for a pod without a completion index (not ours)."""
    index = _pod_index(body)
    if index is None:
        return None
    meta = body.get("metadata", {})
    labels = _labels(body)
    status = body.get("status") or {}
    exit_code = None
    reason = ""
    started = finished = None
    for cs in status.get("containerStatuses") or []:
        if cs.get("name") != names.CONTAINER_RUNNER:
            continue
        term = (cs.get("state") or {}).get("terminated")
        running = (cs.get("state") or {}).get("running")
        if term:
            exit_code = term.get("exitCode")
            reason = term.get("reason") or ""
            started, finished = term.get("startedAt"), term.get("finishedAt")
        elif running:
            started = running.get("startedAt")
    return PodView(
        name=meta["name"],
        test=labels.get(names.LABEL_TEST, ""),
        run_id=labels.get(names.LABEL_RUN, ""),
        index=index,
        phase=status.get("phase") or "Pending",
        created=meta.get("creationTimestamp") or "",
        deleting=meta.get("deletionTimestamp") is not None,
        runner_exit=exit_code,
        runner_reason=reason,
        started_at=started,
        finished_at=finished,
    )
