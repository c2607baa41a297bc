"""The operator on a real cluster flies real PX4 SITL: a PX4 build packaged by
runner-image/build-px4-image.sh (no Docker), imported into the node's containerd, as the `sitl`
native sidecar of every replica pod next to the runner; verdicts, PX4's own ULogs in MinIO, status,
Events and metrics.

Needs a PX4 SITL (SIH) build: UAVTEST_PX4_BIN=<PX4-Autopilot>/build/px4_sitl_default/bin/px4
(the image is made from the build folder holding that binary); skipped without it.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import subprocess
from pathlib import Path
from typing import Any

import pytest
from pyulog import ULog

from e2e.operator_support import Operator, store_keys, wait_complete
from harness.cluster import CACHE_DIR, REPO_ROOT, Cluster
from harness.minio import MinioServer

PX4_BIN = os.environ.get("UAVTEST_PX4_BIN", "")
# a skip mark, not a fixture's pytest.skip: it holds before the session starts a cluster
pytestmark = [
    pytest.mark.e2e,
    pytest.mark.px4,
    pytest.mark.slow,
    pytest.mark.skipif(
        not PX4_BIN or not Path(PX4_BIN).is_file(), reason="UAVTEST_PX4_BIN does not name a PX4 SITL binary"
    ),
]

PX4_IMAGE = "uavtest-px4:e2e"
BUILD_SCRIPT = REPO_ROOT / "runner-image" / "build-px4-image.sh"
HOME = {"lat": 47.397742, "lon": 8.545594, "alt": 488.0}  # Zurich: not v1.15's default (Montreal)
REPLICAS = 3
#: 3 PX4 replicas at once on the suite's 2-core machine: each PX4 takes ~10 % of a core per 1x
#: and its runner follows PX4's telemetry; 2x keeps the three well inside the machine.
SPEED_FACTOR = 2


@pytest.fixture(scope="module")
def px4_build() -> Path:
    return Path(PX4_BIN).resolve().parent.parent  # build/px4_sitl_default


@pytest.fixture(scope="module")
def px4_image(cluster: Cluster, px4_build: Path) -> str:
    """The user's PX4 build as an image, made the way the README tells users to, in the node."""
    archive = CACHE_DIR / "share" / "uavtest-px4-e2e.tar"
    cmd = ["bash", str(BUILD_SCRIPT), str(px4_build), str(archive), "--thin", "--name", PX4_IMAGE]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=3600, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr[-3000:]
    cluster.import_image(archive)
    return PX4_IMAGE


def px4_hover(name: str, image: str) -> dict[str, Any]:
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": name},
        "spec": {
            "replicas": REPLICAS,
            "parallelism": REPLICAS,
            "seed": 1,
            "timeout": 300,  # vehicle seconds: PX4 boots ~36 s before its pre-arm checks pass
            "vehicle": {
                "simulator": "px4",
                "image": image,
                "speedFactor": SPEED_FACTOR,
                "params": {"MIS_TAKEOFF_ALT": 5},
            },
            "world": {"home": HOME},
            "mission": {
                "takeoffAltitude": 5,
                "waypoints": [{"x": 0, "y": 0, "z": -5, "hold": 10}],
                "land": True,
            },
            "commands": [{"at": 1, "action": "mode", "mode": "mission"}],
            "assertions": {"noCollision": True, "missionCompleted": True, "maxFlightTime": 120},
        },
    }


def test_px4_replicas_fly_in_pods_and_their_ulogs_reach_the_store(
    cluster: Cluster,
    namespace: str,
    operator: Operator,
    minio: MinioServer,
    bucket: str,
    px4_image: str,
) -> None:
    name = "px4-hover"
    cluster.apply({**px4_hover(name, px4_image), "metadata": {"name": name, "namespace": namespace}})
    status = wait_complete(cluster, namespace, name, timeout=1800)
    assert status["phase"] == "Succeeded", (status, operator.log_text()[-4000:])
    assert (status["replicas"], status["passed"], status["failed"], status["errors"]) == (REPLICAS, 3, 0, 0)
    assert sorted((r["index"], r["verdict"]) for r in status["results"]) == [(i, "pass") for i in range(3)]

    # real pods: PX4 SITL from the packaged image as the native sidecar, working in the shared emptyDir
    pods = cluster.kubectl_json("get", "pods", "-n", namespace, "-l", f"uavtest.io/test={name}")["items"]
    assert len(pods) == REPLICAS and all(p["status"]["phase"] == "Succeeded" for p in pods)
    for pod in pods:
        sitl = pod["spec"]["initContainers"][0]
        assert sitl["image"].endswith(PX4_IMAGE) and sitl["restartPolicy"] == "Always"
        env = {e["name"]: e.get("value") for e in sitl["env"]}
        assert env["PX4_SIM_SPEED_FACTOR"] == str(SPEED_FACTOR)
        px4_out = cluster.kubectl("logs", "-n", namespace, pod["metadata"]["name"], "-c", "sitl")
        # the test's home reached PX4, in the form its build takes (v1.15: degrees * 1e7; v1.16+: degrees)
        assert re.search(r"SIH_LOC_LAT0: curr: \S+ -> new: (473977420|47\.3977)", px4_out), px4_out[-3000:]
        runner_out = cluster.kubectl("logs", "-n", namespace, pod["metadata"]["name"], "-c", "runner")
        assert "downloading it from the vehicle" not in runner_out  # taken from the shared folder

    # artifacts: PX4's own ULog of every replica, starting at the test's home
    run = status["runId"]
    prefix = f"{namespace}/{name}/{run}/"
    keys = store_keys(minio, bucket, prefix)
    for i in range(REPLICAS):
        for artifact in ("flight.ulg", "trajectory.csv", "result.json"):
            assert f"{prefix}replica-{i}/{artifact}" in keys
        result = json.loads(minio.client().get_object(bucket, f"{prefix}replica-{i}/result.json").read())
        assert result["verdict"] == "pass" and 4.0 < result["metrics"]["max_altitude"] < 6.5, result
        data = minio.client().get_object(bucket, f"{prefix}replica-{i}/flight.ulg").read()
        ulog = ULog(io.BytesIO(data))
        assert ulog.msg_info_dict["sys_name"] == "PX4"
        assert ulog.msg_info_dict["ver_sw"]
        topics = {d.name for d in ulog.data_list}
        assert {"vehicle_status", "vehicle_global_position", "estimator_status"} <= topics
        position = ulog.get_dataset("vehicle_global_position").data
        assert math.isclose(position["lat"][0], HOME["lat"], abs_tol=1e-3)
        assert math.isclose(position["lon"][0], HOME["lon"], abs_tol=1e-3)
    assert f"{prefix}aggregate/summary.json" in keys

    # Events and metrics
    events = cluster.kubectl(
        "get", "events", "-n", namespace, "--field-selector", f"involvedObject.name={name}-g1"
    )
    assert "TestPassed" in events
    labels = {"test_namespace": namespace, "test": name}
    assert operator.metric("uavtest_test_runs_total", result="succeeded", **labels) == 1
