"""Faults on a real cluster: the operator killed mid-run, a replica pod deleted, MinIO unreachable."""

from __future__ import annotations

import signal
import threading
from typing import Any

import pytest
import yaml

from e2e.operator_support import (
    Operator,
    first_run,
    store_keys,
    wait_complete,
)
from harness.cluster import REPO_ROOT, Cluster
from harness.minio import MinioServer

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

MINIO_OUTAGE_SECONDS = 30.0


def hover(name: str, namespace: str, *, replicas: int, parallelism: int, hold: float = 10) -> dict[str, Any]:
    """examples/hover.yaml, hovering HOLD seconds (long holds keep a replica in the air for a while)."""
    doc = yaml.safe_load((REPO_ROOT / "examples" / "hover.yaml").read_text())
    doc["metadata"] = {"name": name, "namespace": namespace}
    spec = doc["spec"]
    spec["replicas"] = replicas
    spec["parallelism"] = parallelism
    spec["mission"]["waypoints"][0]["hold"] = hold
    spec["timeout"] = max(spec["timeout"], hold + 120)
    spec["assertions"]["maxFlightTime"] = max(spec["assertions"]["maxFlightTime"], hold + 60)
    return doc


def runs_of(cluster: Cluster, namespace: str, name: str) -> list[dict[str, Any]]:
    return cluster.kubectl_json("get", "uavtestruns", "-n", namespace, "-l", f"uavtest.io/test={name}")[
        "items"
    ]


def jobs_of(cluster: Cluster, namespace: str, name: str) -> list[dict[str, Any]]:
    return cluster.kubectl_json("get", "jobs", "-n", namespace, "-l", f"uavtest.io/test={name}")["items"]


def wait_pod_running(cluster: Cluster, namespace: str, selector: str, timeout: float = 300) -> None:
    """Until a pod matching SELECTOR runs (kubectl wait needs the pod to exist first)."""
    assert cluster.wait_until(
        lambda: cluster.kubectl("get", "pods", "-n", namespace, "-l", selector, "-o", "name") != "", timeout
    )
    cluster.kubectl(
        "wait",
        "-n",
        namespace,
        "pod",
        "-l",
        selector,
        "--for=jsonpath={.status.phase}=Running",
        f"--timeout={int(timeout)}s",
        timeout=timeout + 30,
    )


def wait_running(cluster: Cluster, namespace: str, name: str, timeout: float = 300) -> None:
    """Until the UavTest's first replica pod runs."""
    wait_pod_running(
        cluster, namespace, f"uavtest.io/test={name},batch.kubernetes.io/job-completion-index=0", timeout
    )


