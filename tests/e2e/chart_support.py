"""Helpers of the chart's e2e tests: `helm install` of charts/uavtest, the operator's Deployment, its
metrics Service, and the chart's throwaway MinIO, all reached the way a user's cluster reaches them
(kube-proxy ClusterIPs, the cluster DNS).
"""

from __future__ import annotations

import contextlib
import json
import secrets
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import yaml
from minio import Minio

from harness.cluster import REPO_ROOT, Cluster, ClusterError, KubectlError

CHART = REPO_ROOT / "charts" / "uavtest"
EXAMPLE = REPO_ROOT / "examples" / "uavtest.yaml"


def chart_defaults() -> dict[str, Any]:
    return dict(yaml.safe_load((CHART / "values.yaml").read_text()))


@dataclass
class Release:
    """One `helm install` of the chart."""

    cluster: Cluster
    name: str
    namespace: str

    @property
    def operator(self) -> str:
        """The operator's Deployment, ServiceAccount and (Cluster)Role name: <release>-operator."""
        return f"{self.name}-operator"

    @property
    def metrics_service(self) -> str:
        return f"{self.operator}-metrics"

    def operator_pod(self) -> dict[str, Any]:
        pods = self.cluster.kubectl_json(
            "get", "pods", "-n", self.namespace, "-l",
            f"app.kubernetes.io/instance={self.name},app.kubernetes.io/component=operator",
        )["items"]  # fmt: skip
        running = [p for p in pods if not p["metadata"].get("deletionTimestamp")]
        if len(running) != 1:
            raise ClusterError(f"expected one operator pod, found {[p['metadata']['name'] for p in running]}")
        return dict(running[0])

    def wait_available(self, timeout: int = 180) -> None:
        """The Deployment turns Available: its pod passed the readiness probe."""
        try:
            self.cluster.kubectl(
                "wait", "deployment", self.operator, "-n", self.namespace,
                "--for=condition=Available", f"--timeout={timeout}s", timeout=timeout + 30,
            )  # fmt: skip
        except KubectlError as e:
            raise ClusterError(f"{e}\n{self.diagnostics()}") from e

    def diagnostics(self) -> str:
        out = self.cluster.kubectl("describe", "pods", "-n", self.namespace, check=False)[-4000:]
        logs = self.cluster.kubectl(
            "logs", f"deployment/{self.operator}", "-n", self.namespace, "--tail=40", check=False
        )
        return f"{out}\n--- operator log\n{logs}"

    def log(self) -> str:
        return self.cluster.kubectl("logs", f"deployment/{self.operator}", "-n", self.namespace, check=False)

    def service_url(self, service: str, port: int, path: str = "") -> str:
        """http://CLUSTER-IP:PORT/PATH of a Service of the release (reached through kube-proxy)."""
        ip = self.cluster.kubectl(
            "get", "service", service, "-n", self.namespace, "-o", "jsonpath={.spec.clusterIP}"
        )
        return f"http://{ip}:{port}{path}"

    def metrics(self) -> str:
        """GET /metrics through the metrics Service's ClusterIP, from the host."""
        port = int(chart_defaults()["metrics"]["service"]["port"])
        url = self.service_url(self.metrics_service, port, "/metrics")
        with urllib.request.urlopen(url, timeout=10) as r:
            return str(r.read().decode())

    def minio(self, access_key: str, secret_key: str) -> Minio:
        """A client of the chart's throwaway MinIO, through its Service's ClusterIP."""
        url = self.service_url(f"{self.name}-minio", 9000)
        return Minio(url.removeprefix("http://"), access_key=access_key, secret_key=secret_key, secure=False)


@contextlib.contextmanager
def installed(cluster: Cluster, name: str, namespace: str, *values: str) -> Iterator[Release]:
    """`helm install NAME charts/uavtest -n NAMESPACE --set VALUE...`; uninstalled (waited for) on exit."""
    cluster.helm("install", name, str(CHART), "-n", namespace, *(a for v in values for a in ("--set", v)))
    release = Release(cluster, name, namespace)
    try:
        yield release
    finally:
        cluster.helm("uninstall", name, "-n", namespace, "--wait", "--timeout=180s")


def dev_image_values(operator_image: str, runner_image: str) -> list[str]:
    """--set values for the images the suite builds (imported into the node, never pulled)."""
    return [
        f"operator.image={operator_image}",
        "operator.imagePullPolicy=Never",
        f"replicas.image={runner_image}",
        "replicas.imagePullPolicy=Never",
    ]


