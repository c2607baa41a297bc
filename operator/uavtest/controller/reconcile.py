"""What the kopf handlers delegate to: start a run, follow it, aggregate it.

I/O happens here (API calls through ``Kube``, the store through ``uavtest.store``); the decisions
are the pure functions of ``jobs``, ``progress``, ``status`` and ``events``. One lock per UavTest
serialises status writes of concurrent pod / Job events and the aggregation (kopf runs sync
handlers in threads), and remembers the last status written, so an event that changes nothing
sends nothing and a late event never overwrites a final status.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta
from typing import Any

import kopf
from pydantic import ValidationError

from uavtest.analysis.models import RunSummary
from uavtest.controller import names
from uavtest.controller.events import events_for
from uavtest.controller.jobs import (
    UploadWindow,
    build_configmap,
    build_job,
    build_upload_secret,
    deadline_seconds,
    owned_by,
    pod_endpoint_url,
    unresolved_files,
    upload_expires,
    upload_prefix,
    upload_secret_name,
    upload_window,
    uses_upload_policy,
)
from uavtest.controller.kube import Kube
from uavtest.controller.metrics import Metrics
from uavtest.controller.settings import OperatorSettings
from uavtest.controller.status import awaiting_aggregation, is_final, status_from
from uavtest.controller.views import JobView, PodView, RunView, job_view, run_view
from uavtest.errors import BadInput, UavTestError
from uavtest.spec.models import Metadata, UavTest, UavTestSpec
from uavtest.spec.status import Condition, ConditionStatus, Phase, UavTestStatus
from uavtest.store import ArtifactStore, S3Settings, StoreUnavailable, open_store
from uavtest.store.post_policy import UploadPolicy

__all__ = [
    "Book",
    "Books",
    "Runtime",
    "aggregate",
    "ensure_upload_secret",
    "job_of",
    "parse_test",
    "start_run",
    "sync_run",
]

log = logging.getLogger(__name__)

Key = tuple[str, str]


@dataclass
class Book:
    """What the operator remembers of one UavTest between events."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    status: dict[str, Any] | None = None  # the last status this operator wrote
    job_deleted: bool = False  # the run's Job was deleted before the run finished
    final: bool = False  # the final status is written: nothing changes it any more
    aggregation_error: str | None = None  # why the last aggregation failed (cleared on success)


class Books:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._books: dict[Key, Book] = {}

    def get(self, key: Key) -> Book:
        with self._lock:
            return self._books.setdefault(key, Book())

    def drop(self, key: Key) -> None:
        with self._lock:
            self._books.pop(key, None)

    def __len__(self) -> int:
        return len(self._books)


@dataclass
class Runtime:
    """The operator's clients and state, kept in kopf's ``memo``."""

    config: OperatorSettings
    s3: S3Settings
    kube: Kube
    metrics: Metrics
    books: Books = field(default_factory=Books)
    _store: ArtifactStore | None = None

    def store(self) -> ArtifactStore:
        if self._store is None:
            self._store = open_store(self.config.store_url, settings=self.s3)
        return self._store


def parse_test(body: Mapping[str, Any]) -> UavTest:
    """The UavTest model a UavTestRun flies (its frozen ``spec.testSpec``, named after its test);
    BadInput naming the field when it does not fit."""
    meta = body.get("metadata", {})
    run_spec = body.get("spec") or {}
    try:
        return UavTest(
            metadata=Metadata(name=run_spec.get("testName") or meta["name"], namespace=meta.get("namespace")),
            spec=UavTestSpec.model_validate(run_spec.get("testSpec") or {}),
        )
    except ValidationError as e:
        first = e.errors()[0]
        where = "spec.testSpec." + ".".join(str(p) for p in first["loc"])
        raise BadInput(first["msg"], field=where) from e


