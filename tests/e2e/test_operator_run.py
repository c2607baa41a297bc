"""The operator on a real cluster: kubectl apply a UavTest → real pods fly the built-in sim → MinIO → status.

The operator runs as `uavtest operator` with a ServiceAccount holding only the chart's RBAC rules.
"""

from __future__ import annotations

import base64
import json
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from e2e.operator_support import (
    Operator,
    assert_no_root_credentials,
    first_run,
    store_keys,
    wait_complete,
    wait_exists,
    wait_status,
)
from harness.cluster import REPO_ROOT, Cluster, KubectlError
from harness.kstatus import KstatusUnavailable, kstatus
from harness.minio import MinioServer

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

EXAMPLES = REPO_ROOT / "examples"
FORBIDDEN = re.compile(r"forbidden|\(403\)|'code': 403", re.IGNORECASE)


@pytest.fixture(scope="module")
def operator(operator: Operator) -> Iterator[Operator]:
    """The conftest's operator, whose log must show no call the chart's RBAC refused."""
    yield operator
    op = operator
    # an HTTP 403 Forbidden answer (kopf: APIForbiddenError ... 'code': 403; kubernetes client:
    # "(403)" / "Reason: Forbidden"), not a "403" inside a timestamp such as "08:38:59,403"
    forbidden = [line for line in op.log_text().splitlines() if FORBIDDEN.search(line)]
    assert not forbidden, f"the chart's RBAC misses a call: {forbidden[:5]}"


def apply_example(cluster: Cluster, namespace: str, name: str) -> str:
    """kubectl apply an example as JSON (the examples are YAML 1.2; kubectl reads a bare `y:` as true)."""
    doc = yaml.safe_load((EXAMPLES / name).read_text())
    cluster.kubectl("apply", "-n", namespace, "-f", "-", input=json.dumps(doc))
    return str(doc["metadata"]["name"])


@pytest.fixture(scope="module")
def obstacle_pass(cluster: Cluster, namespace: str, operator: Operator) -> tuple[str, dict[str, Any]]:
    """examples/uavtest.yaml applied as is and flown to the end: (name, final status).

    Created here, not by a test, so each test that reads it runs on its own too."""
    cluster.kubectl("apply", "-n", namespace, "-f", str(EXAMPLES / "uavtest.yaml"))  # the file as is
    name = yaml.safe_load((EXAMPLES / "uavtest.yaml").read_text())["metadata"]["name"]
    return name, wait_complete(cluster, namespace, name)


