"""The e2e harness works: a real apiserver, a Ready node that runs the runner image, and MinIO."""

from __future__ import annotations

import io
import json
import secrets

import pytest

from harness.cluster import Cluster
from harness.minio import MinioServer

pytestmark = pytest.mark.e2e

K8S_VERSION = "v1.36.3"


def test_apiserver_answers_kubectl_version(cluster: Cluster) -> None:
    version = json.loads(cluster.kubectl("version", "-o", "json"))
    assert version["serverVersion"]["gitVersion"] == K8S_VERSION
    assert version["clientVersion"]["gitVersion"] == K8S_VERSION


def test_real_node_is_ready(cluster: Cluster) -> None:
    node = cluster.kubectl_json("get", "node", cluster.node_name)
    ready = {c["type"]: c["status"] for c in node["status"]["conditions"]}["Ready"]
    assert ready == "True"
    assert node["status"]["nodeInfo"]["containerRuntimeVersion"].startswith("containerd://")


def test_runner_image_runs_a_pod(cluster: Cluster, runner_image: str, namespace: str) -> None:
    pod = {
        "apiVersion": "v1",
        "kind": "Pod",
        "metadata": {"name": "smoke", "namespace": namespace},
        "spec": {
            "restartPolicy": "Never",
            "containers": [
                {
                    "name": "smoke",
                    "image": runner_image,
                    "imagePullPolicy": "Never",
                    "command": ["python3", "-c", 'import uavtest, pymavlink, minio; print("ok")'],
                }
            ],
        },
    }
    cluster.apply(pod)
    phase = cluster.wait_pod_done(namespace, "smoke", timeout=180)
    logs = cluster.kubectl("logs", "-n", namespace, "smoke")
    assert phase == "Succeeded", logs
    assert logs.strip() == "ok"


def test_minio_put_get(minio: MinioServer) -> None:
    client = minio.client()
    bucket = f"smoke-{secrets.token_hex(4)}"
    client.make_bucket(bucket)
    payload = secrets.token_bytes(4096)
    client.put_object(bucket, "a/b/blob.bin", io.BytesIO(payload), len(payload))
    resp = client.get_object(bucket, "a/b/blob.bin")
    try:
        assert resp.read() == payload
    finally:
        resp.close()
        resp.release_conn()
    assert [o.object_name for o in client.list_objects(bucket, recursive=True)] == ["a/b/blob.bin"]


def test_kwok_cluster_fakes_a_job(kwok_cluster: Cluster, kwok_namespace: str) -> None:
    job = {
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": {"name": "fake", "namespace": kwok_namespace},
        "spec": {
            "completions": 3,
            "parallelism": 3,
            "backoffLimit": 0,
            "template": {
                "spec": {
                    "restartPolicy": "Never",
                    "containers": [{"name": "c", "image": "nothing-pulls-this:0", "command": ["false"]}],
                }
            },
        },
    }
    kwok_cluster.apply(job)
    kwok_cluster.kubectl(
        "wait", "-n", kwok_namespace, "--for=condition=Complete", "job/fake", "--timeout=60s", timeout=90
    )
    nodes = kwok_cluster.kubectl(
        "get", "pods", "-n", kwok_namespace, "-o", "jsonpath={.items[*].spec.nodeName}"
    )
    assert set(nodes.split()) == {kwok_cluster.node_name}
