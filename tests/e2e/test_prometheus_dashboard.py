"""The dashboard and the alert rules, proven on a real Prometheus (Debian's package).

The chart is installed for real (the operator in-cluster, its MinIO); Prometheus runs on the host
and finds the operator the way the chart's ServiceMonitor tells prometheus-operator to: the endpoints of
the Service selected by the ServiceMonitor's labels, its `metrics` port, and the target labels
prometheus-operator adds (`namespace`, `service`, `pod`), which is what would rename a metric
label called `namespace`. Debian's prometheus is built without Kubernetes discovery, so the test
reads the EndpointSlices and Services as that discovery would and hands Prometheus the targets
with their `__meta_kubernetes_*` labels through file_sd; the relabeling is Prometheus' own.
Tests live in a namespace of their own, not the operator's, so `test_namespace` must survive
scraping for the dashboard's namespace variable to work.

A passing test run twice (its re-run), a failing test run twice (failing 2 runs in a row), and a
flaky test; then every panel query of `charts/uavtest/files/dashboard.json` and every alert rule of
the chart's PrometheusRule is evaluated against Prometheus: each returns the series it should.
"""

from __future__ import annotations

import json
import re
import secrets
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from e2e.chart_support import CHART, Release, dev_image_values, installed
from e2e.operator_support import first_run, wait_complete, wait_exists
from harness.cluster import REPO_ROOT, Cluster
from harness.prometheus import PrometheusServer, helm_binary, render_rules

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

EXAMPLES = REPO_ROOT / "examples"
DASHBOARD = CHART / "files" / "dashboard.json"
SCRAPE = "2s"


def _example(name: str, test: str, namespace: str, **spec: Any) -> dict[str, Any]:
    doc = yaml.safe_load((EXAMPLES / name).read_text())
    doc["metadata"] = {"name": test, "namespace": namespace}
    doc["spec"].update(spec)
    return dict(doc)


def _rerun(cluster: Cluster, namespace: str, test: str, value: str) -> str:
    """Annotate a re-run; the name of the run it starts, once it exists."""
    cluster.kubectl(
        "annotate", "-n", namespace, f"uavtest/{test}", f"uavtest.io/rerun={value}", "--overwrite"
    )
    names: list[str] = []

    def started() -> bool:
        runs = cluster.kubectl_json("get", "uavtestruns", "-n", namespace, "-l", f"uavtest.io/test={test}")
        names[:] = [r["metadata"]["name"] for r in runs["items"] if r["spec"].get("trigger") == "rerun"]
        return bool(names)

    assert cluster.wait_until(started, 120, interval=1.0), f"no re-run of {test}"
    return names[0]


def _meta(name: str) -> str:
    return re.sub(r"[^a-zA-Z0-9_]", "_", name)


def discover_endpoints(cluster: Cluster, namespaces: list[str]) -> list[dict[str, Any]]:
    """What Prometheus' Kubernetes endpoints discovery yields, read from the EndpointSlices and
    Services: one target per ready address and port, with its ``__meta_kubernetes_*`` labels.
    (Debian's prometheus package is built without Kubernetes discovery; the test does the
    discovery and hands Prometheus the targets through file_sd, the relabeling stays Prometheus'.)"""
    groups = []
    for ns in namespaces:
        services = {
            s["metadata"]["name"]: s for s in cluster.kubectl_json("get", "services", "-n", ns)["items"]
        }
        for es in cluster.kubectl_json("get", "endpointslices", "-n", ns)["items"]:
            service = services.get(es["metadata"].get("labels", {}).get("kubernetes.io/service-name", ""))
            if service is None:
                continue
            labels = {
                "__meta_kubernetes_namespace": ns,
                "__meta_kubernetes_service_name": service["metadata"]["name"],
                **{
                    f"__meta_kubernetes_service_label_{_meta(k)}": v
                    for k, v in (service["metadata"].get("labels") or {}).items()
                },
            }
            for endpoint in es.get("endpoints") or []:
                if not endpoint.get("conditions", {}).get("ready"):
                    continue
                pod = (endpoint.get("targetRef") or {}).get("name", "")
                for port in es.get("ports") or []:
                    groups.append(
                        {
                            "targets": [f"{a}:{port['port']}" for a in endpoint["addresses"]],
                            "labels": {
                                **labels,
                                "__meta_kubernetes_pod_name": pod,
                                "__meta_kubernetes_endpoint_port_name": port.get("name", ""),
                            },
                        }
                    )
    return groups


