"""The replica Job and ConfigMap the operator creates for a UavTest (pure builders)."""

from __future__ import annotations

import os
import stat
import subprocess
from pathlib import Path
from typing import Any

import kubernetes
import pytest
import yaml

from uavtest.controller.jobs import (
    build_configmap,
    build_job,
    deadline_seconds,
    job_name_for,
    parallelism_for,
    run_id_for,
    unresolved_files,
)
from uavtest.controller.reconcile import parse_test
from uavtest.controller.settings import OperatorSettings
from uavtest.errors import BadInput
from uavtest.spec.loaders import load_test_text
from uavtest.store import S3Settings

from .controller_bodies import RUN, UID, uavtest_body

S3 = S3Settings(endpoint="minio.storage:9000", access_key="AKIAEXAMPLE", secret_key="s3cr3t-value")


def make_job(body: dict[str, Any] | None = None, **settings: Any) -> dict[str, Any]:
    body = body or uavtest_body()
    return build_job(parse_test(body), RUN, OperatorSettings(**settings), body)


def pod_spec(job: dict[str, Any]) -> dict[str, Any]:
    return job["spec"]["template"]["spec"]


def container(job: dict[str, Any], name: str) -> dict[str, Any]:
    spec = pod_spec(job)
    return next(c for c in [*spec.get("initContainers", []), *spec["containers"]] if c["name"] == name)


def test_one_indexed_job_with_a_completion_per_replica() -> None:
    job = make_job(uavtest_body(replicas=7, parallelism=3))
    spec = job["spec"]
    assert spec["completionMode"] == "Indexed"
    assert spec["completions"] == 7
    assert spec["parallelism"] == 3
    assert spec["backoffLimitPerIndex"] == 2
    assert spec["maxFailedIndexes"] == 7  # one bad replica never stops the others


def test_parallelism_defaults_to_all_replicas_and_respects_the_operator_cap() -> None:
    spec = parse_test(uavtest_body(replicas=12)).spec
    assert parallelism_for(spec, OperatorSettings()) == 12
    assert parallelism_for(spec, OperatorSettings(max_parallelism=5)) == 5


def test_deadline_covers_every_wave_and_retry_plus_margin() -> None:
    spec = parse_test(uavtest_body(replicas=10, parallelism=4, timeout=100)).spec
    # 3 waves × 100 s × (1 + 2 retries) + 300 s start-up margin
    assert deadline_seconds(spec, OperatorSettings()) == 3 * 100 * 3 + 300
    assert (
        make_job(uavtest_body(replicas=10, parallelism=4, timeout=100))["spec"]["activeDeadlineSeconds"]
        == 1200
    )


def test_fail_verdicts_are_final_and_only_bench_errors_are_retried() -> None:
    rules = make_job()["spec"]["podFailurePolicy"]["rules"]
    assert rules[0] == {
        "action": "Ignore",
        "onPodConditions": [{"type": "DisruptionTarget", "status": "True"}],
    }
    fail_index = rules[1]
    assert fail_index["action"] == "FailIndex"
    assert fail_index["onExitCodes"] == {"containerName": "runner", "operator": "In", "values": [1, 2]}
    count = rules[2]
    assert count["action"] == "Count"
    assert count["onExitCodes"]["operator"] == "NotIn"
    assert 3 not in count["onExitCodes"]["values"]  # exit 3 (bench error) is counted → retried
    assert make_job()["spec"]["podReplacementPolicy"] == "Failed"
    assert pod_spec(make_job())["restartPolicy"] == "Never"


def test_sitl_is_a_native_sidecar_so_the_pod_ends_with_the_runner() -> None:
    job = make_job()
    spec = pod_spec(job)
    assert [c["name"] for c in spec["initContainers"]] == ["sitl"]
    assert spec["initContainers"][0]["restartPolicy"] == "Always"
    assert [c["name"] for c in spec["containers"]] == ["runner"]
    sitl = container(job, "sitl")
    assert sitl["args"][:2] == ["--test", "/etc/uavtest/test.yaml"]
    assert "--lockstep" in sitl["args"]
    runner = container(job, "runner")
    assert "udpin:127.0.0.1:14540" in runner["args"]
    # both see the same ULog folder and the same test file
    logs = {m["mountPath"] for m in sitl["volumeMounts"]} & {m["mountPath"] for m in runner["volumeMounts"]}
    assert {"/var/uavtest/logs", "/etc/uavtest"} <= logs


def test_runner_writes_to_the_store_under_the_run_layout() -> None:
    args = container(make_job(), "runner")["args"]
    opts = dict(zip(args[::2], args[1::2], strict=True))
    assert opts["--store"] == "s3://uavtest"
    assert opts["--run-id"] == RUN
    assert opts["--namespace"] == "team-a"
    assert opts["--test-name"] == "hover"


def test_replica_pods_get_only_the_runs_upload_policy_never_store_keys() -> None:
    job = make_job()
    text = yaml.safe_dump(job)
    assert "AKIAEXAMPLE" not in text and "s3cr3t-value" not in text
    env = {e["name"]: e for e in container(job, "runner")["env"]}
    assert env["UAVTEST_S3_UPLOAD_POLICY"]["valueFrom"]["secretKeyRef"] == {
        "name": f"hover-{RUN}-upload",
        "key": "policy",
    }
    assert not {"UAVTEST_S3_ACCESS_KEY", "UAVTEST_S3_SECRET_KEY", "UAVTEST_S3_ENDPOINT"} & set(env)
    # the upload Secret is the only Secret any container of the pod refers to
    refs = [
        e["valueFrom"]["secretKeyRef"]["name"]
        for c in [*pod_spec(job)["initContainers"], *pod_spec(job)["containers"]]
        for e in c.get("env", [])
        if "secretKeyRef" in e.get("valueFrom", {})
    ]
    assert refs == [f"hover-{RUN}-upload"]
    assert not any("envFrom" in c for c in pod_spec(job)["containers"])
    # a file:// store (runs whose pods never fly, like the scale bench on kwok): no policy, no Secret
    local = make_job(store_url="file:///var/uavtest")
    assert "UAVTEST_S3_UPLOAD_POLICY" not in {e["name"] for e in container(local, "runner")["env"]}


