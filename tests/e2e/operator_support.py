"""Helpers of the operator's e2e tests: the CRD, a least-privilege identity, the operator process.

The operator runs as a real subprocess (`uavtest operator -n NS`), watching only the test module's
namespace, with a kubeconfig whose user is a ServiceAccount holding exactly the chart's RBAC rules
(charts/uavtest/files/rbac/): a call the chart does not grant fails the tests. The store's root
credentials are in the operator's environment only: the test namespace holds no copy of them (replica
pods upload through the per-run policy Secret the operator creates; `assert_no_root_credentials`).
"""

from __future__ import annotations

import base64
import contextlib
import ipaddress
import json
import os
import secrets
import signal
import socket
import subprocess
import sys
import threading
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import yaml
from prometheus_client.parser import text_string_to_metric_families

from harness.cluster import REPO_ROOT, Cluster, free_ports
from harness.minio import MinioServer

CRD = REPO_ROOT / "crds" / "uavtest.yaml"
RBAC = REPO_ROOT / "charts" / "uavtest" / "files" / "rbac"
SA = "uavtest-operator"


def install_crd(cluster: Cluster) -> None:
    cluster.kubectl("apply", "-f", str(CRD))
    for crd in ("crd/uavtests.uavtest.io", "crd/uavtestruns.uavtest.io"):
        cluster.kubectl("wait", "--for=condition=Established", crd, "--timeout=60s")


def assert_no_root_credentials(cluster: Cluster, namespace: str, minio: MinioServer) -> list[dict[str, Any]]:
    """No Secret in NAMESPACE holds the store's secret key; returns the Secrets that are there."""
    secrets_ = cluster.kubectl_json("get", "secrets", "-n", namespace)["items"]
    for s in secrets_:
        values = [base64.b64decode(v).decode(errors="replace") for v in (s.get("data") or {}).values()]
        assert not any(minio.secret_key in v for v in values), f"Secret {s['metadata']['name']} holds it"
    return list(secrets_)


def least_privilege_kubeconfig(cluster: Cluster, namespace: str, out: Path) -> Path:
    """A kubeconfig for a ServiceAccount bound to the chart's rules only (a Role in NAMESPACE)."""
    namespaced = yaml.safe_load((RBAC / "namespaced-rules.yaml").read_text())
    subject = [{"kind": "ServiceAccount", "name": SA, "namespace": namespace}]
    rbac = "rbac.authorization.k8s.io"
    cluster.apply(
        {"apiVersion": "v1", "kind": "ServiceAccount", "metadata": {"name": SA, "namespace": namespace}},
        {
            "apiVersion": f"{rbac}/v1",
            "kind": "Role",
            "metadata": {"name": SA, "namespace": namespace},
            "rules": namespaced,
        },
        {
            "apiVersion": f"{rbac}/v1",
            "kind": "RoleBinding",
            "metadata": {"name": SA, "namespace": namespace},
            "roleRef": {"apiGroup": rbac, "kind": "Role", "name": SA},
            "subjects": subject,
        },
    )
    token = cluster.kubectl("create", "token", SA, "-n", namespace, "--duration=4h").strip()
    config = yaml.safe_load(cluster.kubeconfig.read_text())
    user = "uavtest-operator"
    config["users"] = [{"name": user, "user": {"token": token}}]
    for ctx in config["contexts"]:
        ctx["context"]["user"] = user
        ctx["context"]["namespace"] = namespace
    out.write_text(yaml.safe_dump(config))
    return out


def pod_reachable(cluster: Cluster, namespace: str, image: str, address: str) -> str:
    """host:port of a TCP relay pods can reach, forwarding to ADDRESS on the host's loopback.

    MinIO listens on 127.0.0.1 only; replica pods live behind the CNI bridge. The relay listens on
    the bridge's address. The harness's bridge has no address of its own (isGateway: false), so
    one is added (the subnet's last host address); it goes away with the bridge at teardown.
    """
    bridge_ip = _bridge_address(cluster, namespace, image)
    host, port = address.rsplit(":", 1)
    relay = _Relay(bridge_ip, (host, int(port)))
    return f"{bridge_ip}:{relay.port}"


