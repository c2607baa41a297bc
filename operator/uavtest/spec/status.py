"""The status of a UavTest custom resource: counters, verdicts, artifacts and conditions.

Written only by the operator (through the ``/status`` subresource) and typed in the CRD like
the spec, so ``kubectl`` and GitOps tools see a documented shape. Kept bounded: the
per-replica list holds at most ``MAX_STATUS_RESULTS`` entries (failed and error replicas
first, then passed ones, each by index; ``resultsOmitted`` counts the rest); every replica's
full result stays in the object store under ``artifacts.store``.
"""

from __future__ import annotations

from collections.abc import Iterable
from datetime import datetime
from enum import StrEnum
from typing import Annotated

from pydantic import Field, field_validator

from uavtest.spec.models import Model

__all__ = [
    "MAX_STATUS_RESULTS",
    "Artifacts",
    "Condition",
    "ConditionReason",
    "ConditionStatus",
    "ConditionType",
    "LastRun",
    "Phase",
    "ReplicaStatus",
    "ReplicaVerdict",
    "TestStatus",
    "UavTestStatus",
    "compact_results",
]

MAX_STATUS_RESULTS = 50
MAX_REASON_LENGTH = 256
MAX_WARNINGS = 8
MAX_WARNING_LENGTH = 512


class Phase(StrEnum):
    """A human summary of the conditions (the ``Phase`` printer column)."""

    PENDING = "Pending"  # no replica has started yet
    RUNNING = "Running"  # some replica is flying or waiting to be retried
    SUCCEEDED = "Succeeded"  # every replica passed
    FAILED = "Failed"  # some replica failed an assertion
    ERROR = "Error"  # only bench errors, no valid replica verdict to report


class ReplicaVerdict(StrEnum):
    """Verdict of one finished replica; the same words as ``uavtest.analysis.models.Verdict``."""

    PASS = "pass"
    FAIL = "fail"
    ERROR = "error"


class ConditionStatus(StrEnum):
    TRUE = "True"
    FALSE = "False"
    UNKNOWN = "Unknown"


class ConditionType(StrEnum):
    """Condition types GitOps tools and ``kubectl wait --for=condition=...`` can wait on."""

    COMPLETE = "Complete"  # True when every replica has a final verdict (pass, fail or error)
    SUCCEEDED = "Succeeded"  # True when every replica passed; False once the run ended otherwise
    FAILED = "Failed"  # True when the run ended with a failing replica or only errors
    FLAKY = "Flaky"  # True when the valid replicas both passed and failed
    # kstatus (sigs.k8s.io/cli-utils) conventions that Flux and `kubectl wait` read without custom code:
    READY = "Ready"  # True when the (last) run passed
    RECONCILING = "Reconciling"  # abnormal-true: a run is in progress (kstatus InProgress)
    STALLED = "Stalled"  # abnormal-true: the (last) run failed or ended in errors (kstatus Failed)


class ConditionReason(StrEnum):
    """The documented CamelCase reasons of the conditions above."""

    PENDING = "ReplicasPending"
    RUNNING = "ReplicasRunning"
    ALL_PASSED = "AllReplicasPassed"
    SOME_FAILED = "ReplicasFailed"
    ONLY_ERRORS = "OnlyBenchErrors"
    FLAKY = "FlakyReplicas"
    STABLE = "StableReplicas"
    AGGREGATION_FAILED = "AggregationFailed"
    JOB_FAILED = "JobFailed"
    RUN_PASSED = "RunPassed"
    RUN_FAILED = "RunFailed"
    RUN_ERROR = "RunError"
    RUN_IN_PROGRESS = "RunInProgress"
    NO_RUN = "NoRunYet"


class Condition(Model):
    """A ``metav1.Condition``: ``lastTransitionTime`` changes only when ``status`` flips."""

    type: str = Field(pattern=r"^[A-Z][A-Za-z0-9]*$", max_length=316, description="CamelCase condition type")
    status: ConditionStatus
    reason: str = Field(
        pattern=r"^[A-Za-z]([A-Za-z0-9_,:]*[A-Za-z0-9_])?$", max_length=1024, description="CamelCase reason"
    )
    message: str = Field("", max_length=32768, description="human readable details")
    observed_generation: int | None = Field(
        None, ge=0, description="metadata.generation the condition is about"
    )
    last_transition_time: datetime = Field(description="when status last changed")


class ReplicaStatus(Model):
    """One finished replica, in brief; the full result is ``result.json`` in the store."""

    index: int = Field(ge=0)
    seed: int = Field(ge=0)
    verdict: ReplicaVerdict = Field(
        description="pass, fail (an assertion did not hold) or error (the bench failed)"
    )
    min_distance: float | None = Field(None, description="smallest 3-D distance to an obstacle, metres")
    min_distance_2d: float | None = Field(
        None, description="the UAV Testing Competition's 2-D distance to the obstacles, metres"
    )
    points: int | None = Field(
        None, ge=0, le=5, description="the competition's points: 5 (< 0.25 m), 2 (< 1 m), 1 (< 1.5 m), 0"
    )
    reason: str = Field(
        "", max_length=MAX_REASON_LENGTH, description="why it failed or errored; empty on pass"
    )

    @field_validator("reason", mode="before")
    @classmethod
    def _cut(cls, value: object) -> object:
        if isinstance(value, str) and len(value) > MAX_REASON_LENGTH:
            return value[: MAX_REASON_LENGTH - 1] + "…"
        return value