def test_example_flies_in_parallel_pods_and_reports(
    cluster: Cluster,
    namespace: str,
    operator: Operator,
    minio: MinioServer,
    bucket: str,
    obstacle_pass: tuple[str, dict[str, Any]],
) -> None:
    name, status = obstacle_pass
    log = operator.log_text()[-4000:]
    assert status["phase"] == "Succeeded", (status, log)
    assert (status["replicas"], status["passed"], status["failed"], status["errors"]) == (3, 3, 0, 0)
    assert status["flakiness"] == 0 and status["flaky"] is False
    assert sorted((r["index"], r["seed"], r["verdict"]) for r in status["results"]) == [
        (0, 7, "pass"),
        (1, 8, "pass"),
        (2, 9, "pass"),
    ]
    # one Indexed Job, its pods: sitl as a native sidecar next to the runner
    jobs = cluster.kubectl_json("get", "jobs", "-n", namespace, "-l", f"uavtest.io/test={name}")["items"]
    assert len(jobs) == 1
    assert jobs[0]["spec"]["completionMode"] == "Indexed" and jobs[0]["spec"]["completions"] == 3
    pods = cluster.kubectl_json("get", "pods", "-n", namespace, "-l", f"uavtest.io/test={name}")["items"]
    indexes = sorted(int(p["metadata"]["labels"]["batch.kubernetes.io/job-completion-index"]) for p in pods)
    assert indexes == [0, 1, 2]
    assert all(p["status"]["phase"] == "Succeeded" for p in pods)
    # artifacts of every replica and the aggregate are in MinIO
    run = status["runId"]
    keys = store_keys(minio, bucket, f"{namespace}/{name}/{run}/")
    for i in range(3):
        for artifact in ("flight.ulg", "trajectory.csv", "result.json"):
            assert f"{namespace}/{name}/{run}/replica-{i}/{artifact}" in keys
    assert f"{namespace}/{name}/{run}/aggregate/summary.json" in keys
    summary = json.loads(
        minio.client().get_object(bucket, f"{namespace}/{name}/{run}/aggregate/summary.json").read()
    )
    assert summary["passed"] == 3
    # the competition's outcomes: each replica's 2-D distance and points, the run's total
    assert all(r["points"] in (0, 1, 2, 5) and r["minDistance2D"] >= 0 for r in status["results"])
    assert summary["competition_points"]["count"] == 3
    assert summary["competition_points"]["total"] == sum(r["points"] for r in status["results"])
    assert status["artifacts"]["summary"] == f"s3://{bucket}/{namespace}/{name}/{run}/aggregate/summary.json"
    # the replicas wrote with the run's upload policy only: no copy of the store's keys in the namespace
    secrets = assert_no_root_credentials(cluster, namespace, minio)
    upload = next(s for s in secrets if s["metadata"]["name"] == f"{jobs[0]['metadata']['name']}-upload")
    assert [r["kind"] for r in upload["metadata"]["ownerReferences"]] == ["UavTestRun"]
    # the run is owned by its test, the Job by the run
    run_obj = cluster.kubectl_json("get", "uavtestrun", first_run(name), "-n", namespace)
    assert [r["kind"] for r in run_obj["metadata"]["ownerReferences"]] == ["UavTest"]
    assert [r["kind"] for r in jobs[0]["metadata"]["ownerReferences"]] == ["UavTestRun"]
    policy = json.loads(base64.b64decode(upload["data"]["policy"]))
    assert policy["bucket"] == bucket and policy["key_prefix"] == f"{namespace}/{name}/{run}/"
    runner = jobs[0]["spec"]["template"]["spec"]["containers"][0]
    assert {e["name"] for e in runner["env"]} & {"UAVTEST_S3_ACCESS_KEY", "UAVTEST_S3_SECRET_KEY"} == set()
    # Events and metrics
    events = cluster.kubectl(
        "get", "events", "-n", namespace, "--field-selector", f"involvedObject.name={first_run(name)}"
    )
    assert "TestPassed" in events
    # metrics keyed by the test (not the run), namespace as test_namespace; the test's summary
    # follows its run's final status
    wait_status(cluster, namespace, name, "{.status.lastRun.phase}", "Succeeded", 120, kind="uavtest")
    labels = {"test_namespace": namespace, "test": name}
    assert operator.metric("uavtest_test_last_run_replicas", verdict="pass", **labels) == 3
    assert operator.metric("uavtest_test_last_run_flakiness", **labels) == 0
    assert operator.metric("uavtest_test_runs_total", result="succeeded", **labels) == 1
    assert (operator.metric("uavtest_min_obstacle_distance_meters_count", test_namespace=namespace) or 0) >= 3


def test_kubectl_get_shows_the_columns(
    cluster: Cluster, namespace: str, obstacle_pass: tuple[str, dict[str, Any]]
) -> None:
    name, _ = obstacle_pass
    wait_status(cluster, namespace, name, "{.status.lastRun.phase}", "Succeeded", 120, kind="uavtest")
    out = cluster.kubectl("get", "uavtr", first_run(name), "-n", namespace).splitlines()
    header = out[0].split()
    assert header[:6] == ["NAME", "TEST", "PHASE", "REPLICAS", "PASSED", "FAILED"]
    assert "FLAKINESS" in header
    row = dict(zip(header, out[1].split(), strict=False))
    assert (row["TEST"], row["PHASE"], row["REPLICAS"], row["PASSED"], row["FAILED"], row["FLAKINESS"]) == (
        name,
        "Succeeded",
        "3",
        "3",
        "0",
        "0",
    )
    out = cluster.kubectl("get", "uavt", name, "-n", namespace).splitlines()
    header = out[0].split()
    assert header[:4] == ["NAME", "PHASE", "LAST-RUN", "FLAKINESS"]
    row = dict(zip(header, out[1].split(), strict=False))
    assert (row["PHASE"], row["LAST-RUN"], row["FLAKINESS"]) == ("Succeeded", first_run(name), "0")
    assert "RUNS" in header and "FLAKY-RATE" in header