def _addresses(bridge: str) -> list[str] | None:
    out = subprocess.run(["ip", "-j", "-4", "addr", "show", "dev", bridge], capture_output=True, text=True)
    if out.returncode != 0:
        return None  # no such link (yet)
    return [
        str(info["local"]) for link in json.loads(out.stdout or "[]") for info in link.get("addr_info", [])
    ]


def _bridge_address(cluster: Cluster, namespace: str, image: str) -> str:
    bridge = os.environ.get("UAVTEST_BRIDGE", "uavtest0")
    subnet = ipaddress.ip_network(os.environ.get("UAVTEST_POD_SUBNET", "10.244.7.0/24"))
    if _addresses(bridge) is None:  # CNI makes the bridge with the first pod: start one
        pod = {
            "apiVersion": "v1",
            "kind": "Pod",
            "metadata": {"name": "bridge-up", "namespace": namespace},
            "spec": {
                "restartPolicy": "Never",
                "containers": [
                    {"name": "up", "image": image, "imagePullPolicy": "Never", "command": ["true"]}
                ],
            },
        }
        cluster.apply(pod)
        cluster.wait_pod_done(namespace, "bridge-up")
        cluster.kubectl("delete", "pod", "bridge-up", "-n", namespace, "--wait=false")
    addresses = _addresses(bridge) or []
    for a in addresses:
        if ipaddress.ip_address(a) in subnet:
            return a
    ours = str(subnet.broadcast_address - 1)
    subprocess.run(["ip", "addr", "add", f"{ours}/{subnet.prefixlen}", "dev", bridge], check=True)
    return ours


class _Relay:
    """A tiny TCP forwarder (threads), alive for the test session."""

    def __init__(self, listen_host: str, target: tuple[str, int]) -> None:
        self.target = target
        self.server = socket.create_server((listen_host, 0))
        self.port = self.server.getsockname()[1]
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self.server.accept()
            except OSError:
                return
            try:
                upstream = socket.create_connection(self.target, timeout=10)
            except OSError:
                client.close()
                continue
            for a, b in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    @staticmethod
    def _pipe(src: socket.socket, dst: socket.socket) -> None:
        try:
            while data := src.recv(65536):
                dst.sendall(data)
        except OSError:
            pass
        finally:
            with contextlib.suppress(OSError):
                dst.shutdown(socket.SHUT_WR)


class Operator:
    """`uavtest operator -n NAMESPACE` as a subprocess that can be killed and started again."""

    def __init__(
        self,
        cluster: Cluster,
        namespace: str,
        minio: MinioServer,
        *,
        bucket: str,
        pod_endpoint: str,
        kubeconfig: Path,
        log: Path,
        runner_image: str,
    ) -> None:
        self.cluster = cluster
        self.namespace = namespace
        self.log = log
        (self.metrics_port,) = free_ports(1)
        self.env = {
            **os.environ,
            "KUBECONFIG": str(kubeconfig),
            "UAVTEST_OPERATOR_RUNNER_IMAGE": runner_image,
            "UAVTEST_OPERATOR_IMAGE_PULL_POLICY": "Never",
            "UAVTEST_OPERATOR_STORE_URL": f"s3://{bucket}",
            "UAVTEST_OPERATOR_POD_S3_ENDPOINT": pod_endpoint,
            "UAVTEST_S3_ENDPOINT": minio.endpoint,
            "UAVTEST_S3_ACCESS_KEY": minio.access_key,
            "UAVTEST_S3_SECRET_KEY": minio.secret_key,
            "UAVTEST_S3_RETRY_TOTAL": "10",
        }
        self.proc: subprocess.Popen[bytes] | None = None
        self.starts = 0

    def start(self) -> None:
        self.starts += 1
        with open(self.log, "ab") as out:
            out.write(f"--- start {self.starts}\n".encode())
            self.proc = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "uavtest.cli",
                    "operator",
                    "-n",
                    self.namespace,
                    "--metrics-port",
                    str(self.metrics_port),
                ],
                env=self.env,
                stdout=out,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
            )
        if not self.cluster.wait_until(
            lambda: self.metrics_text() is not None or self.proc.poll() is not None, 60
        ):
            raise RuntimeError(f"operator did not serve metrics:\n{self.log_text()[-3000:]}")
        if self.proc.poll() is not None:
            raise RuntimeError(f"operator exited {self.proc.returncode}:\n{self.log_text()[-3000:]}")

    def kill(self) -> None:
        """SIGKILL: no clean-up, like a node failure or an OOM kill."""
        assert self.proc is not None
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(30)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)

    def log_text(self) -> str:
        return self.log.read_text(errors="replace") if self.log.exists() else ""

    def metrics_text(self) -> str | None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{self.metrics_port}/metrics", timeout=5) as r:
                return r.read().decode()
        except OSError:
            return None

    def metric(self, name: str, **labels: str) -> float | None:
        text = self.metrics_text() or ""
        for family in text_string_to_metric_families(text):
            for s in family.samples:
                if s.name == name and all(s.labels.get(k) == v for k, v in labels.items()):
                    return float(s.value)
        return None


