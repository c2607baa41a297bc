"""The kopf handlers of the uavtest operator: thin, typed, each delegating to ``reconcile`` / ``testsync``.

Two kinds, like CronJob and Job: a ``UavTest`` (the test) owns ``UavTestRun`` objects (its runs);
each run owns its ConfigMap, upload Secret and Indexed Job.

- startup: kopf's finalizer and progress storage under uavtest.io, clients and metrics in memo;
- indexes of UavTests, their runs, Jobs and pods (keyed by namespace and test name), so every
  handler sees its siblings without an API call and a restart rebuilds them from one list;
- UavTest created, changed (spec or the ``uavtest.io/rerun`` annotation) or found at start-up:
  the runs it needs (``testsync.ensure_runs``); with ``spec.schedule``, a timer checks the
  schedule every ``SCHEDULE_CHECK_SECONDS``;
- UavTestRun created: its ConfigMap and Indexed Job, unless they exist (idempotent); every event
  of a run: the test's summary and history trimming (``testsync.sync_test``);
- every event of a replica Job: the run's status from the Job and the pods index (patched only
  when it changed). Pod events need no handler: they only update the index;
- a timer that runs only while a run awaits aggregation (every index finished): aggregate,
  or, while the store is unreachable, come back after ``AGGREGATE_RETRY_SECONDS``.
"""

from __future__ import annotations

import logging
from typing import Any

import kopf

from uavtest.controller import names, reconcile, testsync
from uavtest.controller.kube import Kube, api_client
from uavtest.controller.metrics import Metrics
from uavtest.controller.settings import OperatorSettings
from uavtest.controller.status import awaiting_aggregation
from uavtest.controller.views import (
    JobView,
    PodView,
    RunView,
    TestView,
    job_view,
    pod_view,
    run_view,
    test_view,
)
from uavtest.store import S3Settings

__all__ = ["AGGREGATE_RETRY_SECONDS", "SCHEDULE_CHECK_SECONDS"]

AGGREGATE_RETRY_SECONDS = 30.0
SCHEDULE_CHECK_SECONDS = 15.0

_UAVTESTS = (names.API_GROUP, names.VERSION, names.PLURAL)
_RUNS = (names.API_GROUP, names.VERSION, names.RUN_PLURAL)
_OURS = {names.LABEL_RUN: kopf.PRESENT, names.LABEL_MANAGED_BY: names.MANAGER}


def _rt(memo: kopf.Memo) -> reconcile.Runtime:
    return memo["runtime"]  # type: ignore[no-any-return]


@kopf.on.startup()
def configure(
    settings: kopf.OperatorSettings, memo: kopf.Memo, logger: kopf.Logger, tests_by_name: kopf.Index, **_: Any
) -> None:
    settings.persistence.finalizer = names.FINALIZER
    settings.persistence.progress_storage = kopf.AnnotationsProgressStorage(prefix=names.PROGRESS_PREFIX)
    settings.persistence.diffbase_storage = kopf.AnnotationsDiffBaseStorage(
        prefix=names.PROGRESS_PREFIX, key="last-handled-configuration"
    )
    settings.posting.level = logging.WARNING  # Events only for warnings: no event per handler run
    # Serve the resources and namespaces found at start-up; do not watch CRDs and namespaces (which
    # would need cluster-wide read access): the chart installs the CRDs before the operator starts.
    settings.scanning.disabled = True
    config = memo.get("config") or OperatorSettings()

    def tests() -> list[TestView]:
        return [view for store in list(tests_by_name.values()) for view in list(store)]

    metrics = Metrics(tests)
    if config.metrics_port:
        port = metrics.serve(config.metrics_port)
        logger.info(f"metrics on :{port}/metrics")
    memo["runtime"] = reconcile.Runtime(
        config=config, s3=S3Settings(), kube=Kube(api_client()), metrics=metrics
    )


@kopf.on.cleanup()
def shut_down(memo: kopf.Memo, **_: Any) -> None:
    rt = memo.get("runtime")
    if rt is not None:
        rt.metrics.close()
        rt.kube.close()


@kopf.index(*_UAVTESTS)
def tests_by_name(body: kopf.Body, namespace: str, name: str, **_: Any) -> dict[tuple[str, str], TestView]:
    return {(namespace, name): test_view(body)}


@kopf.index(*_RUNS)
def runs_by_test(body: kopf.Body, namespace: str, **_: Any) -> dict[tuple[str, str], RunView]:
    view = run_view(body)
    return {(namespace, view.test): view}


@kopf.index("batch/v1", "jobs", labels=_OURS)
def jobs_by_test(
    body: kopf.Body, namespace: str, labels: kopf.Labels, **_: Any
) -> dict[tuple[str, str], JobView]:
    return {(namespace, labels[names.LABEL_TEST]): job_view(body)}


@kopf.index("v1", "pods", labels=_OURS)
def pods_by_test(
    body: kopf.Body, namespace: str, labels: kopf.Labels, **_: Any
) -> dict[tuple[str, str], PodView] | None:
    view = pod_view(body)
    return {(namespace, labels[names.LABEL_TEST]): view} if view is not None else None


# ------------------------------------------------------------------------------------------ tests