def scrape_config(monitor: dict[str, Any], targets_file: Path) -> dict[str, Any]:
    """The chart's ServiceMonitor as prometheus-operator turns it into a scrape config: keep the
    endpoints of the selected Services' port, add the namespace / service / pod target labels."""
    spec = monitor["spec"]
    (endpoint,) = spec["endpoints"]
    keep = [
        {
            "source_labels": [f"__meta_kubernetes_service_label_{_meta(k)}"],
            "regex": re.escape(v),
            "action": "keep",
        }
        for k, v in spec["selector"]["matchLabels"].items()
    ]
    keep.append(
        {
            "source_labels": ["__meta_kubernetes_endpoint_port_name"],
            "regex": endpoint["port"],
            "action": "keep",
        }
    )
    targets = [
        {"source_labels": ["__meta_kubernetes_namespace"], "target_label": "namespace"},
        {"source_labels": ["__meta_kubernetes_service_name"], "target_label": "service"},
        {"source_labels": ["__meta_kubernetes_pod_name"], "target_label": "pod"},
        {"target_label": "endpoint", "replacement": endpoint["port"]},
    ]
    return {
        "job_name": f"serviceMonitor/{monitor['metadata']['namespace']}/{monitor['metadata']['name']}/0",
        "scrape_interval": SCRAPE,
        "metrics_path": endpoint["path"],
        "file_sd_configs": [{"files": [str(targets_file)]}],
        "relabel_configs": keep + targets,
    }


def render_service_monitor(release: Release) -> dict[str, Any]:
    out = subprocess.run(
        [
            str(helm_binary()), "template", release.name, str(CHART), "--namespace", release.namespace,
            "--set", "metrics.serviceMonitor.enabled=true", "--show-only", "templates/servicemonitor.yaml",
        ],
        check=True, capture_output=True, text=True,
    ).stdout  # fmt: skip
    return dict(yaml.safe_load(out))


@pytest.fixture(scope="module")
def tests_ns(cluster: Cluster) -> Iterator[str]:
    ns = cluster.create_namespace(f"prom-tests-{secrets.token_hex(3)}")
    yield ns
    cluster.delete_namespace(ns)


@pytest.fixture(scope="module")
def release(
    cluster: Cluster, tests_ns: str, operator_image: str, runner_image: str, minio_image: str
) -> Iterator[Release]:
    """The chart, its operator watching only the tests' namespace (tests other modules leave behind
    elsewhere stay out of this Prometheus' series)."""
    ns = cluster.create_namespace(f"prom-op-{secrets.token_hex(3)}")
    values = [
        *dev_image_values(operator_image, runner_image),
        "minio.enabled=true",
        f"minio.image={minio_image}",
        "minio.rootUser=uavtest",
        f"minio.rootPassword={secrets.token_hex(12)}",
        "store.createSecret=true",
        f"operator.watchNamespaces={{{tests_ns}}}",
    ]
    try:
        with installed(cluster, f"prom-{secrets.token_hex(3)}", ns, *values) as rel:
            rel.wait_available()
            try:
                yield rel
            finally:  # deleted while the operator still runs (it removes its finalizers)
                cluster.kubectl(
                    "delete", "uavtests", "--all", "-n", tests_ns, "--timeout=120s", timeout=150, check=False
                )
    finally:
        cluster.delete_namespace(ns)


