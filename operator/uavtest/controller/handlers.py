"""The kopf handlers of the uavtest operator: thin, typed, each delegating to ``reconcile``.

- startup: kopf's finalizer and progress storage under uavtest.io, clients and metrics in memo;
- indexes of UavTests, their Jobs and their pods (keyed by namespace and test name), so every
  handler sees its siblings without an API call and a restart rebuilds them from one list;
- on create of a UavTest: its ConfigMap and Indexed Job, unless they exist (idempotent);
- on every event of a replica Job: the parent's status from the Job and the pods index (patched
  only when it changed). The Job's own status changes with every pod that starts, becomes ready,
  ends or is retried, so pod events need no handler of their own: they only update the index,
  which keeps a few hundred bytes per pod instead of queueing whole pod bodies for a handler;
- a timer that runs only while a test awaits aggregation (every index finished): aggregate,
  or, while the store is unreachable, come back after ``AGGREGATE_RETRY_SECONDS``.
"""

from __future__ import annotations

import logging
from typing import Any

import kopf

from uavtest.controller import names, reconcile
from uavtest.controller.kube import Kube, api_client
from uavtest.controller.metrics import Metrics
from uavtest.controller.settings import OperatorSettings
from uavtest.controller.status import awaiting_aggregation
from uavtest.controller.views import JobView, PodView, UavTestView, job_view, pod_view, uavtest_view
from uavtest.store import S3Settings

__all__ = ["AGGREGATE_RETRY_SECONDS"]

AGGREGATE_RETRY_SECONDS = 30.0

_UAVTESTS = (names.API_GROUP, names.VERSION, names.PLURAL)
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
    # would need cluster-wide read access): the chart installs the CRD before the operator starts.
    settings.scanning.disabled = True
    config = memo.get("config") or OperatorSettings()

    def tests() -> list[UavTestView]:
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
def tests_by_name(body: kopf.Body, namespace: str, name: str, **_: Any) -> dict[tuple[str, str], UavTestView]:
    return {(namespace, name): uavtest_view(body)}


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


@kopf.on.create(*_UAVTESTS)
def create_run(
    body: kopf.Body,
    namespace: str,
    name: str,
    memo: kopf.Memo,
    logger: kopf.Logger,
    jobs_by_test: kopf.Index,
    **_: Any,
) -> None:
    rt = _rt(memo)
    with rt.metrics.reconcile_errors.labels(handler="create").count_exceptions():
        reconcile.start_run(rt, body, jobs_by_test.get((namespace, name), []), logger)


@kopf.on.event(*_UAVTESTS)
def forget_deleted(type: str, namespace: str, name: str, memo: kopf.Memo, **_: Any) -> None:
    if type == "DELETED":
        _rt(memo).books.drop((namespace, name))


def _sync(
    memo: kopf.Memo,
    namespace: str,
    test_name: str,
    run_id: str,
    tests_by_name: kopf.Index,
    jobs_by_test: kopf.Index,
    pods_by_test: kopf.Index,
    *,
    job_deleted: bool = False,
) -> None:
    key = (namespace, test_name)
    test = next((t for t in tests_by_name.get(key, []) if t.run_id == run_id), None)
    if test is None:
        return  # an orphan of a deleted UavTest, or an older run of a re-created one
    rt = _rt(memo)
    job = reconcile.job_of(jobs_by_test.get(key, []), run_id)
    pods = [p for p in pods_by_test.get(key, []) if p.run_id == run_id]
    with rt.metrics.reconcile_errors.labels(handler="status").count_exceptions():
        reconcile.sync_run(rt, test, job, pods, job_deleted=job_deleted and job is None)


@kopf.on.event("batch/v1", "jobs", labels=_OURS)
def job_changed(
    type: str,
    namespace: str,
    labels: kopf.Labels,
    memo: kopf.Memo,
    tests_by_name: kopf.Index,
    jobs_by_test: kopf.Index,
    pods_by_test: kopf.Index,
    **_: Any,
) -> None:
    _sync(
        memo,
        namespace,
        labels[names.LABEL_TEST],
        labels[names.LABEL_RUN],
        tests_by_name,
        jobs_by_test,
        pods_by_test,
        job_deleted=type == "DELETED",
    )


def _awaiting(status: kopf.Status, **_: Any) -> bool:
    return awaiting_aggregation(status)


@kopf.timer(*_UAVTESTS, interval=AGGREGATE_RETRY_SECONDS, when=_awaiting)
def aggregate_run(
    body: kopf.Body,
    namespace: str,
    name: str,
    memo: kopf.Memo,
    logger: kopf.Logger,
    jobs_by_test: kopf.Index,
    pods_by_test: kopf.Index,
    **_: Any,
) -> None:
    rt = _rt(memo)
    run_id = uavtest_view(body).run_id
    job = reconcile.job_of(jobs_by_test.get((namespace, name), []), run_id)
    pods = [p for p in pods_by_test.get((namespace, name), []) if p.run_id == run_id]
    with rt.metrics.reconcile_errors.labels(handler="aggregate").count_exceptions():
        reconcile.aggregate(rt, body, job, pods, logger)
