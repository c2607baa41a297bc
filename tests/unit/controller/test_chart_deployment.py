"""The chart's operator Deployment as the kubelet sees it: probes, and an environment of its own."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

CHART = Path(__file__).resolve().parents[3] / "charts" / "uavtest"


def render(*sets: str) -> list[dict[str, Any]]:
    helm = shutil.which("helm") or str(Path.home() / ".cache" / "uavtest" / "bin" / "helm")
    if not Path(helm).exists():
        pytest.skip("helm is not installed (tests/cluster/build.sh helm)")
    args = [helm, "template", "rel", str(CHART), "--namespace", "uavtest-system"]
    for s in sets:
        args += ["--set", s]
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout
    return [d for d in yaml.safe_load_all(out) if d]


def operator_pod(docs: list[dict[str, Any]]) -> dict[str, Any]:
    (dep,) = [d for d in docs if d["kind"] == "Deployment" and d["metadata"]["name"] == "rel-operator"]
    return dict(dep["spec"]["template"]["spec"])


def test_operator_is_ready_and_alive_by_kopfs_health_endpoint() -> None:
    pod = operator_pod(render())
    (c,) = pod["containers"]
    ports = {p["name"]: p["containerPort"] for p in c["ports"]}
    for probe in ("readinessProbe", "livenessProbe"):
        assert c[probe]["httpGet"] == {"path": "/healthz", "port": "liveness"}, probe
    assert "--liveness-port=8081" in c["args"] and ports["liveness"] == 8081


def test_no_service_link_variables_shadow_the_operators_settings() -> None:
    # a Service "rel-operator-metrics" would put RELEASE_OPERATOR_METRICS_PORT=tcp://... into every pod
    # of its namespace; with release "uavtest" that is UAVTEST_OPERATOR_METRICS_PORT, a setting
    docs = render()
    services = [d["metadata"]["name"] for d in docs if d["kind"] == "Service"]
    assert "rel-operator-metrics" in services
    assert operator_pod(docs)["enableServiceLinks"] is False