@pytest.fixture(scope="module")
def prometheus(
    cluster: Cluster, release: Release, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[PrometheusServer]:
    work = tmp_path_factory.mktemp("prometheus")
    rules = render_rules(work, failedRunsInARow=2, flakyRateAbove=0.2, reconcileErrorWindow="15m")
    monitor = render_service_monitor(release)
    targets = work / "targets.json"
    discovered = discover_endpoints(cluster, monitor["spec"]["namespaceSelector"]["matchNames"])
    targets.write_text(json.dumps(discovered))
    config = scrape_config(monitor, targets)
    with PrometheusServer(work, [config], rules, interval=SCRAPE) as prom:
        yield prom


@pytest.fixture(scope="module")
def flown(
    cluster: Cluster, release: Release, tests_ns: str, prometheus: PrometheusServer
) -> dict[str, list[str]]:
    """steady (passes) run twice, broken (collides) run twice, wobbly (flaky) once: their runs."""
    ns = tests_ns
    cluster.apply(_example("hover.yaml", "steady", ns, replicas=2, parallelism=2))
    cluster.apply(_example("collision.yaml", "broken", ns, replicas=2, parallelism=2))
    # near-miss-wind's seeds 1000-1003: three replicas pass, one fails (uavtest run shows the same)
    cluster.apply(_example("near-miss-wind.yaml", "wobbly", ns, replicas=4, parallelism=4))
    runs: dict[str, list[str]] = {t: [first_run(t)] for t in ("steady", "broken", "wobbly")}
    for test in ("steady", "broken", "wobbly"):
        wait_complete(cluster, ns, test, timeout=900)
    for test in ("steady", "broken"):
        runs[test].append(_rerun(cluster, ns, test, "again-1"))
    for test in ("steady", "broken"):
        wait_complete(cluster, ns, test, timeout=900, run=runs[test][1])

    def summarised() -> bool:
        st = {t: cluster.kubectl_json("get", "uavtest", t, "-n", ns).get("status", {}) for t in runs}
        return (st["steady"].get("lastRun") or {}).get("name") == runs["steady"][1] and st["broken"].get(
            "failedInARow"
        ) == 2

    assert cluster.wait_until(summarised, 120, interval=1.0)
    # two scrapes and a rule evaluation after the last status change
    time.sleep(3 * 2 + 1)
    return runs


def _grafana(expr: str, namespace: str, range_s: int) -> str:
    """A panel's query with the dashboard's variables substituted as Grafana does."""
    return (
        expr.replace("$namespace", namespace)  # names are [a-z0-9-]: regex-safe
        .replace("$__rate_interval", "1m")
        .replace("$__range", f"{range_s}s")
    )


def _series(result: list[dict[str, Any]]) -> dict[tuple[tuple[str, str], ...], float]:
    out = {}
    for r in result:
        value = r["value"][1] if "value" in r else r["values"][-1][1]
        out[tuple(sorted(r["metric"].items()))] = float(value)
    return out


def _by_test(result: list[dict[str, Any]]) -> dict[str, float]:
    return {r["metric"]["test"]: float(r["value"][1]) for r in result if "test" in r["metric"]}


def test_prometheus_finds_the_operator_through_the_service_monitor_and_keeps_test_namespace(
    release: Release, tests_ns: str, prometheus: PrometheusServer, flown: dict[str, list[str]]
) -> None:
    (target,) = [t for t in prometheus.targets() if t["health"] == "up"]
    assert target["labels"]["namespace"] == release.namespace  # the target label scrape setups add
    assert target["labels"]["service"] == release.metrics_service
    rate = prometheus.query("uavtest_test_flaky_rate")
    assert {(r["metric"]["test_namespace"], r["metric"]["test"]) for r in rate} == {
        (tests_ns, "steady"),
        (tests_ns, "broken"),
        (tests_ns, "wobbly"),
    }
    assert not prometheus.query("{exported_namespace!=''}")  # nothing renamed
    # the dashboard's namespace variable lists the tests' namespace, not only the operator's
    values = prometheus.api("label/test_namespace/values", **{"match[]": "uavtest_tests"})
    assert values == [tests_ns]


def test_every_dashboard_panel_returns_the_expected_series(
    tests_ns: str, prometheus: PrometheusServer, flown: dict[str, list[str]]
) -> None:
    dash = json.loads(DASHBOARD.read_text())
    range_s = int(time.time() - prometheus.started) + 10
    got: dict[str, list[list[dict[str, Any]]]] = {}
    for panel in dash["panels"]:
        results = []
        for target in panel["targets"]:
            expr = _grafana(target["expr"], tests_ns, range_s)
            if target.get("instant"):
                results.append(prometheus.query(expr))
            else:
                results.append(prometheus.query_range(expr, range_s, step=SCRAPE))
            assert results[-1], f"panel {panel['title']!r}: {expr} returned nothing"
        got[panel["title"]] = results
    assert set(got) == {p["title"] for p in dash["panels"]}
    (flaky_count,) = got["Flaky tests"][0]
    assert float(flaky_count["value"][1]) == 1  # wobbly
    phases = {r["metric"]["phase"]: float(r["value"][1]) for r in got["Tests by phase"][0]}
    assert phases == {"Succeeded": 1, "Failed": 2}  # steady; broken and wobbly (a replica failed)
    flakiness = _by_test(got["Flakiness per test"][0])
    assert flakiness == {"steady": 0, "broken": 1, "wobbly": 0.25}
    verdicts = {
        (r["metric"]["test"], r["metric"]["verdict"]): float(r["value"][1])
        for r in got["Verdicts per test"][0]
    }
    assert verdicts[("steady", "pass")] == 2 and verdicts[("broken", "fail")] == 2
    assert (verdicts[("wobbly", "pass")], verdicts[("wobbly", "fail")]) == (3, 1)
    # runs finished per minute, by result: both results were seen to increase in the window
    rates = {r["metric"]["result"]: max(float(v) for _, v in r["values"]) for r in got[
        "Verdict rates (runs finished per minute)"][0]}  # fmt: skip
    assert rates["succeeded"] > 0 and rates["failed"] > 0
    distance = {
        r["metric"]["le"]: float(r["value"][1])
        for r in got["Minimum obstacle distance (replicas in range)"][0]
    }
    assert distance["0.0"] > 0  # broken's second run: collisions (distance 0) were observed
    durations = [
        float(v) for r in got["Replica duration (p50, p95)"][0] for _, v in r["values"] if v != "NaN"
    ]
    assert durations and all(d > 0 for d in durations)
    rate = _by_test(got["Flaky-rate per test (flaky runs / finished runs kept)"][0])
    assert rate == {"steady": 0, "broken": 0, "wobbly": 1}
    # the table: one row per test, its flaky-rate, last run and failed runs in a row
    table = [_by_test(r) for r in got["Tests: flaky-rate and last runs"]]
    assert table[0] == rate
    assert table[1] == flakiness
    assert table[2]["steady"] == 2 and table[3]["broken"] == 2 and table[3]["wobbly"] == 1
    assert table[5] == {"steady": 0, "broken": 2, "wobbly": 1}  # a flaky run is a failed run too
    assert table[6]["steady"] > 0 and table[7]["broken"] > 0  # the re-runs within the range
    over_time = {
        r["metric"]["test"]: [float(v) for _, v in r["values"]]
        for r in got["Flaky-rate over time per test"][0]
    }
    assert over_time["wobbly"][-1] == 1 and over_time["steady"][-1] == 0


def test_every_alert_rule_fires_for_its_test_and_only_for_it(
    cluster: Cluster, tests_ns: str, prometheus: PrometheusServer, flown: dict[str, list[str]]
) -> None:
    def firing() -> dict[str, set[str]]:
        out: dict[str, set[str]] = {}
        for a in prometheus.alerts():
            if a["state"] == "firing":
                out.setdefault(a["labels"]["alertname"], set()).add(
                    a["labels"].get("test", a["labels"].get("handler", ""))
                )
        return out

    assert cluster.wait_until(
        lambda: {"UavTestTurnedFlaky", "UavTestFlakyRateHigh", "UavTestFailingRepeatedly"} <= set(firing()),
        60,
        interval=1.0,
    ), prometheus.alerts()
    now = firing()
    assert now["UavTestTurnedFlaky"] == {"wobbly"}
    assert now["UavTestFlakyRateHigh"] == {"wobbly"}
    assert now["UavTestFailingRepeatedly"] == {"broken"}
    assert "UavTestOperatorReconcileErrors" not in now  # nothing went wrong so far
    # a real reconcile error: a quota that forbids UavTestRuns in the namespace makes the operator's
    # create of a run fail (403 from the apiserver's ResourceQuota admission)
    quota = {
        "apiVersion": "v1",
        "kind": "ResourceQuota",
        "metadata": {"name": "no-runs", "namespace": tests_ns},
        "spec": {"hard": {"count/uavtestruns.uavtest.io": "0"}},
    }
    cluster.apply(quota)
    try:
        cluster.apply(_example("hover.yaml", "quota-denied", tests_ns, replicas=1))
        assert cluster.wait_until(lambda: "UavTestOperatorReconcileErrors" in firing(), 120, interval=1.0), (
            prometheus.query("uavtest_reconcile_errors_total")
        )
        assert firing()["UavTestOperatorReconcileErrors"] == {"test"}
    finally:
        cluster.kubectl("delete", "resourcequota", "no-runs", "-n", tests_ns, check=False)
    # once the quota is gone the operator's retry creates the run: the error was transient
    wait_exists(cluster, tests_ns, f"uavtestrun/{first_run('quota-denied')}", timeout=180)
