"""Prometheus metrics scraped over real HTTP, and the Events a finished run posts."""

from __future__ import annotations

import urllib.request
from collections.abc import Iterator

import pytest
from prometheus_client.parser import text_string_to_metric_families

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.controller.events import events_for
from uavtest.controller.metrics import Metrics
from uavtest.controller.views import TestView, test_view
from uavtest.spec.status import Phase

from .controller_bodies import RUN, test_body


def view(name: str, status: dict[str, object]) -> TestView:
    return test_view(test_body(name=name, status=status))


def last_run(phase: str, passed: int, failed: int, errors: int, flakiness: float | None) -> dict[str, object]:
    return {
        "name": "r",
        "phase": phase,
        "passed": passed,
        "failed": failed,
        "errors": errors,
        "flakiness": flakiness,
    }


def result(index: int, verdict: Verdict, distance: float = 2.0, wall: float = 42.0) -> ReplicaResult:
    metrics = None if verdict == Verdict.ERROR else FlightMetrics(min_obstacle_distance=distance)
    return ReplicaResult(index=index, seed=index, verdict=verdict, metrics=metrics, wall_time=wall)


@pytest.fixture
def tests_now() -> list[TestView]:
    return [
        view(
            "flaky",
            {
                "phase": "Failed",
                "lastRun": last_run("Failed", 3, 1, 1, 0.25),
                "runs": 4,
                "succeeded": 2,
                "failed": 2,
                "flakyRuns": 1,
                "flakyRate": 0.25,
                "failedInARow": 2,
            },
        ),
        view(
            "steady",
            {"phase": "Succeeded", "lastRun": last_run("Succeeded", 5, 0, 0, 0.0), "runs": 1, "succeeded": 1},
        ),
        view("starting", {"phase": "Pending"}),
    ]


@pytest.fixture
def metrics(tests_now: list[TestView]) -> Iterator[tuple[Metrics, int]]:
    m = Metrics(lambda: list(tests_now))
    port = m.serve(0, addr="127.0.0.1")
    yield m, port
    m.close()


def scrape(port: int) -> dict[tuple[str, tuple[tuple[str, str], ...]], float]:
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=10) as resp:
        text = resp.read().decode()
    out = {}
    for family in text_string_to_metric_families(text):
        for s in family.samples:
            out[(s.name, tuple(sorted(s.labels.items())))] = s.value
    return out


def test_test_series_are_computed_from_the_resources_at_scrape_time(
    metrics: tuple[Metrics, int], tests_now: list[TestView]
) -> None:
    _, port = metrics
    got = scrape(port)
    ns = ("test_namespace", "team-a")  # not "namespace": scrape setups overwrite that one
    flaky = (("test", "flaky"), ns)
    assert got[("uavtest_test_last_run_replicas", (*flaky, ("verdict", "fail")))] == 1
    assert got[("uavtest_test_last_run_replicas", (*flaky, ("verdict", "pass")))] == 3
    assert got[("uavtest_test_last_run_replicas", (*flaky, ("verdict", "error")))] == 1
    assert got[("uavtest_test_last_run_flakiness", flaky)] == 0.25
    assert got[("uavtest_test_last_run_flakiness", (("test", "steady"), ns))] == 0.0
    assert ("uavtest_test_last_run_flakiness", (("test", "starting"), ns)) not in got  # no run yet
    assert got[("uavtest_test_flaky_rate", flaky)] == 0.25
    assert got[("uavtest_test_kept_runs", (("result", "failed"), *flaky))] == 2
    assert got[("uavtest_tests", (("phase", "Pending"), ns))] == 1
    assert got[("uavtest_test_failed_runs_in_a_row", flaky)] == 2
    assert got[("uavtest_test_failed_runs_in_a_row", (("test", "steady"), ns))] == 0
    # gauges, not counters: computed from the current status (a run's replicas, not a running total)
    assert "uavtest_test_last_run_replicas_total" not in {name for name, _ in got}
    # a deleted test leaves no stale series
    tests_now.pop(0)
    again = scrape(port)
    assert not any(labels and ("test", "flaky") in labels for (_, labels) in again)


def test_aggregated_runs_are_counted_and_observed(metrics: tuple[Metrics, int]) -> None:
    m, port = metrics
    summary = summarize(
        [
            result(0, Verdict.PASS, 2.5, 30),
            result(1, Verdict.FAIL, 0.4, 50),
            result(2, Verdict.ERROR, wall=5),
        ],
        test="flaky",
        namespace="team-a",
        run_id=RUN,
    )
    m.record_run(summary, "failed")
    m.reconcile_errors.labels(handler="aggregate").inc()
    got = scrape(port)
    ns = ("test_namespace", "team-a")
    assert got[("uavtest_test_runs_total", (("result", "failed"), ("test", "flaky"), ns))] == 1
    assert got[("uavtest_test_flaky_runs_total", (("test", "flaky"), ns))] == 1
    assert got[("uavtest_min_obstacle_distance_meters_count", (ns,))] == 2  # errors have no distance
    assert got[("uavtest_min_obstacle_distance_meters_bucket", (("le", "0.5"), ns))] == 1
    assert got[("uavtest_min_obstacle_distance_meters_sum", (ns,))] == pytest.approx(2.9)
    assert got[("uavtest_replica_duration_seconds_count", (ns,))] == 3
    assert got[("uavtest_replica_duration_seconds_sum", (ns,))] == 85
    assert got[("uavtest_reconcile_errors_total", (("handler", "aggregate"),))] == 1


def test_two_operators_in_one_process_have_separate_registries() -> None:
    a, b = Metrics(list), Metrics(list)
    a.runs.labels("x", "t", "succeeded").inc()
    labels = {"test_namespace": "x", "test": "t", "result": "succeeded"}
    assert a.registry.get_sample_value("uavtest_test_runs_total", labels) == 1
    assert b.registry.get_sample_value("uavtest_test_runs_total", labels) is None


def test_events_of_a_flaky_failing_run() -> None:
    summary = summarize(
        [result(0, Verdict.PASS), result(1, Verdict.FAIL, 0.5), result(2, Verdict.ERROR)],
        test="t",
        namespace="n",
        run_id=RUN,
    )
    events = events_for(summary, Phase.FAILED)
    reasons = [(e.type, e.reason) for e in events]
    assert reasons == [("Warning", "TestFailed"), ("Warning", "FlakyTest"), ("Warning", "ReplicaError")]
    assert "flakiness 0.50" in events[1].message
    assert "replica 2" in events[2].message


def test_events_of_a_passing_run_and_many_errors() -> None:
    passing = summarize([result(0, Verdict.PASS)], test="t", namespace="n", run_id=RUN)
    assert [(e.type, e.reason) for e in events_for(passing, Phase.SUCCEEDED)] == [("Normal", "TestPassed")]
    errors = summarize([result(i, Verdict.ERROR) for i in range(9)], test="t", namespace="n", run_id=RUN)
    events = events_for(errors, Phase.ERROR)
    errors_events = [e for e in events if e.reason == "ReplicaError"]
    assert len(errors_events) == 1  # one per run, not one per replica
    assert errors_events[0].message.startswith("9 of 9 replicas had bench errors: replica 0 (seed 0)")
    assert errors_events[0].message.endswith("and 6 more")