def kstatus_of(cluster: Cluster, namespace: str, obj: str) -> str:
    """kstatus (the library Flux uses, built from Go modules) of a real object read back from the cluster."""
    try:
        return kstatus(cluster.kubectl_json("get", obj, "-n", namespace))[0]
    except KstatusUnavailable as e:
        pytest.skip(str(e))


def test_gitops_health_a_passing_test_and_its_run_read_current(
    cluster: Cluster, namespace: str, obstacle_pass: tuple[str, dict[str, Any]]
) -> None:
    name, _ = obstacle_pass
    wait_status(cluster, namespace, name, "{.status.lastRun.phase}", "Succeeded", 120, kind="uavtest")
    assert kstatus_of(cluster, namespace, f"uavtestrun/{first_run(name)}") == "Current"
    assert kstatus_of(cluster, namespace, f"uavtest/{name}") == "Current"


def test_a_failing_test_ends_failed(cluster: Cluster, namespace: str, operator: Operator) -> None:
    name = apply_example(cluster, namespace, "collision.yaml")
    wait_exists(cluster, namespace, f"uavtestrun/{first_run(name)}")
    cluster.kubectl(
        "wait",
        "-n",
        namespace,
        f"uavtestrun/{first_run(name)}",
        "--for=condition=Failed",
        "--timeout=900s",
        timeout=930,
    )
    status = cluster.kubectl_json("get", "uavtestrun", first_run(name), "-n", namespace)["status"]
    assert status["phase"] == "Failed"
    assert status["failed"] == 3 and status["flakiness"] == 1 and status["flaky"] is False
    assert all(r["verdict"] == "fail" and r["reason"] for r in status["results"])
    # GitOps health (kstatus, as Flux reads it): the run and the test read Failed
    assert kstatus_of(cluster, namespace, f"uavtestrun/{first_run(name)}") == "Failed"
    wait_status(cluster, namespace, name, "{.status.lastRun.phase}", "Failed", 120, kind="uavtest")
    assert kstatus_of(cluster, namespace, f"uavtest/{name}") == "Failed"
    # a fail verdict is a result, not an accident: never retried
    job = cluster.kubectl_json("get", "jobs", "-n", namespace, "-l", f"uavtest.io/test={name}")["items"][0]
    pods = cluster.kubectl_json("get", "pods", "-n", namespace, "-l", f"uavtest.io/test={name}")["items"]
    assert len(pods) == 3, [p["metadata"]["name"] for p in pods]
    assert job["status"].get("failedIndexes") == "0-2"


