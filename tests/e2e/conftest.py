"""Fixtures of the e2e tier: a real one-node cluster the suite starts by itself, the runner image, MinIO.

Session-scoped (started on first use, stopped at the end of the session, also on SIGTERM):
- `cluster`       -> harness.cluster.Cluster: etcd + apiserver + kcm + scheduler + containerd + a real kubelet
                     (node "localhost"); `cluster.kubeconfig`, `cluster.kubectl(*args)`, `cluster.apply(...)`,
                     `cluster.env()`. KUBECONFIG is set to it for the session, so in-process clients
                     (kubernetes, kopf) find it too. Needs root.
- `kwok_cluster`  -> a second Cluster with a kwok fake node ("kwok-node-0"): pods never run, they just turn
                     Succeeded. For scale / operator-logic tests. No root needed.
- `runner_image`  -> "uavtest-runner:dev", built from the current working tree and imported into `cluster`'s
                     containerd; pods use it with imagePullPolicy: Never.
- `operator_image`-> "uavtest-operator:dev": the same layers with the root Dockerfile's config (entrypoint
                     `uavtest`, command `operator ...`, uid 65532), written by the same build; imported.
- `minio_image`   -> "uavtest.local/minio:dev": the MinIO build.sh makes, on the image's Debian base; imported
                     (for the chart's throwaway MinIO, `minio.enabled=true`).
- `minio`         -> harness.minio.MinioServer: `.endpoint` (127.0.0.1:port), `.access_key`, `.secret_key`,
                     `.client()`.
Module-scoped:
- `namespace`     -> a fresh namespace in `cluster` for the test module, deleted afterwards.
- `kwok_namespace`-> the same in `kwok_cluster`.
"""

from __future__ import annotations

import os
import re
import secrets
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/ -> `import harness`

from harness.cluster import (
    MINIO_IMAGE,
    OPERATOR_IMAGE,
    REPO_ROOT,
    RUNNER_IMAGE,
    Cluster,
    ClusterError,
    build_runner_image,
    image_archives,
    start_cluster,
    terminate_on_sigterm,
)
from harness.minio import MinioServer, start_minio

if TYPE_CHECKING:
    from e2e.operator_support import Operator


def _ns_name(request: pytest.FixtureRequest) -> str:
    base = re.sub(r"[^a-z0-9-]+", "-", request.module.__name__.rsplit(".", 1)[-1].lower()).strip("-")
    return f"{base[:40]}-{secrets.token_hex(3)}"


@pytest.fixture(scope="session")
def cluster() -> Iterator[Cluster]:
    """A real one-node cluster on 127.0.0.1 (built and started by the suite; torn down at the end)."""
    if os.geteuid() != 0:
        pytest.skip("the e2e cluster's real node (kubelet + containerd) needs root")
    with terminate_on_sigterm():
        c = start_cluster(real_node=True)
        previous = os.environ.get("KUBECONFIG")
        os.environ["KUBECONFIG"] = str(c.kubeconfig)
        try:
            yield c
        finally:
            if previous is None:
                os.environ.pop("KUBECONFIG", None)
            else:
                os.environ["KUBECONFIG"] = previous
            c.stop()


@pytest.fixture(scope="session")
def kwok_cluster() -> Iterator[Cluster]:
    """Control plane + kwok fake node "kwok-node-0" (every pod 'succeeds' without running)."""
    with terminate_on_sigterm():
        c = start_cluster(real_node=False, kwok=True)
        try:
            yield c
        finally:
            c.stop()


@pytest.fixture(scope="session")
def runner_image(cluster: Cluster) -> str:
    """The runner image built from the working tree, imported into the node; returns its name."""
    cluster.import_image(build_runner_image(REPO_ROOT))
    return RUNNER_IMAGE


@pytest.fixture(scope="session")
def operator_image(cluster: Cluster, runner_image: str) -> str:
    """The operator image the runner image's build wrote beside it, imported into the node."""
    cluster.import_image(image_archives()[OPERATOR_IMAGE])
    return OPERATOR_IMAGE


@pytest.fixture(scope="session")
def minio_image(cluster: Cluster, runner_image: str) -> str:
    """A MinIO image (build.sh's MinIO on the runner image's Debian base), imported into the node."""
    archives = image_archives()
    if MINIO_IMAGE not in archives:
        raise ClusterError("no MinIO image archive: tests/cluster/build.sh minio did not run")
    cluster.import_image(archives[MINIO_IMAGE])
    return MINIO_IMAGE


@pytest.fixture(scope="module")
def namespace(request: pytest.FixtureRequest, cluster: Cluster) -> Iterator[str]:
    """A namespace of its own for each test module, in `cluster`."""
    name = cluster.create_namespace(_ns_name(request))
    yield name
    cluster.delete_namespace(name)


@pytest.fixture(scope="module")
def kwok_namespace(request: pytest.FixtureRequest, kwok_cluster: Cluster) -> Iterator[str]:
    name = kwok_cluster.create_namespace(_ns_name(request))
    yield name
    kwok_cluster.delete_namespace(name)


@pytest.fixture(scope="session")
def minio() -> Iterator[MinioServer]:
    """A MinIO server on a free loopback port with random credentials."""
    with terminate_on_sigterm():
        server = start_minio()
        try:
            yield server
        finally:
            server.stop()


@pytest.fixture(scope="module")
def bucket(request: pytest.FixtureRequest, minio: MinioServer) -> str:
    """A new, empty bucket for the test module (``uavtest-<module>-<hex>``)."""
    from e2e.operator_support import fresh_bucket

    base = request.module.__name__.rsplit(".", 1)[-1].removeprefix("test_").replace("_", "-")
    return fresh_bucket(minio, f"uavtest-{base[:40]}")


@pytest.fixture(scope="module")
def operator(
    cluster: Cluster,
    namespace: str,
    minio: MinioServer,
    runner_image: str,
    bucket: str,
    tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[Operator]:
    """``uavtest operator`` (a host process) under the chart's RBAC, watching the module's namespace
    and storing to its bucket; stopped after the module, its UavTests deleted first."""
    from e2e.operator_support import running_operator

    with running_operator(
        cluster, namespace, minio, runner_image, bucket, tmp_path_factory.mktemp("operator")
    ) as op:
        yield op
