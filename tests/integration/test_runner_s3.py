"""A replica stores into real MinIO, and nothing is lost when MinIO is down while it uploads."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling runner and store tests' helpers
from test_runner_sitl import SHORT_MISSION, make_replica, simulator
from test_store_s3 import MinioServer, minio_binary_or_skip, restart_same, start_minio

from uavtest.analysis.models import ReplicaResult, Verdict

pytestmark = pytest.mark.integration

RUN_TIMEOUT = 240


@pytest.fixture
def minio(tmp_path: Path) -> Iterator[MinioServer]:
    minio_binary_or_skip()
    server = start_minio(tmp_path / "minio")
    try:
        yield server
    finally:
        server.stop()


def runner_env(minio: MinioServer) -> dict[str, str]:
    return {
        **os.environ,
        "UAVTEST_S3_ENDPOINT": f"http://{minio.endpoint}",
        "UAVTEST_S3_ACCESS_KEY": minio.access_key,
        "UAVTEST_S3_SECRET_KEY": minio.secret_key,
        "UAVTEST_S3_RETRY_INITIAL": "0.2",
        "UAVTEST_S3_RETRY_MAX": "1",
    }


def test_a_replica_whose_store_is_down_retries_and_loses_nothing(minio: MinioServer, tmp_path: Path) -> None:
    replica = make_replica(tmp_path, SHORT_MISSION)
    cmd = replica.runner_cmd()
    cmd[cmd.index("--store") + 1] = "s3://uavtest/artifacts"
    minio.stop()  # down before the replica starts uploading
    restarted: subprocess.Popen[bytes] | None = None
    try:
        with simulator(replica, tmp_path):
            runner = subprocess.Popen(
                cmd, env=runner_env(minio), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
            )
            try:
                assert runner.stderr is not None
                lines: list[str] = []
                for line in runner.stderr:  # MinIO comes back once the runner has retried 3 times
                    lines.append(line)
                    if sum("store put" in x and "retry" in x for x in lines) == 3:
                        restarted = restart_same(minio)
                        break
                out, rest = runner.communicate(timeout=RUN_TIMEOUT)
            finally:
                if runner.poll() is None:
                    runner.kill()
        stderr = "".join(lines) + rest
        assert restarted is not None, stderr[-3000:]
        result = ReplicaResult.model_validate_json(out.strip().splitlines()[-1])
        assert result.verdict is Verdict.PASS, f"{result.reason}\n{stderr[-3000:]}"
        assert runner.returncode == 0
        assert minio.secret_key not in stderr and minio.access_key not in stderr
        client = minio.client()
        names = sorted(o.object_name for o in client.list_objects("uavtest", recursive=True))
        prefix = "artifacts/local/short-mission/it/replica-0/"
        assert names == [prefix + "flight.ulg", prefix + "result.json", prefix + "trajectory.csv"]
        assert (
            ReplicaResult.model_validate_json(client.get_object("uavtest", prefix + "result.json").read())
            == result
        )
        assert client.get_object("uavtest", prefix + "flight.ulg").read(7) == b"ULog\x01\x12\x35"
    finally:
        if restarted is not None:
            restarted.terminate()
            restarted.wait(10)


def test_a_replica_with_only_an_upload_policy_stores_its_artifacts(
    minio: MinioServer, tmp_path: Path
) -> None:
    """A replica as a pod runs it: no S3 keys, only the upload policy the operator signed for its run."""
    from datetime import UTC, datetime, timedelta

    from test_store_s3 import settings_for

    from uavtest.store.s3 import S3Store

    operator_side = S3Store("uavtest", "artifacts", settings=settings_for(minio))
    policy = operator_side.upload_policy(
        "local/short-mission/it/", expires=datetime.now(UTC) + timedelta(hours=1), max_bytes=64 << 20
    )
    replica = make_replica(tmp_path, SHORT_MISSION)
    cmd = replica.runner_cmd()
    cmd[cmd.index("--store") + 1] = "s3://uavtest/artifacts"
    env = {k: v for k, v in os.environ.items() if not k.startswith("UAVTEST_S3_")}
    env["UAVTEST_S3_UPLOAD_POLICY"] = policy.model_dump_json()
    with simulator(replica, tmp_path):
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=RUN_TIMEOUT)
    result = ReplicaResult.model_validate_json(done.stdout.strip().splitlines()[-1])
    assert result.verdict is Verdict.PASS, f"{result.reason}\n{done.stderr[-3000:]}"
    assert done.returncode == 0
    assert "PostPolicyStore('s3://uavtest/artifacts/local/short-mission/it/'" in done.stderr
    assert policy.fields["x-amz-signature"] not in done.stderr + done.stdout
    prefix = "artifacts/local/short-mission/it/replica-0/"
    names = sorted(o.object_name for o in minio.client().list_objects("uavtest", recursive=True))
    assert names == [prefix + "flight.ulg", prefix + "result.json", prefix + "trajectory.csv"]
    assert minio.client().get_object("uavtest", prefix + "flight.ulg").read(7) == b"ULog\x01\x12\x35"
