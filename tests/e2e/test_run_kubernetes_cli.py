"""`uavtest run --engine kubernetes` as a CI job uses it, on the real cluster with the operator running.

The options it honours: --replicas and --seed reach the UavTest it creates, --json prints the local
engine's RunSummary shape, --out brings the run's artifacts home from MinIO with the operator's S3
settings, --timeout gives up with exit 3 and leaves the test running; options it ignores are named.
Each test creates its own UavTest.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from pyulog import ULog

from e2e.operator_support import Operator
from harness.cluster import REPO_ROOT, Cluster
from harness.minio import MinioServer
from uavtest.analysis.models import ReplicaResult, RunSummary

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

HOVER = REPO_ROOT / "examples" / "hover.yaml"


def run_cli(cluster: Cluster, minio: MinioServer, *args: str) -> subprocess.CompletedProcess[str]:
    """`uavtest run ... --engine kubernetes` with this machine's view of the operator's store."""
    env = {
        **cluster.env(),
        "UAVTEST_S3_ENDPOINT": minio.endpoint,
        "UAVTEST_S3_ACCESS_KEY": minio.access_key,
        "UAVTEST_S3_SECRET_KEY": minio.secret_key,
        "COLUMNS": "300",
    }
    return subprocess.run(
        [sys.executable, "-m", "uavtest.cli", "run", *args, "--engine", "kubernetes"],
        env=env,
        capture_output=True,
        text=True,
        timeout=1500,
    )


def test_replicas_seed_out_and_json_are_honoured(
    cluster: Cluster, namespace: str, operator: Operator, minio: MinioServer, tmp_path: Path
) -> None:
    out = tmp_path / "artifacts"
    done = run_cli(
        cluster,
        minio,
        *(str(HOVER), "--namespace", namespace, "--replicas", "2", "--seed", "7"),
        *("--out", str(out), "--json", "--timeout", "1200", "--jobs", "4"),
    )
    assert done.returncode == 0, (done.stderr[-4000:], operator.log_text()[-3000:])
    stderr = " ".join(done.stderr.split())
    assert "ignored with --engine kubernetes: --jobs" in stderr
    # stdout is the local engine's --json: a RunSummary
    summary = RunSummary.model_validate_json(done.stdout)
    name = summary.test
    assert name == yaml.safe_load(HOVER.read_text())["metadata"]["name"]  # the test keeps its name
    assert summary.namespace == namespace
    assert (summary.replicas, summary.passed, summary.failed, summary.errors) == (2, 2, 0, 0)
    assert [(r.index, r.seed) for r in summary.results] == [(0, 7), (1, 8)]
    assert summary.flight_time is not None  # the store's summary.json, not only the status
    # the UavTest it applied carries the overrides, and the run it followed the seeds
    obj = cluster.kubectl_json("get", "uavtest", name, "-n", namespace)
    assert (obj["spec"]["replicas"], obj["spec"]["seed"]) == (2, 7)
    run_name = stderr.split("run uavtestrun/", 1)[1].split(":")[0]
    run_obj = cluster.kubectl_json("get", "uavtestrun", run_name, "-n", namespace)
    assert run_obj["spec"]["testName"] == name and run_obj["spec"]["testSpec"]["replicas"] == 2
    assert sorted((r["index"], r["seed"], r["verdict"]) for r in run_obj["status"]["results"]) == [
        (0, 7, "pass"),
        (1, 8, "pass"),
    ]
    # --out: the run's artifacts, in the store layout
    run = out / namespace / name / summary.run_id
    for i in (0, 1):
        replica = run / f"replica-{i}"
        assert {p.name for p in replica.iterdir()} >= {"flight.ulg", "trajectory.csv", "result.json"}
        result = ReplicaResult.model_validate_json((replica / "result.json").read_text())
        assert (result.index, result.seed, result.verdict) == (i, 7 + i, "pass")
        ulog = ULog(str(replica / "flight.ulg"), ["vehicle_local_position"])
        z = ulog.get_dataset("vehicle_local_position").data["z"]
        assert z.min() < -4.0  # the log holds the 5 m hover
        assert len((replica / "trajectory.csv").read_text().splitlines()) > 10
    assert json.loads((run / "aggregate" / "summary.json").read_text())["passed"] == 2


def test_timeout_exits_3_and_leaves_the_test_running(
    cluster: Cluster, namespace: str, operator: Operator, minio: MinioServer
) -> None:
    done = run_cli(cluster, minio, str(HOVER), "--namespace", namespace, "--replicas", "1", "--timeout", "1")
    try:
        assert done.returncode == 3, done.stderr[-3000:]
        stderr = " ".join(done.stderr.split())
        assert "still running" in stderr and "kubectl get uavtestrun/" in stderr
        name = stderr.split("run uavtestrun/", 1)[1].split(":")[0]
        obj = cluster.kubectl_json("get", "uavtestrun", name, "-n", namespace)  # still there
        complete = [c for c in obj.get("status", {}).get("conditions", []) if c["type"] == "Complete"]
        assert not complete or complete[0]["status"] != "True"
    finally:
        if done.returncode == 3 and "run uavtestrun/" in done.stderr:
            created = " ".join(done.stderr.split()).split("run uavtestrun/", 1)[1].split(":")[0]
            cluster.kubectl("delete", "uavtestrun", created, "-n", namespace, "--timeout=120s", check=False)


def test_two_tests_are_created_followed_and_reported_as_junit(
    cluster: Cluster, namespace: str, operator: Operator, minio: MinioServer, tmp_path: Path
) -> None:
    import junitparser

    slow = tmp_path / "hover-too-slow.yaml"
    text = HOVER.read_text().replace("name: hover", "name: hover-too-slow")
    slow.write_text(text.replace("maxFlightTime: 60", "maxFlightTime: 5"))
    report = tmp_path / "report.xml"
    out = tmp_path / "artifacts"
    done = run_cli(
        cluster,
        minio,
        *(str(HOVER), str(slow), "--namespace", namespace, "--replicas", "1"),
        *("--junit", str(report), "--json", "--out", str(out), "--timeout", "1200"),
    )
    assert done.returncode == 1, (done.stderr[-4000:], operator.log_text()[-3000:])  # one test failed
    summaries = [RunSummary.model_validate(s) for s in json.loads(done.stdout)]
    assert [(s.verdict, s.passed, s.failed) for s in summaries] == [("pass", 1, 0), ("fail", 0, 1)]
    assert [s.test for s in summaries] == ["hover", "hover-too-slow"]  # each test keeps its name
    stderr = " ".join(done.stderr.split())
    assert stderr.count("run uavtestrun/") == 2 and "exit 1: a test failed" in stderr
    doc = junitparser.JUnitXml.fromfile(str(report))
    assert [s.name for s in doc] == [s.test for s in summaries]
    assert (doc.tests, doc.failures, doc.errors) == (2, 1, 0)
    case = next(iter(list(doc)[1]))
    assert "flight time" in case.result[0].message
    links = dict(ln.split(": ", 1) for ln in (case.system_out or "").splitlines())
    run_key = f"{namespace}/{summaries[1].test}/{summaries[1].run_id}/replica-0"
    assert links["flight.ulg"].startswith("s3://") and links["flight.ulg"].endswith(f"{run_key}/flight.ulg")
    # the operator's aggregation wrote the same suite to the store, next to summary.json
    stored = out / namespace / summaries[1].test / summaries[1].run_id / "aggregate" / "junit.xml"
    (suite,) = list(junitparser.JUnitXml.fromfile(str(stored)))
    assert (suite.name, suite.tests, suite.failures) == (summaries[1].test, 1, 1)