def apply_uavtest(cluster: Cluster, namespace: str, name: str, replicas: int = 3) -> str:
    """examples/uavtest.yaml under another name (and replica count) in NAMESPACE."""
    doc = yaml.safe_load(EXAMPLE.read_text())
    doc["metadata"] = {"name": name, "namespace": namespace}
    doc["spec"]["replicas"] = replicas
    cluster.kubectl("apply", "-f", "-", input=json.dumps(doc))
    return name


def jobs_of(cluster: Cluster, namespace: str, test: str) -> list[dict[str, Any]]:
    return list(
        cluster.kubectl_json("get", "jobs", "-n", namespace, "-l", f"uavtest.io/test={test}")["items"]
    )


def wait_reconciled(release: Release, namespace: str, name: str, timeout: float = 120) -> dict[str, Any]:
    """Wait until RELEASE's operator made the UavTest's Job and wrote a status phase; return the status."""
    cluster = release.cluster

    run = f"{name}-g1"  # the test's first run (a UavTestRun), which owns the Job

    def done() -> bool:
        got = cluster.kubectl("get", "uavtestrun", run, "-n", namespace, "--ignore-not-found", "-o", "json")
        obj = json.loads(got) if got.strip() else {}
        return bool(obj.get("status", {}).get("phase")) and bool(jobs_of(cluster, namespace, name))

    if not cluster.wait_until(done, timeout, interval=1):
        events = cluster.kubectl("get", "events", "-n", namespace, check=False)
        raise ClusterError(
            f"UavTest {namespace}/{name} not reconciled after {timeout}s\n{events}\n"
            f"--- operator log\n{release.log()[-3000:]}"
        )
    return dict(cluster.kubectl_json("get", "uavtestrun", run, "-n", namespace)["status"])


def wait_complete(cluster: Cluster, namespace: str, name: str, timeout: int = 600) -> dict[str, Any]:
    """The final status of the test's first run (``<name>-g1``)."""
    run = f"{name}-g1"
    assert cluster.wait_until(
        lambda: (
            cluster.kubectl("get", "uavtestrun", run, "-n", namespace, "--ignore-not-found").strip() != ""
        ),
        120,
        interval=1,
    ), f"no run {run}"
    cluster.kubectl(
        "wait", f"uavtestrun/{run}", "-n", namespace, "--for=condition=Complete", f"--timeout={timeout}s",
        timeout=timeout + 30,
    )  # fmt: skip
    return dict(cluster.kubectl_json("get", "uavtestrun", run, "-n", namespace)["status"])


def fetch_in_pod(cluster: Cluster, namespace: str, image: str, url: str, timeout: float = 120) -> str:
    """Run a pod that GETs URL (a Service name: cluster DNS + kube-proxy, as any pod reaches it)."""
    name = f"fetch-{secrets.token_hex(3)}"
    code = "import sys, urllib.request as u; print(u.urlopen(sys.argv[1], timeout=20).read().decode())"
    cluster.apply(
        {
            "apiVersion": "v1",
            "kind": "Pod",
            "metadata": {"name": name, "namespace": namespace},
            "spec": {
                "restartPolicy": "Never",
                "containers": [
                    {
                        "name": "fetch",
                        "image": image,
                        "imagePullPolicy": "Never",
                        "command": ["python3", "-c", code, url],
                    }
                ],
            },
        }
    )
    try:
        phase = cluster.wait_pod_done(namespace, name, timeout)
        out = cluster.kubectl("logs", name, "-n", namespace)
        if phase != "Succeeded":
            raise ClusterError(f"GET {url} from a pod failed ({phase}):\n{out[-2000:]}")
        return out
    finally:
        cluster.kubectl("delete", "pod", name, "-n", namespace, "--wait=false", check=False)


def sa_can(cluster: Cluster, release: Release, verb: str, resource: str, namespace: str) -> bool:
    """`kubectl auth can-i` as the operator's ServiceAccount."""
    out = cluster.kubectl(
        "auth", "can-i", verb, resource, "-n", namespace,
        f"--as=system:serviceaccount:{release.namespace}:{release.operator}", check=False,
    )  # fmt: skip
    return out.strip() == "yes"


def store_objects(client: Minio, bucket: str) -> list[str]:
    return sorted(str(o.object_name) for o in client.list_objects(bucket, recursive=True))