def test_pods_run_unprivileged_without_a_service_account_token() -> None:
    spec = pod_spec(make_job())
    assert spec["automountServiceAccountToken"] is False
    assert spec["securityContext"]["runAsNonRoot"] is True
    assert spec["securityContext"]["runAsUser"] == 65532
    assert spec["securityContext"]["seccompProfile"] == {"type": "RuntimeDefault"}
    for c in [*spec["initContainers"], *spec["containers"]]:
        ctx = c["securityContext"]
        assert ctx["allowPrivilegeEscalation"] is False
        assert ctx["readOnlyRootFilesystem"] is True
        assert ctx["capabilities"] == {"drop": ["ALL"]}


def test_children_are_owned_by_and_labelled_for_their_test() -> None:
    body = uavtest_body()
    job = make_job(body)
    ref = job["metadata"]["ownerReferences"][0]
    assert (ref["kind"], ref["name"], ref["uid"], ref["controller"]) == ("UavTestRun", "hover-g1", UID, True)
    assert job["metadata"]["namespace"] == "team-a"
    for labels in (job["metadata"]["labels"], job["spec"]["template"]["metadata"]["labels"]):
        assert labels["uavtest.io/test"] == "hover"
        assert labels["uavtest.io/run"] == RUN
        assert labels["app.kubernetes.io/managed-by"] == "uavtest-operator"
    cm = build_configmap(parse_test(body), RUN, body)
    assert cm["metadata"]["name"] == job["metadata"]["name"]
    assert cm["metadata"]["ownerReferences"][0]["uid"] == UID
    assert pod_spec(job)["volumes"][0] == {"name": "test", "configMap": {"name": cm["metadata"]["name"]}}


def test_names_are_deterministic_and_fit_pod_hostnames() -> None:
    assert run_id_for(UID) == RUN
    assert job_name_for("hover", RUN) == f"hover-{RUN}"
    long = job_name_for("a" * 63, RUN)
    assert len(long) <= 48 and long.endswith(RUN)
    assert job_name_for("x" * 38 + "-" + "y" * 20, RUN) == "x" * 38 + f"-{RUN}"  # no "--"
    with pytest.raises(BadInput):
        run_id_for("abc")


def test_configmap_holds_the_test_the_sitl_and_runner_read() -> None:
    body = uavtest_body()
    cm = build_configmap(parse_test(body), RUN, body)
    loaded = load_test_text(cm["data"]["test.yaml"], "test.yaml")
    assert loaded.spec == parse_test(body).spec
    assert loaded.metadata.name == "hover"


def test_file_references_cannot_run_in_a_cluster() -> None:
    body = uavtest_body(mission={"planFile": "mission.plan"}, commandsFile="cmds.csv")
    assert unresolved_files(parse_test(body).spec) == ["spec.mission.planFile", "spec.commandsFile"]
    assert unresolved_files(parse_test(uavtest_body()).spec) == []


def test_px4_simulator_uses_its_image_and_needs_one() -> None:
    body = uavtest_body(vehicle={"simulator": "px4", "image": "px4io/px4-sitl:v1.15"})
    sitl = container(make_job(body), "sitl")
    assert sitl["image"] == "px4io/px4-sitl:v1.15"
    assert "command" not in sitl
    with pytest.raises(BadInput, match=r"spec\.vehicle\.image"):
        make_job(uavtest_body(vehicle={"simulator": "px4"}))


def test_manifests_have_only_fields_kubernetes_knows() -> None:
    # the kubernetes client's models drop unknown fields: a round trip must keep everything
    client = kubernetes.client.ApiClient()
    job = make_job()
    model = client._ApiClient__deserialize(job, "V1Job")  # type: ignore[attr-defined]
    assert client.sanitize_for_serialization(model) == job
    body = uavtest_body()
    cm = build_configmap(parse_test(body), RUN, body)
    cm_model = client._ApiClient__deserialize(cm, "V1ConfigMap")  # type: ignore[attr-defined]
    assert client.sanitize_for_serialization(cm_model) == cm


@pytest.mark.parametrize("name", ["sitl", "runner"])
def test_shell_wrapper_passes_index_and_seed(tmp_path: Path, name: str) -> None:
    """Run the container's real command with a stand-in ``uavtest`` that prints its arguments."""
    fake = tmp_path / "uavtest"
    fake.write_text('#!/bin/sh\nfor a in "$@"; do echo "$a"; done\n')
    fake.chmod(fake.stat().st_mode | stat.S_IEXEC)
    c = container(make_job(uavtest_body(seed=10)), name)
    env = {e["name"]: e["value"] for e in c["env"] if "value" in e}
    env.update(PATH=f"{tmp_path}:{os.environ['PATH']}", JOB_COMPLETION_INDEX="3")
    out = subprocess.run([*c["command"], *c["args"]], env=env, capture_output=True, text=True, check=True)
    argv = out.stdout.splitlines()
    assert argv[0] == name
    assert argv[argv.index("--seed") + 1] == "13"  # base 10 + index 3
    if name == "runner":
        assert argv[argv.index("--replica") + 1] == "3"
    assert argv[-len(c["args"]) :] == c["args"]