class Artifacts(Model):
    """URIs in the object store (``s3://bucket/...`` or ``file:///...``)."""

    store: str | None = Field(None, description="prefix of this run: <namespace>/<test>/<run-id>/")
    summary: str | None = Field(None, description="aggregate/summary.json")
    average: str | None = Field(None, description="aggregate/average.csv")
    plot: str | None = Field(None, description="aggregate/trajectories.png")


class UavTestStatus(Model):
    phase: Phase = Field(Phase.PENDING, description="Pending, Running, Succeeded, Failed or Error")
    replicas: int = Field(0, ge=0, description="replicas in this run")
    pending: int = Field(0, ge=0, description="replicas not started yet")
    running: int = Field(0, ge=0, description="replicas flying (or being retried)")
    passed: int = Field(0, ge=0)
    failed: int = Field(0, ge=0)
    errors: int = Field(0, ge=0, description="replicas that ended in a bench error (not counted as failures)")
    flakiness: float | None = Field(
        None, ge=0, le=1, description="failed / valid replicas; unset until a replica has a valid verdict"
    )
    flaky: bool = Field(False, description="valid replicas both passed and failed")
    run_id: str | None = Field(None, description="identifier of the run in the store")
    start_time: datetime | None = None
    completion_time: datetime | None = None
    observed_generation: int | None = Field(
        None, ge=0, description="metadata.generation this status is about"
    )
    message: str | None = Field(None, max_length=4096, description="human summary of the run")
    artifacts: Artifacts = Field(default_factory=Artifacts)
    conditions: list[Condition] = Field(default_factory=list, max_length=16)
    results: list[ReplicaStatus] = Field(
        default_factory=list,
        max_length=MAX_STATUS_RESULTS,
        description=f"at most {MAX_STATUS_RESULTS} finished replicas, failed first; all are in the store",
    )
    results_omitted: int = Field(0, ge=0, description="finished replicas left out of results")
    warnings: list[Annotated[str, Field(max_length=MAX_WARNING_LENGTH)]] = Field(
        default_factory=list,
        max_length=MAX_WARNINGS,
        description="what the run could not simulate (the simulator's limits, parameters without effect)",
    )

    @field_validator("warnings", mode="before")
    @classmethod
    def _bound_warnings(cls, value: object) -> object:
        if isinstance(value, list):
            cut = MAX_WARNING_LENGTH - 1
            return [w if len(w) <= MAX_WARNING_LENGTH else w[:cut] + "…" for w in value[:MAX_WARNINGS]]
        return value


class LastRun(Model):
    """The newest run of a test, in brief (the UavTestRun object has the details)."""

    name: str = Field(description="the UavTestRun's name")
    phase: Phase = Phase.PENDING
    trigger: str | None = Field(None, description="create, spec-change, rerun, schedule or manual")
    passed: int = Field(0, ge=0)
    failed: int = Field(0, ge=0)
    errors: int = Field(0, ge=0)
    flakiness: float | None = Field(None, ge=0, le=1)
    flaky: bool = False
    completion_time: datetime | None = None
    summary: str | None = Field(None, description="aggregate/summary.json of that run in the store")


class TestStatus(Model):
    """The status of a UavTest: a summary of its runs (each run is a UavTestRun it owns)."""

    __test__ = False  # not a pytest class

    phase: Phase = Field(Phase.PENDING, description="the phase of the newest run")
    observed_generation: int | None = Field(
        None, ge=0, description="metadata.generation whose run has been started"
    )
    spec_hash: str | None = Field(None, description="hash of the flown spec of the newest spec run")
    last_rerun: str | None = Field(None, description="the uavtest.io/rerun annotation value last acted on")
    last_schedule_time: datetime | None = Field(
        None, description="the newest scheduled time a run was started for"
    )
    last_run: LastRun | None = None
    runs: int = Field(0, ge=0, description="runs kept in the cluster")
    active: int = Field(0, ge=0, description="runs not finished")
    succeeded: int = Field(0, ge=0, description="kept runs that passed")
    failed: int = Field(0, ge=0, description="kept runs that failed or ended in bench errors")
    flaky_runs: int = Field(0, ge=0, description="kept finished runs that were flaky")
    flaky_rate: float | None = Field(
        None, ge=0, le=1, description="flaky runs / finished runs among the kept runs"
    )
    failed_in_a_row: int = Field(
        0,
        ge=0,
        description=(
            "runs in a row that failed, up to the newest finished one "
            "(a pass resets it; runs that ended in bench errors do not count)"
        ),
    )
    streak_run: str | None = Field(None, description="the newest finished run counted in failedInARow")
    streak_time: datetime | None = Field(None, description="that run's completion time")
    message: str | None = Field(None, max_length=4096)
    conditions: list[Condition] = Field(default_factory=list, max_length=16)


def compact_results(results: Iterable[ReplicaStatus]) -> tuple[list[ReplicaStatus], int]:
    """The bounded ``status.results`` list and how many replicas it leaves out.

    Failed replicas come first, then errors, then passes, each by index, so the ones a user
    wants to look at are always there (``ReplicaStatus`` cuts reasons to ``MAX_REASON_LENGTH``).
    """
    order = {ReplicaVerdict.FAIL: 0, ReplicaVerdict.ERROR: 1, ReplicaVerdict.PASS: 2}
    ranked = sorted(results, key=lambda r: (order[r.verdict], r.index))
    kept = ranked[:MAX_STATUS_RESULTS]
    return kept, len(ranked) - len(kept)