def first_run(test: str) -> str:
    """The name of the run the operator starts when a test is created: ``<test>-g1``."""
    return f"{test}-g1"


def wait_exists(cluster: Cluster, namespace: str, obj: str, timeout: float = 120) -> None:
    """Until ``kind/name`` exists (kubectl wait needs the object to be there first)."""
    assert cluster.wait_until(
        lambda: cluster.kubectl("get", obj, "-n", namespace, "-o", "name", check=False) != "",
        timeout,
        interval=1.0,
    ), f"{obj} never appeared"


def wait_status(
    cluster: Cluster,
    namespace: str,
    name: str,
    jsonpath: str,
    value: str,
    timeout: float,
    kind: str = "uavtestrun",
) -> None:
    """kubectl wait --for=jsonpath=... on a UavTestRun (default) or a UavTest (no polling in the test)."""
    wait_exists(cluster, namespace, f"{kind}/{name}")
    cluster.kubectl(
        "wait",
        "-n",
        namespace,
        f"{kind}/{name}",
        f"--for=jsonpath={jsonpath}={value}",
        f"--timeout={int(timeout)}s",
        timeout=timeout + 30,
    )


def wait_complete(
    cluster: Cluster, namespace: str, test: str, timeout: float = 900, *, run: str | None = None
) -> dict[str, Any]:
    """The final status of a run of TEST (default: its first run, ``<test>-g1``)."""
    run = run or first_run(test)
    wait_status(
        cluster, namespace, run, '{.status.conditions[?(@.type=="Complete")].status}', "True", timeout
    )
    return cluster.kubectl_json("get", "uavtestrun", run, "-n", namespace)["status"]


def store_keys(minio: MinioServer, bucket: str, prefix: str) -> list[str]:
    return sorted(o.object_name for o in minio.client().list_objects(bucket, prefix=prefix, recursive=True))


def fresh_bucket(minio: MinioServer, prefix: str) -> str:
    """A new, empty bucket for one test module."""
    name = f"{prefix}-{secrets.token_hex(3)}"
    minio.client().make_bucket(name)
    return name


@contextlib.contextmanager
def running_operator(
    cluster: Cluster, namespace: str, minio: MinioServer, runner_image: str, bucket: str, tmp: Path
) -> Iterator[Operator]:
    """`uavtest operator` under the chart's least-privilege RBAC, storing to ``bucket``.

    On exit the module's UavTests (and their UavTestRuns) are deleted while the operator still runs
    (it removes its finalizer from them), then the operator stops.
    """
    install_crd(cluster)
    op = Operator(
        cluster,
        namespace,
        minio,
        bucket=bucket,
        pod_endpoint=pod_reachable(cluster, namespace, runner_image, minio.endpoint),
        kubeconfig=least_privilege_kubeconfig(cluster, namespace, tmp / "kubeconfig"),
        log=tmp / "operator.log",
        runner_image=runner_image,
    )
    op.start()
    try:
        yield op
    finally:
        for kind in ("uavtests", "uavtestruns"):  # a test's runs go with it (owner references)
            cluster.kubectl(
                "delete", kind, "--all", "-n", namespace, "--timeout=120s", check=False, timeout=150
            )
        op.stop()
