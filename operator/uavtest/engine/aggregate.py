"""A run's aggregation: replicas' artifacts in a store → ``aggregate/`` and a ``RunSummary``.

Shared by the local engine (LocalStore) and the Kubernetes operator (S3Store): it knows the
store layout and ``uavtest.analysis``, nothing about how the replicas were flown.
"""

from __future__ import annotations

from collections.abc import Iterable

from pydantic import ValidationError

from uavtest.analysis.models import ReplicaResult, RunSummary, Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import UavTestError
from uavtest.spec.models import UavTestSpec
from uavtest.spec.px4_params import unmodelled_params
from uavtest.store import ArtifactStore
from uavtest.store.layout import FLIGHT_LOG, JUNIT, RESULT, SUMMARY, aggregate_key, replica_key
from uavtest.store.local import LocalStore

__all__ = ["aggregate_run", "artifact_links", "load_replica"]


def _missing(index: int, seed: int, what: str) -> ReplicaResult:
    return ReplicaResult(index=index, seed=seed, verdict=Verdict.ERROR, reason=f"artifacts missing: {what}")


def load_replica(
    store: ArtifactStore, namespace: str, test: str, run_id: str, index: int, seed: int
) -> tuple[ReplicaResult, Trajectory | None]:
    """One replica's result and (for pass / fail) trajectory; an ``error`` result when missing.

    A replica whose result.json is absent or unreadable, or whose pass / fail has no readable
    trajectory.csv, becomes ``error`` with the reason — it is never dropped from the run.
    """
    result_key = replica_key(namespace, test, run_id, index, "result.json")
    if not store.exists(result_key):
        return _missing(index, seed, result_key), None
    try:
        result = ReplicaResult.model_validate_json(store.get(result_key))
    except ValidationError as e:
        reason = f"unreadable {result_key}: {e.errors()[0]['msg']}"
        return ReplicaResult(index=index, seed=seed, verdict=Verdict.ERROR, reason=reason), None
    if result.verdict == Verdict.ERROR:
        return result, None
    traj_key = replica_key(namespace, test, run_id, index, "trajectory.csv")
    if not store.exists(traj_key):
        return result.model_copy(
            update={"verdict": Verdict.ERROR, "reason": f"artifacts missing: {traj_key}"}
        ), None
    try:
        trajectory = Trajectory.from_csv(store.get(traj_key).decode(errors="replace"), source=traj_key)
    except UavTestError as e:
        return result.model_copy(update={"verdict": Verdict.ERROR, "reason": str(e)}), None
    return result, trajectory


def _reference(spec: UavTestSpec) -> Trajectory | None:
    """The inline reference trajectory of a similarity assertion (a rendered test has one)."""
    similarity = spec.assertions.similarity
    if similarity is None or similarity.reference is None:
        return None
    t, x, y, z = zip(*similarity.reference.points, strict=True)
    return Trajectory(t, x, y, z)


def artifact_links(
    store: ArtifactStore, namespace: str, test: str, run_id: str, indices: Iterable[int]
) -> dict[int, dict[str, str]]:
    """Each replica's flight log and result: file paths in a local store, else the store's URIs."""

    def where(key: str) -> str:
        return str(store.path(key)) if isinstance(store, LocalStore) else store.url(key)

    return {
        i: {name: where(replica_key(namespace, test, run_id, i, name)) for name in (FLIGHT_LOG, RESULT)}
        for i in indices
    }


def aggregate_run(
    store: ArtifactStore,
    namespace: str,
    test: str,
    run_id: str,
    indices: Iterable[int],
    spec: UavTestSpec,
) -> RunSummary:
    """Read the replicas ``indices`` of a run, write ``aggregate/*`` and return the summary.

    Writes ``aggregate/summary.json`` and ``aggregate/junit.xml`` always, and ``aggregate/average.csv`` and
    ``aggregate/trajectories.png`` when at least one replica has a trajectory.
    """
    from uavtest.analysis.average import average_trajectories
    from uavtest.analysis.flakiness import summarize
    from uavtest.analysis.junit import junit_document, run_suite
    from uavtest.analysis.plots import plot_run
    from uavtest.analysis.verdict import simulator_warnings

    results: list[ReplicaResult] = []
    trajectories: list[Trajectory] = []
    for index in sorted(set(indices)):
        result, trajectory = load_replica(store, namespace, test, run_id, index, spec.replica_seed(index))
        results.append(result)
        if trajectory is not None and len(trajectory) >= 2 and trajectory.duration > 0:
            trajectories.append(trajectory)
    summary = summarize(results, test=test, namespace=namespace, run_id=run_id)
    summary = summary.model_copy(update={"unmodelled_params": unmodelled_params(spec)})
    # the simulator's limits, also when no replica wrote a result.json
    summary.warnings = list(dict.fromkeys([*simulator_warnings(spec), *summary.warnings]))
    if trajectories:
        average = average_trajectories(trajectories)
        store.put(
            aggregate_key(namespace, test, run_id, "average.csv"), average.to_csv().encode(), "text/csv"
        )
        png = plot_run(
            trajectories,
            average=average,
            reference=_reference(spec),
            obstacles=spec.world.obstacles,
            title=f"{test} · run {run_id} · {summary.passed} passed, {summary.failed} failed",
        )
        store.put(aggregate_key(namespace, test, run_id, "trajectories.png"), png, "image/png")
    # junit.xml before summary.json: summary.json is the last artifact, the sign aggregation ended
    links = artifact_links(store, namespace, test, run_id, (r.index for r in summary.results))
    store.put(
        aggregate_key(namespace, test, run_id, JUNIT),
        junit_document([run_suite(summary, links)]),
        "application/xml",
    )
    store.put(
        aggregate_key(namespace, test, run_id, SUMMARY),
        summary.model_dump_json(indent=2).encode(),
        "application/json",
    )
    return summary