def _fill_spec(rt: Runtime, body: Mapping[str, Any], view: RunView) -> Mapping[str, Any]:
    """A run created by hand (``kubectl create`` with ``spec.testName``): give it to its test, as
    the runs the operator makes are (owner reference, so deleting the test deletes it; the test's
    label), and copy the test's current spec into it when it has none.

    BadInput when the test does not exist; the run then ends as InvalidSpec."""
    test = rt.kube.get_test(view.namespace, view.test)
    if test is None:
        raise BadInput(
            f"no UavTest {view.test} in namespace {view.namespace}", field="spec.testName", value=view.test
        )
    meta = test.get("metadata", {})
    patch: dict[str, Any] = {
        "metadata": {
            "labels": {names.LABEL_TEST: view.test},
            "ownerReferences": [
                {
                    "apiVersion": names.API_VERSION,
                    "kind": names.KIND,
                    "name": meta.get("name", view.test),
                    "uid": meta.get("uid", ""),
                    "controller": True,
                    "blockOwnerDeletion": True,
                }
            ],
        }
    }
    if not view.has_spec:
        gen = int(meta.get("generation") or 1)
        patch["spec"] = {"testSpec": test.get("spec") or {}, "testGeneration": gen}
    return rt.kube.patch_run(view.namespace, view.name, patch)


def _owned(body: Mapping[str, Any]) -> bool:
    return any(o.get("kind") == names.KIND for o in body.get("metadata", {}).get("ownerReferences") or [])


def job_of(jobs: Iterable[JobView], run_id: str) -> JobView | None:
    """The Job of this run among the Jobs labelled with the test's name (an old run's may linger)."""
    return next((j for j in jobs if j.run_id == run_id), None)


def _same(old: Mapping[str, Any] | None, new: UavTestStatus) -> bool:
    if not old:
        return False
    try:
        return UavTestStatus.model_validate(old) == new
    except ValidationError:
        return False


def _write(rt: Runtime, book: Book, test: RunView, status: UavTestStatus) -> None:
    previous = book.status if book.status is not None else test.status
    if _same(previous, status):
        return
    body = status.dump()
    rt.kube.patch_status(test.namespace, test.name, body)
    book.status = body


def _invalid(
    rt: Runtime, body: Mapping[str, Any], test: RunView, message: str, logger: logging.Logger
) -> None:
    """A spec the cluster cannot run: final status Error with reason InvalidSpec, and an Event."""
    from datetime import UTC, datetime

    now = datetime.now(UTC)
    conds = [
        Condition(
            type=t,
            status=s,
            reason=names.Reason.INVALID_SPEC,
            message=message,
            observed_generation=test.generation,
            last_transition_time=now,
        )
        for t, s in (
            (names.ConditionType.COMPLETE, ConditionStatus.TRUE),
            (names.ConditionType.SUCCEEDED, ConditionStatus.FALSE),
            (names.ConditionType.FAILED, ConditionStatus.TRUE),
            (names.ConditionType.READY, ConditionStatus.FALSE),
            (names.ConditionType.RECONCILING, ConditionStatus.FALSE),
            (names.ConditionType.STALLED, ConditionStatus.TRUE),
        )
    ]
    status = UavTestStatus(
        phase=Phase.ERROR,
        replicas=test.replicas,
        run_id=test.run_id,
        observed_generation=test.generation,
        message=message,
        conditions=conds,
    )
    book = rt.books.get((test.namespace, test.name))
    with book.lock:
        _write(rt, book, test, status)
        book.final = True
    logger.error(message)
    kopf.event(body, type="Warning", reason=names.EventReason.INVALID_SPEC, message=message[:1024])  # type: ignore[arg-type]


def _warn(body: Mapping[str, Any], logger: logging.Logger, message: str) -> None:
    logger.warning(message)
    kopf.event(  # type: ignore[arg-type]
        body, type="Warning", reason=names.EventReason.UPLOAD_POLICY_SHORT, message=message[:1024]
    )