def test_operator_killed_mid_run_restarts_without_duplicate_jobs(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    name = "killed-operator"
    cluster.apply(hover(name, namespace, replicas=3, parallelism=1))
    wait_running(cluster, namespace, name)
    operator.kill()
    operator.start()
    status = wait_complete(cluster, namespace, name)
    assert len(jobs_of(cluster, namespace, name)) == 1
    assert [r["metadata"]["name"] for r in runs_of(cluster, namespace, name)] == [first_run(name)]
    assert (status["replicas"], status["passed"], status["errors"]) == (3, 3, 0), status
    # the restarted operator kept the run's upload Secret: still one, the one its pods read
    uploads = cluster.kubectl(
        "get", "secrets", "-n", namespace, "-l", f"uavtest.io/test={name}", "-o", "name"
    )
    assert uploads.split() == [f"secret/{jobs_of(cluster, namespace, name)[0]['metadata']['name']}-upload"]


def test_operator_down_while_a_test_is_created_starts_it_once(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    name = "created-while-down"
    operator.kill()
    cluster.apply(hover(name, namespace, replicas=2, parallelism=2))
    operator.start()
    status = wait_complete(cluster, namespace, name)
    assert len(jobs_of(cluster, namespace, name)) == 1
    assert [r["metadata"]["name"] for r in runs_of(cluster, namespace, name)] == [first_run(name)]
    assert status["passed"] == 2


def test_a_deleted_replica_pod_is_retried_and_counted_once(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    name = "deleted-pod"
    # a 20-minute hover (some seconds of wall time in lockstep): the deletion hits a replica in flight
    cluster.apply(hover(name, namespace, replicas=2, parallelism=2, hold=1200))
    selector = f"uavtest.io/test={name},batch.kubernetes.io/job-completion-index=0"
    wait_pod_running(cluster, namespace, selector)
    deleted = cluster.kubectl("get", "pods", "-n", namespace, "-l", selector, "-o", "name").split()
    assert len(deleted) == 1
    # killed within a second, as a node loss would (a plain delete stops both containers in ~0.7 s too)
    cluster.kubectl("delete", "-n", namespace, deleted[0], "--grace-period=1", "--wait=false")
    status = wait_complete(cluster, namespace, name)
    assert (status["replicas"], status["passed"], status["failed"], status["errors"]) == (2, 2, 0, 0), status
    assert sorted(r["index"] for r in status["results"]) == [0, 1]
    # replica 0 flew again in a new pod, with the same index and seed
    again = cluster.kubectl_json("get", "pods", "-n", namespace, "-l", selector)["items"]
    everything = cluster.kubectl("get", "pods,jobs,events", "-n", namespace, "-o", "wide")
    assert [f"pod/{p['metadata']['name']}" for p in again] != deleted, everything
    assert [p["status"]["phase"] for p in again] == ["Succeeded"], (deleted, everything)
    job = jobs_of(cluster, namespace, name)[0]
    assert job["status"]["completedIndexes"] == "0,1"


def test_minio_unreachable_for_30s_while_replicas_upload_loses_nothing(
    cluster: Cluster, namespace: str, operator: Operator, minio: MinioServer, bucket: str
) -> None:
    name = "minio-outage"
    cluster.apply(hover(name, namespace, replicas=3, parallelism=3))
    wait_running(cluster, namespace, name)
    # the server stops answering (SIGSTOP: connections hang, like a partition) for 30 s
    minio.process.send_signal(signal.SIGSTOP)
    resume = threading.Timer(MINIO_OUTAGE_SECONDS, minio.process.send_signal, args=(signal.SIGCONT,))
    resume.start()
    try:
        status = wait_complete(cluster, namespace, name)
    finally:
        resume.join()
    assert (status["passed"], status["errors"]) == (3, 0), status
    # the outage really hit the uploads: the runners logged their retries
    logs = cluster.kubectl(
        "logs", "-n", namespace, "-l", f"uavtest.io/test={name}", "-c", "runner", "--tail=-1"
    )
    assert "retry" in logs, logs[-3000:]
    run = status["runId"]
    keys = store_keys(minio, bucket, f"{namespace}/{name}/{run}/")
    for i in range(3):
        for artifact in ("flight.ulg", "trajectory.csv", "result.json"):
            assert f"{namespace}/{name}/{run}/replica-{i}/{artifact}" in keys


def test_a_schedule_of_every_minute_across_an_operator_restart_skips_and_duplicates_nothing(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    name = "every-minute"
    doc = hover(name, namespace, replicas=1, parallelism=1, hold=1)
    doc["spec"].update(schedule="* * * * *", successfulRunsHistoryLimit=1, failedRunsHistoryLimit=1)
    cluster.apply(doc)
    wait_complete(cluster, namespace, name)  # the run of the test's creation

    def scheduled() -> list[str]:
        runs = runs_of(cluster, namespace, name)
        return sorted(r["spec"]["scheduledTime"] for r in runs if r["spec"]["trigger"] == "schedule")

    assert cluster.wait_until(lambda: scheduled() != [], 180, interval=2.0)
    operator.kill()  # in the middle of a scheduled run
    operator.start()
    # two more minutes come due after the restart
    test = cluster.kubectl_json("get", "uavtest", name, "-n", namespace)
    since = test["status"]["lastScheduleTime"]
    assert cluster.wait_until(
        lambda: (
            cluster.kubectl_json("get", "uavtest", name, "-n", namespace)["status"].get(
                "lastScheduleTime", ""
            )
            >= _plus_minutes(since, 2)
        ),
        300,
        interval=2.0,
    )

    # every run the operator created, from its Events on the test: one per minute, none twice, no
    # gap. kopf posts an Event from a background queue, after the status patch that moved
    # lastScheduleTime, so the last minute's Event may still be on its way: wait for it
    selector = f"involvedObject.name={name},reason=RunCreated"

    def schedule_events() -> list[dict]:
        items = cluster.kubectl_json("get", "events", "-n", namespace, "--field-selector", selector)["items"]
        return [e for e in items if "(schedule)" in e["message"]]

    def runs_created() -> int:
        return len({e["message"].split()[1] for e in schedule_events()})

    cluster.wait_until(lambda: runs_created() >= 3, 30, interval=2.0)
    events = schedule_events()
    created = sorted({e["message"].split()[1] for e in events})
    minutes = sorted(int(n.rsplit("-s", 1)[1]) for n in created)
    assert len(minutes) >= 3 and minutes == list(range(minutes[0], minutes[0] + len(minutes))), created
    assert all(e.get("count", 1) == 1 for e in events), events  # no run was created twice
    # history: at most one finished passing run kept, beside those still flying
    runs = runs_of(cluster, namespace, name)
    finished = [r for r in runs if r.get("status", {}).get("phase") in ("Succeeded", "Failed", "Error")]
    assert len(finished) <= 2, [r["metadata"]["name"] for r in runs]  # 1 kept + 1 not trimmed yet
    # the metrics summarise the kept runs: a hover always passes, so its flaky-rate over them is 0
    labels = {"test_namespace": namespace, "test": name}
    assert operator.metric("uavtest_test_flaky_rate", **labels) == 0.0
    kept = operator.metric("uavtest_test_kept_runs", result="succeeded", **labels)
    assert kept is not None and 1 <= kept <= 2, kept


def _plus_minutes(stamp: str, n: int) -> str:
    from datetime import datetime, timedelta

    when = datetime.fromisoformat(stamp.replace("Z", "+00:00")) + timedelta(minutes=n)
    return when.isoformat().replace("+00:00", "Z")
