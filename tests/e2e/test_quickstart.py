"""The README's Kubernetes quick start, run verbatim on the suite's cluster.

The command block is read from README.md ("## In Kubernetes: the operator", its first ```bash
block), so the two cannot drift. Nothing is published: the images the suite builds are tagged with
the names the chart defaults to (operator, runner, MinIO), which is what a user's registry or
`kind load` would provide. The block runs with bash -e, `kubectl` and `helm` from the cache on PATH
and KUBECONFIG set to the suite's cluster, from the repository root.
"""

from __future__ import annotations

import os
import re
import subprocess
import time
from pathlib import Path

import pytest

from e2e.chart_support import Release, chart_defaults, store_objects
from harness.cluster import BIN_DIR, REPO_ROOT, Cluster

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

README = REPO_ROOT / "README.md"
SECTION = "## In Kubernetes: the operator"
# what the block installs and creates (asserted below, removed afterwards)
RELEASE, RELEASE_NS, TEST, TEST_NS = "uavtest", "uavtest-system", "obstacle-pass", "default"
BLOCK_TIMEOUT = 20 * 60
# a replica pod that cannot start for want of its S3 credentials never will: fail early, saying so
CONFIG_ERROR_GRACE = 60.0


def quick_start_block(readme: str) -> str:
    """The first ```bash block of the README's Kubernetes section."""
    section = readme.split(SECTION, 1)[1]
    match = re.search(r"```bash\n(.*?)```", section, re.DOTALL)
    assert match, f"no ```bash block under {SECTION!r} in README.md"
    return match.group(1)


@pytest.fixture
def chart_default_images(cluster: Cluster, operator_image: str, runner_image: str, minio_image: str) -> None:
    values = chart_defaults()
    cluster.tag_image(operator_image, values["operator"]["image"])
    cluster.tag_image(runner_image, values["replicas"]["image"])
    cluster.tag_image(minio_image, values["minio"]["image"])


def _config_errors(cluster: Cluster) -> list[str]:
    """Messages of replica containers in TEST_NS that cannot be created (e.g. a Secret not found)."""
    pods = cluster.kubectl_json("get", "pods", "-n", TEST_NS, "-l", f"uavtest.io/test={TEST}")["items"]
    return [
        f"{p['metadata']['name']}: {s['state']['waiting'].get('message', '')}"
        for p in pods
        for s in p.get("status", {}).get("containerStatuses", [])
        + p.get("status", {}).get("initContainerStatuses", [])
        if s.get("state", {}).get("waiting", {}).get("reason") == "CreateContainerConfigError"
    ]


def _run_block(cluster: Cluster, block: str, helm_home: str) -> subprocess.CompletedProcess[str]:
    env = {
        **os.environ,
        "PATH": f"{BIN_DIR}:{os.environ['PATH']}",
        "KUBECONFIG": str(cluster.kubeconfig),
        **{f"HELM_{k}_HOME": f"{helm_home}/{k}" for k in ("CACHE", "CONFIG", "DATA")},
    }
    proc = subprocess.Popen(
        ["bash", "-euo", "pipefail", "-c", block],
        cwd=REPO_ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    end = time.monotonic() + BLOCK_TIMEOUT
    stuck_since: float | None = None
    try:
        while proc.poll() is None:
            time.sleep(2)
            errors = _config_errors(cluster)
            stuck_since = (stuck_since or time.monotonic()) if errors else None
            if stuck_since is not None and time.monotonic() - stuck_since > CONFIG_ERROR_GRACE:
                pytest.fail(f"replica pods in namespace {TEST_NS} cannot start: {errors}")
            if time.monotonic() > end:
                pytest.fail(f"the quick start did not finish in {BLOCK_TIMEOUT}s")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, 9)
        out = proc.communicate()[0]
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, "")


def test_readme_quick_start_runs_verbatim(
    cluster: Cluster, chart_default_images: None, tmp_path: Path
) -> None:
    block = quick_start_block(README.read_text())
    assert "helm install" in block and "kubectl apply" in block and "kubectl wait" in block, block
    # the names the block uses are free on this cluster (each test creates its own objects)
    # (the CRD may not exist yet: then neither does the UavTest)
    assert not cluster.kubectl(
        "get", "uavtest", TEST, "-n", TEST_NS, "--ignore-not-found", check=False
    ).strip()
    release = Release(cluster, RELEASE, RELEASE_NS)
    try:
        done = _run_block(cluster, block, str(tmp_path))
        assert done.returncode == 0, f"{done.stdout}\n{release.diagnostics()}"
        assert "condition met" in done.stdout
        test_status = cluster.kubectl_json("get", "uavtest", TEST, "-n", TEST_NS)["status"]
        assert test_status["lastRun"]["phase"] == "Succeeded", test_status
        status = cluster.kubectl_json("get", "uavtestrun", test_status["lastRun"]["name"], "-n", TEST_NS)[
            "status"
        ]
        assert status["phase"] == "Succeeded", status
        assert (status["replicas"], status["passed"], status["failed"]) == (3, 3, 0)
        # the operator runs as the chart's Deployment, and the artifacts are in the chart's MinIO
        release.wait_available(timeout=30)
        values = chart_defaults()["minio"]
        keys = store_objects(release.minio(values["rootUser"], values["rootPassword"]), values["bucket"])
        artifacts = {k: v for k, v in status["artifacts"].items() if k != "store" and v}
        assert artifacts and all(u.split("/", 3)[3] in keys for u in artifacts.values()), (artifacts, keys)
        assert sum(k.endswith("/result.json") and status["runId"] in k for k in keys) == 3, keys
    finally:
        # the test first (the operator removes its finalizer), then the release and its namespace
        cluster.kubectl(
            "delete", "uavtest", TEST, "-n", TEST_NS, "--ignore-not-found", "--timeout=90s", check=False
        )
        cluster.helm("uninstall", RELEASE, "-n", RELEASE_NS, "--wait", "--timeout=180s", "--ignore-not-found")
        cluster.delete_namespace(RELEASE_NS)
