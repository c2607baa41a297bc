"""The Helm chart installed for real: `helm install charts/uavtest` on the suite's cluster.

The operator runs in-cluster as the chart's Deployment (the operator image built without Docker),
talks to the apiserver through the `kubernetes` Service (kube-proxy) with its ServiceAccount token,
passes its readiness and liveness probes, and is scraped through its metrics Service. Both RBAC
modes: cluster-wide (ClusterRole) and `operator.watchNamespaces` (a Role per namespace).
"""

from __future__ import annotations

import secrets
from collections.abc import Iterator

import pytest
from prometheus_client.parser import text_string_to_metric_families

from e2e.chart_support import (
    Release,
    apply_uavtest,
    dev_image_values,
    fetch_in_pod,
    installed,
    jobs_of,
    sa_can,
    store_objects,
    wait_complete,
    wait_reconciled,
)
from harness.cluster import Cluster

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

MINIO_USER = "uavtest"
MINIO_PASSWORD = secrets.token_hex(12)


def _ns(cluster: Cluster, prefix: str) -> str:
    return cluster.create_namespace(f"{prefix}-{secrets.token_hex(3)}")


def _delete_tests(cluster: Cluster, *namespaces: str) -> None:
    """Delete the UavTests while the operator still runs (it removes its finalizer from them)."""
    for ns in namespaces:
        cluster.kubectl("delete", "uavtests", "--all", "-n", ns, "--timeout=90s", timeout=120, check=False)


class TestClusterWide:
    """watchNamespaces empty: one ClusterRole, every namespace reconciled."""

    @pytest.fixture(scope="class")
    @classmethod
    def namespaces(cls, cluster: Cluster) -> Iterator[tuple[str, str]]:
        made = (_ns(cluster, "chart-wide"), _ns(cluster, "chart-elsewhere"))
        yield made
        for ns in made:
            cluster.delete_namespace(ns)

    @pytest.fixture(scope="class")
    @classmethod
    def release(
        cls,
        cluster: Cluster,
        namespaces: tuple[str, str],
        operator_image: str,
        runner_image: str,
        minio_image: str,
    ) -> Iterator[Release]:
        ns, other = namespaces
        values = [
            *dev_image_values(operator_image, runner_image),
            "minio.enabled=true",
            f"minio.image={minio_image}",
            f"minio.rootUser={MINIO_USER}",
            f"minio.rootPassword={MINIO_PASSWORD}",
            "store.createSecret=true",
        ]
        with installed(cluster, f"wide-{secrets.token_hex(3)}", ns, *values) as rel:
            try:
                rel.wait_available()
                yield rel
            finally:
                _delete_tests(cluster, ns, other)

    def test_operator_is_the_charts_deployment_and_passes_its_probes(
        self, cluster: Cluster, release: Release, namespaces: tuple[str, str], operator_image: str
    ) -> None:
        pod = release.operator_pod()
        (container,) = pod["spec"]["containers"]
        assert container["image"] == operator_image
        assert container["readinessProbe"]["httpGet"]["path"] == "/healthz"
        assert container["livenessProbe"]["httpGet"]["path"] == "/healthz"
        (state,) = pod["status"]["containerStatuses"]
        assert state["ready"] is True and state["restartCount"] == 0, state
        # in-cluster config: the ServiceAccount token, the apiserver through kubernetes.default (kube-proxy)
        log = release.log()
        assert "Initial authentication has finished" in log
        # the kubelet's probes reached kopf's health endpoint on the pod's IP and got 200
        probed = [line for line in log.splitlines() if "kube-probe/" in line]
        assert any('"GET /healthz HTTP/1.1" 200' in line for line in probed), log[-2000:]
        uid = cluster.kubectl("exec", pod["metadata"]["name"], "-n", release.namespace, "--", "id", "-u")
        assert uid.strip() == "65532"
        # cluster-wide RBAC: a ClusterRole and its binding, valid in any namespace
        assert cluster.kubectl("get", "clusterrole", release.operator, "-o", "name").strip()
        assert cluster.kubectl("get", "clusterrolebinding", release.operator, "-o", "name").strip()
        assert sa_can(cluster, release, "watch", "uavtests.uavtest.io", "default")
        assert sa_can(cluster, release, "create", "jobs.batch", namespaces[1])

    def test_metrics_service_points_at_the_operator_and_answers(
        self, cluster: Cluster, release: Release
    ) -> None:
        pod = release.operator_pod()
        slices = cluster.kubectl_json(
            "get", "endpointslices", "-n", release.namespace,
            "-l", f"kubernetes.io/service-name={release.metrics_service}",
        )["items"]  # fmt: skip
        endpoints = [
            (a, e["conditions"].get("ready"))
            for s in slices
            for e in s.get("endpoints") or []
            for a in e["addresses"]
        ]
        assert endpoints == [(pod["status"]["podIP"], True)]
        # through the Service's ClusterIP: kube-proxy programs a new Service's rules a moment after
        # its endpoints are ready, so a refused connection right then is retried for a while
        answers: list[str] = []

        def fetch() -> bool:
            try:
                answers.append(release.metrics())
            except OSError:
                return False
            return True

        assert cluster.wait_until(fetch, 30, interval=1.0), release.diagnostics()
        text = answers[-1]
        assert "# TYPE uavtest_test_runs_total counter" in text
        assert "# TYPE uavtest_test_last_run_replicas gauge" in text

    def test_a_run_in_the_release_namespace_flies_and_stores(
        self, cluster: Cluster, release: Release, runner_image: str
    ) -> None:
        ns = release.namespace
        name = apply_uavtest(cluster, ns, "chart-pass", replicas=3)
        status = wait_complete(cluster, ns, name)
        assert status["phase"] == "Succeeded", (status, release.log()[-3000:])
        assert (status["passed"], status["failed"], status["errors"]) == (3, 0, 0)
        # replicas and the operator stored through the chart's MinIO Service (cluster DNS name)
        keys = store_objects(release.minio(MINIO_USER, MINIO_PASSWORD), "uavtest")
        run = status["runId"]
        for i in range(3):
            assert any(k.endswith(f"/replica-{i}/result.json") and run in k for k in keys), keys
        artifacts = {k: v for k, v in status["artifacts"].items() if k != "store" and v}
        assert artifacts, status["artifacts"]
        for uri in artifacts.values():
            assert uri.removeprefix("s3://uavtest/") in keys, (uri, keys)
        # a pod scrapes the operator by the Service's DNS name, as Prometheus in the cluster would
        url = f"http://{release.metrics_service}.{ns}.svc.cluster.local:8080/metrics"
        text = fetch_in_pod(cluster, ns, runner_image, url)
        runs = [
            s.value
            for family in text_string_to_metric_families(text)
            for s in family.samples
            if s.name == "uavtest_test_runs_total"
            and s.labels == {"test_namespace": ns, "test": name, "result": "succeeded"}
        ]
        assert runs == [1.0], [ln for ln in text.splitlines() if "runs_total" in ln]

    def test_a_test_in_any_namespace_is_reconciled(
        self, cluster: Cluster, release: Release, namespaces: tuple[str, str]
    ) -> None:
        other = namespaces[1]
        name = apply_uavtest(cluster, other, "elsewhere", replicas=1)
        status = wait_reconciled(release, other, name)
        assert status["replicas"] == 1
        (job,) = jobs_of(cluster, other, name)
        assert job["spec"]["completions"] == 1