def _sign_upload_policy(rt: Runtime, test: UavTest, run_id: str, window: UploadWindow) -> UploadPolicy:
    from uavtest.store.s3 import S3Store

    store = rt.store()
    assert isinstance(store, S3Store), "uses_upload_policy: an s3:// store"
    try:
        return store.upload_policy(
            upload_prefix(test, run_id),
            expires=window.expires,
            max_bytes=rt.config.upload_max_bytes,
            endpoint_url=pod_endpoint_url(rt.config, rt.s3),
        )
    except StoreUnavailable as e:
        raise kopf.TemporaryError(
            f"cannot sign the run's upload policy: {e}", delay=rt.config.aggregate_retry_seconds
        ) from None


def ensure_upload_secret(
    rt: Runtime, body: Mapping[str, Any], test: UavTest, run_id: str, logger: logging.Logger
) -> None:
    """The run's Secret ``<job>-upload`` (its upload-only policy), created before the Job.

    Idempotent: one that exists already (an operator restarted between creating it and the Job) is
    kept as it is when it belongs to this UavTest; when it expires before the Job's deadline could
    end, a Warning says so. A Secret of that name that is not this UavTest's is never used.
    """
    namespace = test.metadata.namespace or "default"
    name = upload_secret_name(test.metadata.name, run_id)
    now = datetime.now(UTC)
    window = upload_window(test.spec, rt.config, now)
    meta = rt.kube.secret_metadata(namespace, name)
    if meta is None:
        policy = _sign_upload_policy(rt, test, run_id, window)
        if rt.kube.create_secret(namespace, build_upload_secret(test, run_id, policy, dict(body))):
            until = policy.expires.isoformat()
            logger.info(f"created Secret {name}: uploads to {policy.where()} until {until}")
            if window.clamped:
                _warn(
                    body,
                    logger,
                    f"the run's upload policy expires at {window.expires.isoformat()} (S3 signs for at most "
                    f"7 days), before the Job's deadline of {deadline_seconds(test.spec, rt.config)} s "
                    "could end: replicas still running then cannot store their artifacts (fewer "
                    "replicas or more parallelism shorten the deadline)",
                )
            return
        meta = rt.kube.secret_metadata(namespace, name)  # created meanwhile by another attempt
        if meta is None:
            raise kopf.TemporaryError(f"Secret {namespace}/{name} came and went; retrying", delay=5)
    uid = str(body.get("metadata", {}).get("uid", ""))
    if not owned_by(meta, uid):
        raise kopf.TemporaryError(
            f"Secret {namespace}/{name} exists and does not belong to this UavTest (uid {uid}): the run "
            "needs that name for its upload policy; delete that Secret and the run starts",
            delay=60,
        )
    expires = upload_expires(meta)
    must_last = now + timedelta(seconds=deadline_seconds(test.spec, rt.config))
    logger.info(f"Secret {name} exists already: kept (expires {expires.isoformat() if expires else '?'})")
    if expires is None or expires < must_last:
        _warn(
            body,
            logger,
            f"the run's upload Secret {name} (kept from an earlier start) expires at "
            f"{expires.isoformat() if expires else 'an unknown time'}, before the Job's deadline could "
            "end: replicas still running then cannot store their artifacts; delete and re-apply the "
            "UavTest for a fresh one",
        )