@kopf.on.resume(*_UAVTESTS)
@kopf.on.create(*_UAVTESTS)
@kopf.on.update(*_UAVTESTS)
def ensure_runs(body: kopf.Body, memo: kopf.Memo, logger: kopf.Logger, **_: Any) -> None:
    rt = _rt(memo)
    with rt.metrics.reconcile_errors.labels(handler="test").count_exceptions():
        testsync.ensure_runs(rt, body, logger)


def _scheduled(spec: kopf.Spec, **_: Any) -> bool:
    return bool(spec.get("schedule"))


@kopf.timer(*_UAVTESTS, interval=SCHEDULE_CHECK_SECONDS, when=_scheduled)
def run_schedule(body: kopf.Body, memo: kopf.Memo, logger: kopf.Logger, **_: Any) -> None:
    rt = _rt(memo)
    with rt.metrics.reconcile_errors.labels(handler="schedule").count_exceptions():
        testsync.ensure_runs(rt, body, logger, schedule=True)


@kopf.on.event(*_UAVTESTS)
def test_event(
    type: str, body: kopf.Body, namespace: str, name: str, memo: kopf.Memo, logger: kopf.Logger, **_: Any
) -> None:
    rt = _rt(memo)
    if type == "DELETED":
        rt.books.drop((namespace, f"{names.KIND}/{name}"))
        return
    # A new generation kopf sees no change in (the API server bumps it for 120 → 120.0): no run
    # is due, but observedGeneration must follow, or kstatus reads the test InProgress forever.
    status = body.get("status") or {}
    if status.get("specHash") and status.get("observedGeneration") != body.get("metadata", {}).get(
        "generation"
    ):
        with rt.metrics.reconcile_errors.labels(handler="test").count_exceptions():
            testsync.ensure_runs(rt, body, logger)


# ------------------------------------------------------------------------------------------- runs


@kopf.on.create(*_RUNS)
def create_run(
    body: kopf.Body,
    namespace: str,
    memo: kopf.Memo,
    logger: kopf.Logger,
    jobs_by_test: kopf.Index,
    **_: Any,
) -> None:
    rt = _rt(memo)
    test = run_view(body).test
    with rt.metrics.reconcile_errors.labels(handler="create").count_exceptions():
        reconcile.start_run(rt, body, jobs_by_test.get((namespace, test), []), logger)


@kopf.on.event(*_RUNS)
def run_changed(
    type: str,
    body: kopf.Body,
    namespace: str,
    name: str,
    memo: kopf.Memo,
    logger: kopf.Logger,
    tests_by_name: kopf.Index,
    runs_by_test: kopf.Index,
    **_: Any,
) -> None:
    rt = _rt(memo)
    if type == "DELETED":
        rt.books.drop((namespace, name))
    test_name = (body.get("spec") or {}).get("testName")
    if not test_name:
        return
    test = next(iter(tests_by_name.get((namespace, test_name), [])), None)
    if test is None:
        return  # the test is gone (its runs follow) or not seen yet
    runs = [
        r for r in runs_by_test.get((namespace, test_name), []) if not (type == "DELETED" and r.name == name)
    ]
    with rt.metrics.reconcile_errors.labels(handler="summary").count_exceptions():
        testsync.sync_test(rt, test, runs, logger)


def _sync(
    memo: kopf.Memo,
    namespace: str,
    test_name: str,
    run_id: str,
    runs_by_test: kopf.Index,
    jobs_by_test: kopf.Index,
    pods_by_test: kopf.Index,
    *,
    job_deleted: bool = False,
) -> None:
    key = (namespace, test_name)
    run = next((r for r in runs_by_test.get(key, []) if r.run_id == run_id), None)
    if run is None:
        return  # an orphan of a deleted run
    rt = _rt(memo)
    job = reconcile.job_of(jobs_by_test.get(key, []), run_id)
    pods = [p for p in pods_by_test.get(key, []) if p.run_id == run_id]
    with rt.metrics.reconcile_errors.labels(handler="status").count_exceptions():
        reconcile.sync_run(rt, run, job, pods, job_deleted=job_deleted and job is None)


@kopf.on.event("batch/v1", "jobs", labels=_OURS)
def job_changed(
    type: str,
    namespace: str,
    labels: kopf.Labels,
    memo: kopf.Memo,
    runs_by_test: kopf.Index,
    jobs_by_test: kopf.Index,
    pods_by_test: kopf.Index,
    **_: Any,
) -> None:
    _sync(
        memo,
        namespace,
        labels[names.LABEL_TEST],
        labels[names.LABEL_RUN],
        runs_by_test,
        jobs_by_test,
        pods_by_test,
        job_deleted=type == "DELETED",
    )


def _awaiting(status: kopf.Status, **_: Any) -> bool:
    return awaiting_aggregation(status)


@kopf.timer(*_RUNS, interval=AGGREGATE_RETRY_SECONDS, when=_awaiting)
def aggregate_run(
    body: kopf.Body,
    namespace: str,
    memo: kopf.Memo,
    logger: kopf.Logger,
    jobs_by_test: kopf.Index,
    pods_by_test: kopf.Index,
    **_: Any,
) -> None:
    rt = _rt(memo)
    view = run_view(body)
    job = reconcile.job_of(jobs_by_test.get((namespace, view.test), []), view.run_id)
    pods = [p for p in pods_by_test.get((namespace, view.test), []) if p.run_id == view.run_id]
    with rt.metrics.reconcile_errors.labels(handler="aggregate").count_exceptions():
        reconcile.aggregate(rt, body, job, pods, logger)