class TestWatchNamespaces:
    """operator.watchNamespaces: a Role in each listed namespace, nothing elsewhere."""

    @pytest.fixture(scope="class")
    @classmethod
    def namespaces(cls, cluster: Cluster) -> Iterator[tuple[str, str, str]]:
        made = (_ns(cluster, "chart-rel"), _ns(cluster, "chart-watched"), _ns(cluster, "chart-unwatched"))
        yield made
        for ns in made:
            cluster.delete_namespace(ns)

    @pytest.fixture(scope="class")
    @classmethod
    def release(
        cls,
        cluster: Cluster,
        namespaces: tuple[str, str, str],
        operator_image: str,
        runner_image: str,
        minio_image: str,
    ) -> Iterator[Release]:
        ns, watched, unwatched = namespaces
        values = [
            *dev_image_values(operator_image, runner_image),
            f"operator.watchNamespaces={{{watched}}}",
            "minio.enabled=true",  # a store the operator can sign each run's upload policy for
            f"minio.image={minio_image}",
            f"minio.rootPassword={MINIO_PASSWORD}",
            "store.createSecret=true",
        ]
        with installed(cluster, f"watch-{secrets.token_hex(3)}", ns, *values) as rel:
            try:
                rel.wait_available()
                yield rel
            finally:
                _delete_tests(cluster, watched, unwatched)

    def test_only_the_watched_namespace_is_reconciled(
        self, cluster: Cluster, release: Release, namespaces: tuple[str, str, str]
    ) -> None:
        ns, watched, unwatched = namespaces
        # RBAC: a Role where it watches, no rights anywhere else, no ClusterRole
        assert sa_can(cluster, release, "watch", "uavtests.uavtest.io", watched)
        assert not sa_can(cluster, release, "watch", "uavtests.uavtest.io", unwatched)
        assert not sa_can(cluster, release, "create", "jobs.batch", ns)
        assert cluster.kubectl("get", "clusterrole", release.operator, "--ignore-not-found").strip() == ""
        # the unwatched test is created first: when the watched one is reconciled, the operator has
        # had every chance to see it
        apply_uavtest(cluster, unwatched, "ignored", replicas=1)
        apply_uavtest(cluster, watched, "watched", replicas=1)
        wait_reconciled(release, watched, "watched")
        assert jobs_of(cluster, unwatched, "ignored") == []
        ignored = cluster.kubectl_json("get", "uavtest", "ignored", "-n", unwatched)
        assert "status" not in ignored or not ignored["status"].get("phase"), ignored.get("status")
        assert f"{unwatched}/ignored" not in release.log()