def start_run(rt: Runtime, body: Mapping[str, Any], jobs: Iterable[JobView], logger: logging.Logger) -> None:
    """Create the run's ConfigMap, upload Secret and Job unless the Job exists (the Job index is the
    lookup), then status."""
    view = run_view(body)
    try:
        if not view.has_spec or not _owned(body):
            body = _fill_spec(rt, body, view)
            view = run_view(body)
        test = parse_test(body)
        files = unresolved_files(test.spec)
        if files:
            raise BadInput(
                "a cluster cannot read files: render the test first (uavtest render, or uavtest run "
                "--engine kubernetes)",
                field=files[0],
            )
        job = job_of(jobs, view.run_id)
        if job is None:
            owner = dict(body)
            configmap = build_configmap(test, view.run_id, owner)
            manifest = build_job(test, view.run_id, rt.config, owner)
        else:
            configmap = manifest = None
    except BadInput as e:
        _invalid(rt, body, view, str(e), logger)
        return
    if configmap is not None and manifest is not None:
        rt.kube.create_configmap(view.namespace, configmap)
        if uses_upload_policy(rt.config):
            ensure_upload_secret(rt, body, test, view.run_id, logger)
        created = rt.kube.create_job(view.namespace, manifest)
        if created is not None:
            job = job_view(created)
            logger.info(f"created Job {job.name}: {view.replicas} replicas")
            kopf.event(  # type: ignore[arg-type]
                body, type="Normal", reason=names.EventReason.JOB_CREATED, message=f"Job {job.name}"
            )
        else:
            logger.info(f"Job {manifest['metadata']['name']} exists already")
    sync_run(rt, view, job, [])


def sync_run(
    rt: Runtime, test: RunView, job: JobView | None, pods: Iterable[PodView], *, job_deleted: bool = False
) -> None:
    """Recompute the status from the Job and pods; patch it when it changed (never a final one).

    ``job_deleted``: this call comes from the run's Job being deleted (not merely not seen yet).
    """
    book = rt.books.get((test.namespace, test.name))
    with book.lock:
        if book.final or is_final(test.status):
            book.final = True
            return
        book.job_deleted = book.job_deleted or job_deleted
        previous = book.status if book.status is not None else test.status
        current = test.model_copy(update={"status": previous})
        status = status_from(
            current,
            job,
            list(pods),
            store_url=rt.config.store_url,
            job_deleted=book.job_deleted,
            aggregation_error=book.aggregation_error,
        )
        _write(rt, book, test, status)


def aggregate(
    rt: Runtime,
    body: Mapping[str, Any],
    job: JobView | None,
    pods: Iterable[PodView],
    logger: logging.Logger,
) -> RunSummary | None:
    """Aggregate a run whose replicas all finished: aggregate/ in the store, final status, Events.

    When the store cannot be reached the status says so (Complete False, StoreUnavailable) and the
    caller (a kopf timer) comes back later; a replica with missing artifacts is an ``error``.
    """
    view = run_view(body)
    test = parse_test(body)
    book = rt.books.get((view.namespace, view.name))
    pods = list(pods)
    with book.lock:
        previous = book.status if book.status is not None else view.status
        if book.final or is_final(previous) or not awaiting_aggregation(previous):
            return None
        current = view.model_copy(update={"status": previous})
        try:
            from uavtest.engine.aggregate import aggregate_run

            summary = aggregate_run(
                rt.store(), view.namespace, view.test, view.run_id, range(view.replicas), test.spec
            )
        except UavTestError as e:
            rt.metrics.reconcile_errors.labels(handler="aggregate").inc()
            logger.warning(f"aggregation failed, will retry: {e}")
            book.aggregation_error = str(e)
            status = status_from(
                current,
                job,
                pods,
                store_url=rt.config.store_url,
                job_deleted=book.job_deleted,
                aggregation_error=str(e),
            )
            _write(rt, book, view, status)
            kopf.event(  # type: ignore[arg-type]
                body, type="Warning", reason=names.EventReason.STORE_UNAVAILABLE, message=str(e)[:1024]
            )
            return None
        status = status_from(
            current, job, pods, store_url=rt.config.store_url, job_deleted=book.job_deleted, summary=summary
        )
        _write(rt, book, view, status)
        book.final = True
        book.aggregation_error = None
    rt.metrics.record_run(summary, status.phase.value.lower())
    logger.info(f"run {view.run_id} aggregated: {status.message}")
    for ev in events_for(summary, status.phase):
        kopf.event(body, type=ev.type, reason=ev.reason, message=ev.message)  # type: ignore[arg-type]
    return summary
