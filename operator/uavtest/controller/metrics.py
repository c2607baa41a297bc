"""Prometheus metrics of the operator (prometheus-client), served on the metrics port.

Keyed by the test (the UavTest's name), not by the run, so a test is one series across its runs.
The namespace label is ``test_namespace``: scrape setups (ServiceMonitor, annotation-based jobs)
add a ``namespace`` target label of the operator's pod, which would rename ours
``exported_namespace``.

- computed from the UavTests (their status: a summary of the kept runs) at scrape time, so a
  deleted test leaves no stale series (gauges):
  ``uavtest_test_last_run_replicas{test_namespace,test,verdict}`` (replicas of the newest run that
  ended with that verdict), ``uavtest_test_last_run_flakiness{test_namespace,test}``,
  ``uavtest_test_flaky_rate{test_namespace,test}`` (flaky runs / finished runs among the kept ones),
  ``uavtest_test_kept_runs{test_namespace,test,result}`` (kept runs: succeeded / failed / active),
  ``uavtest_test_failed_runs_in_a_row{test_namespace,test}`` (runs in a row that failed, up to the
  newest finished one: a pass resets it; history limits do not cut it short),
  ``uavtest_tests{test_namespace,phase}`` (tests by the phase of their newest run);
- counted when a run is aggregated (counters: once per run, as the final status is written once;
  a restarted operator never aggregates a finished run again, so nothing is counted twice; Prometheus'
  ``increase()`` handles the restart's reset to 0):
  ``uavtest_test_runs_total{test_namespace,test,result}`` (result succeeded / failed / error),
  ``uavtest_test_flaky_runs_total{test_namespace,test}``,
  ``uavtest_min_obstacle_distance_meters{test_namespace}`` and
  ``uavtest_replica_duration_seconds{test_namespace}`` (one observation per replica),
  ``uavtest_reconcile_errors_total{handler}``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

from prometheus_client import CollectorRegistry, Counter, Histogram, start_http_server
from prometheus_client.core import GaugeMetricFamily, Metric
from prometheus_client.registry import Collector

from uavtest.analysis.models import RunSummary, Verdict
from uavtest.controller.views import TestView

__all__ = ["DISTANCE_BUCKETS", "DURATION_BUCKETS", "Metrics", "TestsCollector"]

DISTANCE_BUCKETS = (0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0)
DURATION_BUCKETS = (5.0, 10.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1200.0, 3600.0)
NS = "test_namespace"


class TestsCollector(Collector):
    """Series computed from the current UavTests (their status) each time Prometheus scrapes."""

    __test__ = False  # not a pytest class

    def __init__(self, tests: Callable[[], Iterable[TestView]]) -> None:
        self._tests = tests

    def collect(self) -> Iterator[Metric]:
        replicas = GaugeMetricFamily(
            "uavtest_test_last_run_replicas",
            "Replicas of the test's newest run that ended with a verdict (pass, fail, error)",
            labels=[NS, "test", "verdict"],
        )
        flakiness = GaugeMetricFamily(
            "uavtest_test_last_run_flakiness",
            "Failed / valid replicas of the test's newest finished run (0 always passes, 1 always fails)",
            labels=[NS, "test"],
        )
        rate = GaugeMetricFamily(
            "uavtest_test_flaky_rate",
            "Flaky runs / finished runs among the test's kept runs",
            labels=[NS, "test"],
        )
        kept = GaugeMetricFamily(
            "uavtest_test_kept_runs",
            "The test's runs kept in the cluster, by result",
            labels=[NS, "test", "result"],
        )
        in_a_row = GaugeMetricFamily(
            "uavtest_test_failed_runs_in_a_row",
            "Runs of the test in a row that failed, up to its newest finished run (a pass resets it)",
            labels=[NS, "test"],
        )
        phases = GaugeMetricFamily(
            "uavtest_tests", "UavTests by the phase of their newest run", labels=[NS, "phase"]
        )
        by_phase: dict[tuple[str, str], int] = {}
        for test in self._tests():
            status: dict[str, Any] = test.status
            last = status.get("lastRun") or {}
            key = [test.namespace, test.name]
            for verdict, field in (
                (Verdict.PASS, "passed"),
                (Verdict.FAIL, "failed"),
                (Verdict.ERROR, "errors"),
            ):
                replicas.add_metric([*key, verdict.value], float(last.get(field) or 0))
            if last.get("flakiness") is not None:
                flakiness.add_metric(key, float(last["flakiness"]))
            if status.get("flakyRate") is not None:
                rate.add_metric(key, float(status["flakyRate"]))
            for result in ("succeeded", "failed", "active"):
                kept.add_metric([*key, result], float(status.get(result) or 0))
            in_a_row.add_metric(key, float(status.get("failedInARow") or 0))
            pkey = (test.namespace, str(status.get("phase") or "Pending"))
            by_phase[pkey] = by_phase.get(pkey, 0) + 1
        for (namespace, phase), n in sorted(by_phase.items()):
            phases.add_metric([namespace, phase], float(n))
        yield replicas
        yield flakiness
        yield rate
        yield kept
        yield in_a_row
        yield phases


class Metrics:
    """The operator's metrics registry: its own registry, so several operators can live in one process."""

    def __init__(self, tests: Callable[[], Iterable[TestView]]) -> None:
        self.registry = CollectorRegistry(auto_describe=True)
        self.registry.register(TestsCollector(tests))
        self.runs = Counter(
            "uavtest_test_runs",
            "Runs of a test aggregated by this operator, by result (succeeded, failed, error)",
            [NS, "test", "result"],
            registry=self.registry,
        )
        self.flaky_runs = Counter(
            "uavtest_test_flaky_runs",
            "Runs of a test aggregated by this operator whose valid replicas both passed and failed",
            [NS, "test"],
            registry=self.registry,
        )
        self.min_distance = Histogram(
            "uavtest_min_obstacle_distance_meters",
            "Smallest 3-D distance to any obstacle over a replica's flight",
            [NS],
            buckets=DISTANCE_BUCKETS,
            registry=self.registry,
        )
        self.duration = Histogram(
            "uavtest_replica_duration_seconds",
            "Wall-clock seconds one replica took",
            [NS],
            buckets=DURATION_BUCKETS,
            registry=self.registry,
        )
        self.reconcile_errors = Counter(
            "uavtest_reconcile_errors",
            "Errors while reconciling a UavTest (creating children, updating status, aggregating)",
            ["handler"],
            registry=self.registry,
        )
        self._server: Any = None

    def record_run(self, summary: RunSummary, result: str) -> None:
        """Count one aggregated run and observe each replica's min distance and duration."""
        ns = summary.namespace
        self.runs.labels(ns, summary.test, result).inc()
        if summary.flaky:
            self.flaky_runs.labels(ns, summary.test).inc()
        for r in summary.results:
            if (
                r.verdict != Verdict.ERROR
                and r.metrics is not None
                and r.metrics.min_obstacle_distance is not None
            ):
                self.min_distance.labels(ns).observe(r.metrics.min_obstacle_distance)
            if r.wall_time is not None:
                self.duration.labels(ns).observe(r.wall_time)

    def serve(self, port: int, addr: str = "0.0.0.0") -> int:
        """Serve /metrics on ``addr:port`` (port 0: any free port); returns the port."""
        server, _thread = start_http_server(port, addr=addr, registry=self.registry)
        self._server = server
        return int(server.server_port)

    def close(self) -> None:
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()
            self._server = None
