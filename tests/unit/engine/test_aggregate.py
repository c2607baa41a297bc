"""Aggregation of a run from a real LocalStore: counts, missing artifacts, aggregate files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from uavtest.analysis.average import AverageTrajectory
from uavtest.analysis.models import FlightMetrics, ReplicaResult, RunSummary, Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.engine.aggregate import aggregate_run
from uavtest.spec.models import UavTestSpec
from uavtest.store import LocalStore
from uavtest.store.layout import aggregate_key, replica_key

NS, TEST, RUN = "local", "near-miss", "20250101-000000-abcd"


def _spec() -> UavTestSpec:
    return UavTestSpec.model_validate(
        {
            "replicas": 5,
            "seed": 100,
            "mission": {"waypoints": [{"x": 10, "y": 0, "z": -5}]},
            "world": {"obstacles": [{"size": {"l": 2, "w": 2, "h": 8}, "position": {"x": 5, "y": 3}}]},
        }
    )


def _put_replica(store: LocalStore, i: int, verdict: Verdict, *, trajectory: bool = True) -> None:
    dist = 2.0 if verdict == Verdict.PASS else 1.1
    result = ReplicaResult(
        index=i,
        seed=100 + i,
        verdict=verdict,
        reason="" if verdict == Verdict.PASS else "min distance 1.10 m < 1.5 m (short by 0.40 m)",
        metrics=FlightMetrics(flight_time=20.0 + i, min_obstacle_distance=dist),
    )
    store.put(replica_key(NS, TEST, RUN, i, "result.json"), result.model_dump_json().encode())
    if trajectory:
        t = np.linspace(0, 20 + i, 50)
        tr = Trajectory(t, t / 2, np.full_like(t, 0.1 * i), np.full_like(t, -5.0))
        store.put(replica_key(NS, TEST, RUN, i, "trajectory.csv"), tr.to_csv().encode())


def test_aggregate_counts_missing_artifacts_as_errors_and_writes_the_aggregate(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    _put_replica(store, 0, Verdict.PASS)
    _put_replica(store, 1, Verdict.FAIL)
    _put_replica(store, 2, Verdict.PASS)
    # replica 3 wrote nothing; replica 4 passed but its trajectory is gone
    _put_replica(store, 4, Verdict.PASS, trajectory=False)

    summary = aggregate_run(store, NS, TEST, RUN, range(5), _spec())

    assert (summary.passed, summary.failed, summary.errors) == (2, 1, 2)
    assert summary.flakiness is not None and abs(summary.flakiness - 1 / 3) < 1e-9
    assert summary.flaky is True
    by_index = {r.index: r for r in summary.results}
    assert by_index[3].verdict == Verdict.ERROR and by_index[3].seed == 103
    assert by_index[3].reason == f"artifacts missing: {replica_key(NS, TEST, RUN, 3, 'result.json')}"
    assert by_index[4].reason == f"artifacts missing: {replica_key(NS, TEST, RUN, 4, 'trajectory.csv')}"

    written = RunSummary.model_validate_json(store.get(aggregate_key(NS, TEST, RUN, "summary.json")))
    assert written == summary
    average = AverageTrajectory.from_csv(store.get(aggregate_key(NS, TEST, RUN, "average.csv")).decode())
    assert len(average.t) > 0
    assert np.allclose(average.mean[:, 2], -5.0)
    assert store.get(aggregate_key(NS, TEST, RUN, "trajectories.png")).startswith(b"\x89PNG")


def test_aggregate_of_only_errors_writes_a_summary_without_plot(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    error = ReplicaResult(index=0, seed=100, verdict=Verdict.ERROR, reason="simulator exited with code 1")
    store.put(replica_key(NS, TEST, RUN, 0, "result.json"), error.model_dump_json().encode())
    store.put(replica_key(NS, TEST, RUN, 1, "result.json"), b"{not json")

    summary = aggregate_run(store, NS, TEST, RUN, [0, 1], _spec())

    assert (summary.passed, summary.failed, summary.errors) == (0, 0, 2)
    assert summary.flakiness is None and summary.flaky is False
    assert summary.results[0].reason == "simulator exited with code 1"
    assert summary.results[1].reason.startswith("unreadable ")
    assert json.loads(store.get(aggregate_key(NS, TEST, RUN, "summary.json")))["verdict"] == "error"
    assert not store.exists(aggregate_key(NS, TEST, RUN, "trajectories.png"))


def test_the_summary_names_params_the_builtin_simulator_ignores(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    _put_replica(store, 0, Verdict.PASS)
    spec = _spec().model_copy(deep=True)
    spec.vehicle.params = {"NAV_ACC_RAD": 1.0, "EKF2_GPS_DELAY": 100.0}
    summary = aggregate_run(store, NS, TEST, RUN, [0], spec)
    assert summary.unmodelled_params == ["EKF2_GPS_DELAY"]
    stored = json.loads(store.get(aggregate_key(NS, TEST, RUN, "summary.json")))
    assert stored["unmodelled_params"] == ["EKF2_GPS_DELAY"]


def test_the_aggregate_has_a_junit_report_linking_each_replicas_artifacts(tmp_path: Path) -> None:
    import junitparser

    store = LocalStore(tmp_path)
    _put_replica(store, 0, Verdict.PASS)
    _put_replica(store, 1, Verdict.FAIL)
    aggregate_run(store, NS, TEST, RUN, [0, 1, 2], _spec())
    doc = junitparser.JUnitXml.fromfile(str(store.path(aggregate_key(NS, TEST, RUN, "junit.xml"))))
    (suite,) = list(doc)
    assert (suite.name, suite.tests, suite.failures, suite.errors) == (TEST, 3, 1, 1)
    cases = {c.name: c for c in suite}
    assert f"flight.ulg: {store.path(replica_key(NS, TEST, RUN, 1, 'flight.ulg'))}" in (
        cases["replica-1"].system_out or ""
    )
    assert {p.name: p.value for p in suite.properties()}["uavtest.seeds"] == "100..102"
