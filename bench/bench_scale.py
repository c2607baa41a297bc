"""Scale benchmark of the operator against kwok fake nodes: many UavTests at once.

    python bench/bench_scale.py [--tests 200] [--replicas 10] [--nodes 20]

Starts its own control plane with kwok (tests/harness: nothing runs in the pods; kwok turns each
pod Running, then Succeeded), the operator as a subprocess (`uavtest operator`) aggregating from a
MinIO (`--store minio`, the default) or a local folder (`--store local`),
creates TESTS UavTests of REPLICAS replicas each at once, and prints:

- seconds until every Job exists, and until every run's status is final (Complete=True): each
  UavTest gets its first run (a UavTestRun the operator creates), which gets the Job;
- the operator's peak RSS (VmHWM of the process);
- API requests the operator's work caused per test, from the apiserver's apiserver_request_total
  (mutating verbs on the resources only the operator writes; the bench's own POSTs are subtracted);
- phases of the final statuses. kwok's pods upload nothing, so every replica ends `error` with
  "artifacts missing" and every test `Error`: the honest outcome of a run without artifacts.

Targets (issue 9, with runs and history): every Job within 20 s, RSS under 300 MB.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
import urllib.request
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

from harness.cluster import Cluster, free_ports, start_cluster  # noqa: E402
from harness.minio import MinioServer, start_minio  # noqa: E402

GROUP, VERSION, PLURAL, RUNS = "uavtest.io", "v1alpha1", "uavtests", "uavtestruns"
NAMESPACE = "bench"
BUCKET = "uavtest-bench"


def test_manifest(i: int, replicas: int) -> dict[str, Any]:
    return {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "UavTest",
        "metadata": {"name": f"scale-{i:04d}", "namespace": NAMESPACE},
        "spec": {
            "replicas": replicas,
            "seed": i * 100,
            "timeout": 60,
            "mission": {"waypoints": [{"x": 0, "y": 0, "z": -10}, {"x": 30, "y": 0, "z": -10}]},
        },
    }


def fake_node(i: int) -> dict[str, Any]:
    name = f"kwok-bench-{i}"
    cap = {"cpu": "64", "memory": "512Gi", "pods": "250"}
    return {
        "apiVersion": "v1",
        "kind": "Node",
        "metadata": {
            "name": name,
            "annotations": {"node.alpha.kubernetes.io/ttl": "0", "kwok.x-k8s.io/node": "fake"},
            "labels": {"kubernetes.io/hostname": name, "kubernetes.io/os": "linux", "type": "kwok"},
        },
        "status": {"allocatable": cap, "capacity": cap},
    }


def request_counts(cluster: Cluster) -> Counter[tuple[str, str, str]]:
    """apiserver_request_total summed by (verb, resource, subresource)."""
    text = cluster.kubectl("get", "--raw", "/metrics", timeout=60)
    out: Counter[tuple[str, str, str]] = Counter()
    for line in text.splitlines():
        if not line.startswith("apiserver_request_total{"):
            continue
        labels_text, value = line[len("apiserver_request_total{") :].rsplit("} ", 1)
        labels = dict(part.split("=", 1) for part in labels_text.split('",') if "=" in part)
        labels = {k: v.strip('"') for k, v in labels.items()}
        out[(labels.get("verb", ""), labels.get("resource", ""), labels.get("subresource", ""))] += int(
            float(value)
        )
    return out


def peak_rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def metrics_up(port: int) -> bool:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=2) as r:
            return bool(r.status == 200)
    except OSError:
        return False


@contextmanager
def operator_process(
    cluster: Cluster, minio: MinioServer | None, store_dir: Path, log: Path, metrics_port: int
) -> Iterator[subprocess.Popen[bytes]]:
    env = {
        **cluster.env(),
        "UAVTEST_OPERATOR_RUNNER_IMAGE": "uavtest-runner:bench",
        "UAVTEST_OPERATOR_IMAGE_PULL_POLICY": "Never",
    }
    if minio is not None:
        env.update(
            UAVTEST_OPERATOR_STORE_URL=f"s3://{BUCKET}",
            UAVTEST_S3_ENDPOINT=minio.endpoint,
            UAVTEST_S3_ACCESS_KEY=minio.access_key,
            UAVTEST_S3_SECRET_KEY=minio.secret_key,
            UAVTEST_S3_RETRY_TOTAL="10",
        )
    else:
        env["UAVTEST_OPERATOR_STORE_URL"] = store_dir.as_uri()
    with open(log, "wb") as out:
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "uavtest.cli",
                "operator",
                "-n",
                NAMESPACE,
                "--metrics-port",
                str(metrics_port),
            ],
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
        )
        try:
            yield proc
        finally:
            proc.terminate()
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)


class Watcher:
    """Records when each Job appears and when each UavTest's status becomes final (one watch each)."""

    def __init__(self, kubeconfig: Path, expected: int) -> None:
        import kubernetes

        self.api = kubernetes.config.new_client_from_config(config_file=str(kubeconfig))
        self.expected = expected
        self.jobs: dict[str, float] = {}
        self.final: dict[str, float] = {}
        self.phases: dict[str, str] = {}
        self.all_jobs = threading.Event()
        self.all_final = threading.Event()
        self._stop = threading.Event()
        self._threads = [
            threading.Thread(target=self._watch_jobs, daemon=True),
            threading.Thread(target=self._watch_tests, daemon=True),
        ]

    def start(self) -> None:
        for t in self._threads:
            t.start()

    def stop(self) -> None:
        self._stop.set()

    def _watch_jobs(self) -> None:
        import kubernetes

        batch = kubernetes.client.BatchV1Api(self.api)
        while not self._stop.is_set() and not self.all_jobs.is_set():
            for ev in kubernetes.watch.Watch().stream(
                batch.list_namespaced_job, NAMESPACE, timeout_seconds=30
            ):
                self.jobs.setdefault(ev["object"].metadata.name, time.monotonic())
                if len(self.jobs) >= self.expected:
                    self.all_jobs.set()
                    return

    def _watch_tests(self) -> None:
        import kubernetes

        custom = kubernetes.client.CustomObjectsApi(self.api)
        while not self._stop.is_set() and not self.all_final.is_set():
            stream = kubernetes.watch.Watch().stream(
                custom.list_namespaced_custom_object, GROUP, VERSION, NAMESPACE, RUNS, timeout_seconds=30
            )
            for ev in stream:
                obj = ev["object"]
                status = obj.get("status") or {}
                complete = any(
                    c.get("type") == "Complete" and c.get("status") == "True"
                    for c in status.get("conditions") or []
                )
                if complete:
                    name = obj["metadata"]["name"]
                    self.final.setdefault(name, time.monotonic())
                    self.phases[name] = status.get("phase", "?")
                    if len(self.final) >= self.expected:
                        self.all_final.set()
                        return


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tests", type=int, default=200)
    ap.add_argument("--replicas", type=int, default=10)
    ap.add_argument("--nodes", type=int, default=20, help="extra kwok fake nodes (250 pods each)")
    ap.add_argument("--timeout", type=float, default=1800, help="give up after this many seconds")
    ap.add_argument("--store", choices=["minio", "local"], default="minio", help="what the operator reads")
    ap.add_argument("--no-build", action="store_true", help="use the cached cluster binaries as they are")
    args = ap.parse_args()

    print(f"bench_scale: {args.tests} UavTests × {args.replicas} replicas on kwok", flush=True)
    cluster = start_cluster(real_node=False, kwok=True, build=not args.no_build)
    minio = start_minio() if args.store == "minio" else None
    try:
        if minio is not None:
            minio.client().make_bucket(BUCKET)
        cluster.kubectl("apply", "-f", str(REPO / "crds"))
        for plural in (PLURAL, RUNS):
            cluster.kubectl("wait", "--for=condition=Established", f"crd/{plural}.{GROUP}", "--timeout=60s")
        cluster.create_namespace(NAMESPACE)
        cluster.apply(*(fake_node(i) for i in range(args.nodes)))
        log = cluster.logs_dir / "operator.log"
        (metrics_port,) = free_ports(1)
        with operator_process(cluster, minio, cluster.dir / "store", log, metrics_port) as op:
            # the operator is up once its metrics answer; no test exists yet
            up = cluster.wait_until(lambda: metrics_up(metrics_port) or op.poll() is not None, 60)
            if not up or op.poll() is not None:
                print("operator did not start:\n" + log.read_text(errors="replace")[-3000:])
                return 3
            watcher = Watcher(cluster.kubeconfig, args.tests)
            watcher.start()
            before = request_counts(cluster)
            doc = json.dumps(
                {
                    "apiVersion": "v1",
                    "kind": "List",
                    "items": [test_manifest(i, args.replicas) for i in range(args.tests)],
                }
            )
            t0 = time.monotonic()
            cluster.kubectl("create", "-f", "-", input=doc, timeout=600)
            t_created = time.monotonic() - t0
            print(f"created {args.tests} UavTests in {t_created:.1f} s", flush=True)
            ok_jobs = watcher.all_jobs.wait(args.timeout)
            t_jobs = max(watcher.jobs.values()) - t0 if watcher.jobs else float("nan")
            print(f"every Job exists after {t_jobs:.1f} s ({len(watcher.jobs)} Jobs)", flush=True)
            ok_final = watcher.all_final.wait(max(args.timeout - (time.monotonic() - t0), 1))
            t_final = max(watcher.final.values()) - t0 if watcher.final else float("nan")
            after = request_counts(cluster)
            rss = peak_rss_mb(op.pid)
            watcher.stop()
        delta = after - before
        # requests only the operator sends (the job controller writes jobs/status, many write events)
        ours = {
            k: v
            for k, v in delta.items()
            if (k[0], k[1])
            in {
                ("PATCH", "uavtests"),
                ("PATCH", "uavtestruns"),
                ("POST", "uavtestruns"),
                ("POST", "jobs"),
                ("POST", "configmaps"),
            }
        }
        events = cluster.kubectl_json("get", "events", "-n", NAMESPACE)["items"]
        ours[("POST", "events", "on UavTests and runs")] = sum(
            e["involvedObject"]["kind"] in ("UavTest", "UavTestRun") for e in events
        )
        total = sum(ours.values())
        print(f"every status final after {t_final:.1f} s ({len(watcher.final)}/{args.tests})")
        print(f"operator peak RSS: {rss:.0f} MB")
        print(f"API requests per test (the operator's writes): {total / args.tests:.1f}")
        for (verb, res, sub), n in sorted(ours.items()):
            print(f"  {verb:6} {res}{'/' + sub if sub else ''}: {n} ({n / args.tests:.2f} per test)")
        watches = {
            k: v
            for k, v in delta.items()
            if k[0] in {"WATCH", "LIST"} and k[1] in {"uavtests", "uavtestruns", "jobs", "pods"}
        }
        print(
            f"  (LIST/WATCH on tests, runs, jobs, pods by everyone, the bench too: {sum(watches.values())})"
        )
        print(f"final phases: {dict(Counter(watcher.phases.values()))}")
        print(
            f"targets: Jobs within 20 s: {'met' if ok_jobs and t_jobs <= 20 else 'MISSED'}; "
            f"RSS < 300 MB: {'met' if rss < 300 else 'MISSED'}"
        )
        return 0 if ok_jobs and ok_final else 1
    finally:
        if minio is not None:
            minio.stop()
        cluster.stop()


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
