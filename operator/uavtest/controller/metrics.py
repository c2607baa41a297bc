"""Prometheus metrics of the operator (prometheus-client), served on the metrics port.

Two kinds:

- computed from the UavTest objects at scrape time (a custom collector over the operator's
  in-memory index of tests), so a deleted test leaves no stale series:
  ``uavtest_replicas_total{namespace,test,verdict}`` (replicas of the test's run that ended with
  that verdict), ``uavtest_test_flakiness{namespace,test}``, ``uavtest_tests{namespace,phase}``;
- recorded when something happens (counters and histograms for the operator's lifetime):
  ``uavtest_runs_total{namespace,result}`` (a run aggregated; result succeeded / failed / error),
  ``uavtest_min_obstacle_distance_meters{namespace}`` and ``uavtest_replica_duration_seconds{namespace}``
  (one observation per replica at aggregation), ``uavtest_reconcile_errors_total{handler}``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

from prometheus_client import CollectorRegistry, Counter, Histogram, start_http_server
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily, Metric
from prometheus_client.registry import Collector

from uavtest.analysis.models import RunSummary, Verdict
from uavtest.controller.views import UavTestView

__all__ = ["DISTANCE_BUCKETS", "DURATION_BUCKETS", "Metrics", "TestsCollector"]

DISTANCE_BUCKETS = (0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0)
DURATION_BUCKETS = (5.0, 10.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1200.0, 3600.0)


class TestsCollector(Collector):
    """Series computed from the current UavTests (their status) each time Prometheus scrapes."""

    def __init__(self, tests: Callable[[], Iterable[UavTestView]]) -> None:
        self._tests = tests

    def collect(self) -> Iterator[Metric]:
        replicas = CounterMetricFamily(
            "uavtest_replicas",
            "Replicas of a test's run that ended with a verdict (pass, fail, error)",
            labels=["namespace", "test", "verdict"],
        )
        flakiness = GaugeMetricFamily(
            "uavtest_test_flakiness",
            "Failed / valid replicas of a test's run (0 always passes, 1 always fails)",
            labels=["namespace", "test"],
        )
        phases = GaugeMetricFamily("uavtest_tests", "UavTests by phase", labels=["namespace", "phase"])
        by_phase: dict[tuple[str, str], int] = {}
        for test in self._tests():
            status: dict[str, Any] = test.status
            for verdict, field in (
                (Verdict.PASS, "passed"),
                (Verdict.FAIL, "failed"),
                (Verdict.ERROR, "errors"),
            ):
                replicas.add_metric([test.namespace, test.name, verdict.value], float(status.get(field) or 0))
            if status.get("flakiness") is not None:
                flakiness.add_metric([test.namespace, test.name], float(status["flakiness"]))
            key = (test.namespace, str(status.get("phase") or "Pending"))
            by_phase[key] = by_phase.get(key, 0) + 1
        for (namespace, phase), n in sorted(by_phase.items()):
            phases.add_metric([namespace, phase], float(n))
        yield replicas
        yield flakiness
        yield phases


class Metrics:
    """The operator's metrics registry: its own registry, so several operators can live in one process."""

    def __init__(self, tests: Callable[[], Iterable[UavTestView]]) -> None:
        self.registry = CollectorRegistry(auto_describe=True)
        self.registry.register(TestsCollector(tests))
        self.runs = Counter(
            "uavtest_runs",
            "Runs aggregated by this operator, by result (succeeded, failed, error)",
            ["namespace", "result"],
            registry=self.registry,
        )
        self.min_distance = Histogram(
            "uavtest_min_obstacle_distance_meters",
            "Smallest 3-D distance to any obstacle over a replica's flight",
            ["namespace"],
            buckets=DISTANCE_BUCKETS,
            registry=self.registry,
        )
        self.duration = Histogram(
            "uavtest_replica_duration_seconds",
            "Wall-clock seconds one replica took",
            ["namespace"],
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
        self.runs.labels(namespace=ns, result=result).inc()
        for r in summary.results:
            if (
                r.verdict != Verdict.ERROR
                and r.metrics is not None
                and r.metrics.min_obstacle_distance is not None
            ):
                self.min_distance.labels(namespace=ns).observe(r.metrics.min_obstacle_distance)
            if r.wall_time is not None:
                self.duration.labels(namespace=ns).observe(r.wall_time)

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
