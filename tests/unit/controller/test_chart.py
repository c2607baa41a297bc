"""The Helm chart: least-privilege RBAC that covers every API call, the dashboard, the templates."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.controller.kube import API_CALLS
from uavtest.controller.metrics import Metrics
from uavtest.controller.views import test_view

from .controller_bodies import RUN, test_body

CHART = Path(__file__).resolve().parents[3] / "charts" / "uavtest"


def granted(rules: list[dict[str, Any]]) -> set[tuple[str, str, str]]:
    return {
        (g, r, v)
        for rule in rules
        for g in rule["apiGroups"]
        for r in rule["resources"]
        for v in rule["verbs"]
    }


def chart_rules() -> set[tuple[str, str, str]]:
    return granted(yaml.safe_load((CHART / "files" / "rbac" / "namespaced-rules.yaml").read_text()))


def test_rbac_grants_exactly_the_calls_the_operator_makes() -> None:
    rules = chart_rules()
    assert rules - API_CALLS == set(), "granted but never used"
    assert API_CALLS - rules == set(), "used but not granted"


def test_rbac_never_grants_secret_reads_beyond_get_nor_deletes_or_wildcards() -> None:
    rules = chart_rules()
    # Secrets: create each run's upload Secret, get it back by name; never list, watch, change them
    assert {v for _, r, v in rules if r == "secrets"} == {"create", "get"}
    # the one delete: runs beyond a test's history limits (its children follow by owner references)
    deletes = {(g, r) for g, r, v in rules if v == "delete"}
    assert deletes == {("uavtest.io", "uavtestruns")}
    assert not any(v in {"deletecollection", "*", "escalate", "bind", "impersonate"} for *_, v in rules)
    assert not any("*" in (g, r) for g, r, _ in rules)


def all_metric_names() -> set[str]:
    last = {"name": "hover-g1", "phase": "Failed", "passed": 1, "failed": 1, "flakiness": 0.5}
    test = test_view(test_body(status={"phase": "Failed", "lastRun": last, "flakyRate": 0.5, "runs": 2}))
    m = Metrics(lambda: [test])
    results = [
        ReplicaResult(
            index=0, seed=0, verdict=Verdict.PASS, metrics=FlightMetrics(min_obstacle_distance=3), wall_time=9
        ),
        ReplicaResult(
            index=1, seed=1, verdict=Verdict.FAIL, metrics=FlightMetrics(min_obstacle_distance=1), wall_time=9
        ),
    ]
    m.record_run(summarize(results, test="hover", namespace="team-a", run_id=RUN), "failed")
    m.reconcile_errors.labels(handler="status").inc()
    return {s.name for family in m.registry.collect() for s in family.samples}


def test_dashboard_is_grafana_json_over_metrics_the_operator_exports() -> None:
    dash = json.loads((CHART / "files" / "dashboard.json").read_text())
    titles = {p["title"] for p in dash["panels"]}
    assert {"Flakiness per test", "Verdicts per test", "Flaky tests"} <= titles
    assert any("distance" in t.lower() for t in titles)
    exprs = " ".join(t["expr"] for p in dash["panels"] for t in p["targets"])
    used = set(re.findall(r"\buavtest_[a-z_]+", exprs))
    assert used, "the dashboard queries no uavtest metric"
    assert used <= all_metric_names(), used - all_metric_names()


def helm() -> str:
    for candidate in (shutil.which("helm"), str(Path.home() / ".cache" / "uavtest" / "bin" / "helm")):
        if candidate and Path(candidate).is_file():
            return candidate
    pytest.skip("helm is not installed (go install helm.sh/helm/v3/cmd/helm to render the chart)")


def render(*sets: str) -> list[dict[str, Any]]:
    args = [helm(), "template", "rel", str(CHART), "--namespace", "uavtest-system"]
    for s in sets:
        args += ["--set", s]
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout
    return [d for d in yaml.safe_load_all(out) if d]


def test_chart_renders_an_operator_with_cluster_wide_rbac() -> None:
    docs = render()
    kinds = {(d["kind"], d["metadata"]["name"]) for d in docs}
    assert ("Deployment", "rel-operator") in kinds
    assert ("Service", "rel-operator-metrics") in kinds
    assert ("ConfigMap", "rel-operator-dashboard") in kinds
    role = next(d for d in docs if d["kind"] == "ClusterRole" and d["metadata"]["name"] == "rel-operator")
    assert granted(role["rules"]) | chart_rules() == chart_rules()
    deploy = next(d for d in docs if d["kind"] == "Deployment")
    container = deploy["spec"]["template"]["spec"]["containers"][0]
    assert container["args"][0] == "operator"
    env = {e["name"]: e for e in container["env"]}
    assert "secretKeyRef" in env["UAVTEST_S3_SECRET_KEY"]["valueFrom"]
    json.loads(next(d for d in docs if d["kind"] == "ConfigMap")["data"]["uavtest-flaky-tests.json"])


def test_chart_with_watch_namespaces_uses_roles_per_namespace() -> None:
    docs = render("operator.watchNamespaces={a,b}")
    roles = [d for d in docs if d["kind"] == "Role"]
    assert sorted(r["metadata"]["namespace"] for r in roles) == ["a", "b"]
    assert not any(d["kind"] == "ClusterRole" and d["metadata"]["name"] == "rel-operator" for d in docs)
    deploy = next(d for d in docs if d["kind"] == "Deployment")
    assert {"--namespace=a", "--namespace=b"} <= set(
        deploy["spec"]["template"]["spec"]["containers"][0]["args"]
    )


def test_chart_minio_toggle() -> None:
    assert not any(d["metadata"]["name"] == "rel-minio" for d in render())
    docs = render("minio.enabled=true", "store.createSecret=true")
    assert {"Deployment", "Service", "Secret"} <= {
        d["kind"] for d in docs if d["metadata"]["name"] == "rel-minio"
    }
    deploy = next(d for d in docs if d["kind"] == "Deployment" and d["metadata"]["name"] == "rel-operator")
    env = {e["name"]: e for e in deploy["spec"]["template"]["spec"]["containers"][0]["env"]}
    assert env["UAVTEST_S3_ENDPOINT"]["value"] == "rel-minio.uavtest-system.svc:9000"


def test_service_monitor_and_prometheus_rule_are_optional_and_select_the_metrics_service() -> None:
    kinds = {d["kind"] for d in render()}
    assert not kinds & {"ServiceMonitor", "PrometheusRule"}  # off by default: no CRDs required
    docs = render(
        "metrics.serviceMonitor.enabled=true",
        "metrics.serviceMonitor.labels.release=kube-prometheus-stack",
        "metrics.prometheusRule.enabled=true",
        "metrics.prometheusRule.failedRunsInARow=5",
    )
    monitor = next(d for d in docs if d["kind"] == "ServiceMonitor")
    service = next(
        d for d in docs if d["kind"] == "Service" and d["metadata"]["name"] == "rel-operator-metrics"
    )
    assert monitor["metadata"]["labels"]["release"] == "kube-prometheus-stack"
    selector = monitor["spec"]["selector"]["matchLabels"]
    assert selector.items() <= service["metadata"]["labels"].items()  # it selects the metrics Service
    assert monitor["spec"]["namespaceSelector"]["matchNames"] == ["uavtest-system"]
    assert [e["port"] for e in monitor["spec"]["endpoints"]] == [p["name"] for p in service["spec"]["ports"]]
    rule = next(d for d in docs if d["kind"] == "PrometheusRule")
    exprs = {r["alert"]: r["expr"] for g in rule["spec"]["groups"] for r in g["rules"]}
    assert exprs["UavTestFailingRepeatedly"] == "uavtest_test_failed_runs_in_a_row >= 5"
    # every metric an alert reads is one the operator exports
    for expr in exprs.values():
        assert set(re.findall(r"uavtest_[a-z_]+", expr)) <= all_metric_names(), expr