def test_a_flaky_example_reports_flakiness_between_0_and_1(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    name = apply_example(cluster, namespace, "near-miss-wind.yaml")
    status = wait_complete(cluster, namespace, name, timeout=1800)
    assert status["passed"] > 0 and status["failed"] > 0, status
    assert 0 < status["flakiness"] < 1 and status["flaky"] is True
    flaky = next(c for c in status["conditions"] if c["type"] == "Flaky")
    assert flaky["status"] == "True"
    events = cluster.kubectl(
        "get", "events", "-n", namespace, "--field-selector", f"involvedObject.name={first_run(name)}"
    )
    assert "FlakyTest" in events


def test_a_changed_spec_and_a_rerun_start_new_runs_and_history_keeps_the_newest(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    """GitOps edits a test in place: the apply is accepted and starts a new run; the old run stays
    until the history limit removes it; deleting the test removes its runs and Jobs."""
    doc = yaml.safe_load((EXAMPLES / "hover.yaml").read_text())
    name = "edited-in-place"  # (not "history": kubectl reads that as a word of its own)
    doc["metadata"] = {"name": name, "namespace": namespace}
    doc["spec"].update(replicas=1, successfulRunsHistoryLimit=2)
    cluster.kubectl("apply", "-f", "-", input=json.dumps(doc))
    first = wait_complete(cluster, namespace, name)
    assert first["phase"] == "Succeeded", first
    # edit in place (kubectl apply of a changed spec): accepted, a new run with the new spec
    doc["spec"]["replicas"] = 2
    cluster.kubectl("apply", "-f", "-", input=json.dumps(doc))
    assert kstatus_of(cluster, namespace, f"uavtest/{name}") == "InProgress"  # until its new run passes
    second = wait_complete(cluster, namespace, name, run=f"{name}-g2")
    assert (second["replicas"], second["passed"]) == (2, 2), second
    runs = cluster.kubectl_json("get", "uavtestruns", "-n", namespace, "-l", f"uavtest.io/test={name}")[
        "items"
    ]
    assert sorted(r["metadata"]["name"] for r in runs) == [f"{name}-g1", f"{name}-g2"]
    assert {r["spec"]["testSpec"]["replicas"] for r in runs} == {1, 2}  # each run keeps what it flew
    # an explicit re-run: a new value of the annotation
    cluster.kubectl("annotate", "-n", namespace, f"uavtest/{name}", "uavtest.io/rerun=nightly-1")
    wait_status(cluster, namespace, name, "{.status.lastRerun}", "nightly-1", 120, kind="uavtest")
    runs = cluster.kubectl_json("get", "uavtestruns", "-n", namespace, "-l", f"uavtest.io/test={name}")[
        "items"
    ]
    rerun = next(r["metadata"]["name"] for r in runs if r["spec"]["trigger"] == "rerun")
    wait_complete(cluster, namespace, name, run=rerun)
    # history: the 2 newest passing runs are kept, the oldest is deleted; the test summarises them
    wait_status(cluster, namespace, name, "{.status.lastRun.name}", rerun, 120, kind="uavtest")
    assert cluster.wait_until(
        lambda: (
            cluster.kubectl("get", "uavtestrun", f"{name}-g1", "-n", namespace, "--ignore-not-found") == ""
        ),
        120,
        interval=1.0,
    )
    test = cluster.kubectl_json("get", "uavtest", name, "-n", namespace)
    wait_status(cluster, namespace, name, "{.status.runs}", "2", 120, kind="uavtest")
    test = cluster.kubectl_json("get", "uavtest", name, "-n", namespace)
    st = test["status"]
    assert st["observedGeneration"] == test["metadata"]["generation"] == 2
    assert (st["succeeded"], st["failed"], st["flakyRuns"], st["flakyRate"]) == (2, 0, 0, 0)
    conds = {c["type"]: c["status"] for c in st["conditions"]}
    assert (conds["Ready"], conds["Reconciling"], conds["Stalled"]) == ("True", "False", "False")
    labels = {"test_namespace": namespace, "test": name}
    assert operator.metric("uavtest_test_runs_total", result="succeeded", **labels) == 3
    assert operator.metric("uavtest_test_flaky_rate", **labels) == 0
    # deleting the test removes its runs and their Jobs (the artifacts in the store stay)
    cluster.kubectl("delete", "uavtest", name, "-n", namespace, "--timeout=120s", timeout=150)
    selector = f"uavtest.io/test={name}"

    def gone() -> bool:
        left = cluster.kubectl("get", "uavtestruns,jobs", "-n", namespace, "-l", selector, "-o", "name")
        return left == ""

    assert cluster.wait_until(gone, 180, interval=2.0)


def test_an_invalid_test_is_rejected_at_admission_naming_the_field(cluster: Cluster, namespace: str) -> None:
    bad = yaml.safe_load((EXAMPLES / "hover.yaml").read_text())
    bad["metadata"] = {"name": "bad-replicas", "namespace": namespace}
    bad["spec"]["replicas"] = 0
    with pytest.raises(KubectlError) as e:
        cluster.kubectl("apply", "-f", "-", input=json.dumps(bad))
    assert "spec.replicas" in e.value.stderr
    assert cluster.kubectl("get", "uavtest", "bad-replicas", "-n", namespace, check=False) == ""


def test_uavtest_run_engine_kubernetes_waits_and_exits_like_the_local_engine(
    cluster: Cluster, namespace: str, operator: Operator, tmp_path: Path
) -> None:
    def run(example: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [
                sys.executable,
                "-m",
                "uavtest.cli",
                "run",
                str(EXAMPLES / example),
                "--engine",
                "kubernetes",
                "--namespace",
                namespace,
            ],
            env=cluster.env(),
            capture_output=True,
            text=True,
            timeout=1200,
        )

    passing = run("hover.yaml")
    assert passing.returncode == 0, passing.stderr[-3000:]
    assert "3 passed" in passing.stderr
    failing = run("collision.yaml")
    assert failing.returncode == 1, failing.stderr[-3000:]


def test_a_run_created_by_hand_flies_the_tests_spec_and_belongs_to_the_test(
    cluster: Cluster, namespace: str, operator: Operator
) -> None:
    """`kubectl create` of a UavTestRun naming its test: an explicit re-run a person or a CI job
    makes without touching the test. It flies the test's current spec, is owned and counted by
    the test like the runs the operator starts, and goes when the test is deleted."""
    name = "by-hand"
    doc = yaml.safe_load((EXAMPLES / "hover.yaml").read_text())
    doc["metadata"] = {"name": name, "namespace": namespace}
    doc["spec"]["replicas"] = 1
    cluster.kubectl("apply", "-n", namespace, "-f", "-", input=json.dumps(doc))
    wait_complete(cluster, namespace, name)
    run = {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTestRun",
        "metadata": {"name": f"{name}-manual-1", "namespace": namespace},
        "spec": {"testName": name, "trigger": "manual"},
    }
    cluster.kubectl("create", "-f", "-", input=json.dumps(run))
    status = wait_complete(cluster, namespace, name, run=f"{name}-manual-1")
    assert status["phase"] == "Succeeded" and status["passed"] == 1, status
    made = cluster.kubectl_json("get", "uavtestrun", f"{name}-manual-1", "-n", namespace)
    test = cluster.kubectl_json("get", "uavtest", name, "-n", namespace)
    assert made["spec"]["testSpec"]["mission"] == test["spec"]["mission"]  # the test's spec, copied in
    (owner,) = made["metadata"]["ownerReferences"]
    assert (owner["kind"], owner["name"], owner["uid"]) == ("UavTest", name, test["metadata"]["uid"])
    assert made["metadata"]["labels"]["uavtest.io/test"] == name
    # the test counts it: its newest run, two kept runs, both in the metrics
    wait_status(cluster, namespace, name, "{.status.lastRun.name}", f"{name}-manual-1", 120, kind="uavtest")
    wait_status(cluster, namespace, name, "{.status.runs}", "2", 120, kind="uavtest")
    labels = {"test_namespace": namespace, "test": name}
    assert operator.metric("uavtest_test_runs_total", result="succeeded", **labels) == 2
    # deleting the test takes the hand-made run and its Job with it
    cluster.kubectl("delete", "uavtest", name, "-n", namespace, "--timeout=120s", timeout=150)
    assert cluster.wait_until(
        lambda: (
            cluster.kubectl(
                "get", "uavtestruns,jobs", "-n", namespace, "-l", f"uavtest.io/test={name}", "-o", "name"
            )
            == ""
        ),
        120,
        interval=1.0,
    )
