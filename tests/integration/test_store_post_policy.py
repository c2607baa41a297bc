"""Uploads through an S3 POST policy against a real MinIO: what the policy allows arrives, what it does
not allow is refused by MinIO itself, and an outage is retried until the server is back."""

from __future__ import annotations

import logging
import os
import sys
import threading
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling store tests' helpers
from test_store_s3 import MinioServer, _live, _RetrySeen, minio_binary_or_skip, restart_same, settings_for

from harness.minio import start_minio
from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.runner.artifacts import ReplicaPlace, store_artifacts
from uavtest.store import StoreUnavailable
from uavtest.store.post_policy import PostPolicyStore, PostRefused, UploadPolicy, _pool, post_object
from uavtest.store.s3 import S3Store

pytestmark = pytest.mark.integration

RUN = "ci/mission2/r7/"


@pytest.fixture
def minio(tmp_path: Path) -> Iterator[MinioServer]:
    minio_binary_or_skip()
    server = start_minio(tmp_path / "minio")
    try:
        yield server
    finally:
        server.stop()


def sign(
    minio: MinioServer, *, expires_in: float = 3600, max_bytes: int = 1 << 20, bucket: str = "runs"
) -> UploadPolicy:
    """What the operator does: sign a policy for RUN under the store prefix ``team-a``, keys held back."""
    root = S3Store(bucket, "team-a", settings=settings_for(minio))
    return root.upload_policy(
        RUN, expires=datetime.now(UTC) + timedelta(seconds=expires_in), max_bytes=max_bytes
    )


def objects(minio: MinioServer, bucket: str = "runs") -> list[str]:
    return sorted(o.object_name for o in minio.client().list_objects(bucket, recursive=True))


def test_a_replicas_artifacts_arrive_through_the_policy_and_the_bucket_is_made_by_the_signer(
    minio: MinioServer,
) -> None:
    policy = sign(minio)
    assert minio.client().bucket_exists("runs")  # an upload policy cannot create a bucket: the signer did
    store = PostPolicyStore(policy, "runs", "team-a")
    place = ReplicaPlace("ci", "mission2", "r7", 3)
    result = ReplicaResult(index=3, seed=10, verdict=Verdict.PASS)
    stored, ok = store_artifacts(
        store, place, result, log_bytes=b"ULog\x01" + os.urandom(4096), trajectory=None
    )
    assert ok and stored.verdict is Verdict.PASS
    assert objects(minio) == [f"team-a/{RUN}replica-3/flight.ulg", f"team-a/{RUN}replica-3/result.json"]
    got = minio.client().get_object("runs", f"team-a/{RUN}replica-3/result.json").read()
    assert ReplicaResult.model_validate_json(got) == stored
    stat = minio.client().stat_object("runs", f"team-a/{RUN}replica-3/result.json")
    assert stat.content_type == "application/json"
    # and the operator reads them back with its keys
    assert S3Store("runs", "team-a", settings=settings_for(minio)).list(RUN) == [
        f"{RUN}replica-3/flight.ulg",
        f"{RUN}replica-3/result.json",
    ]


@pytest.mark.parametrize(
    "name",
    [
        "team-a/ci/mission2/r8/replica-0/result.json",  # another run of the same test
        "team-a/ci/other/r7/replica-0/result.json",  # another test
        "team-b/ci/mission2/r7/replica-0/result.json",  # another store prefix
        "team-a/ci/mission2/r7",  # the run's folder name without its slash: a sibling, not inside
    ],
)
def test_minio_refuses_a_key_outside_the_runs_prefix(minio: MinioServer, name: str) -> None:
    policy = sign(minio)
    with pytest.raises(PostRefused) as e:
        post_object(_pool(policy.url, settings_for(minio)), policy, name, b"{}", "application/json")
    assert (e.value.status, e.value.code) == (403, "AccessDenied")
    assert objects(minio) == []


def test_minio_refuses_an_object_over_the_size_bound(minio: MinioServer) -> None:
    policy = sign(minio, max_bytes=1000)
    http = _pool(policy.url, settings_for(minio))
    post_object(http, policy, f"team-a/{RUN}replica-0/result.json", b"x" * 1000)
    with pytest.raises(PostRefused) as e:
        post_object(http, policy, f"team-a/{RUN}replica-0/flight.ulg", b"x" * 1001)
    assert e.value.status == 400 and e.value.code == "EntityTooLarge"
    assert objects(minio) == [f"team-a/{RUN}replica-0/result.json"]


def test_an_expired_policy_is_refused_and_the_error_says_it_expired(
    minio: MinioServer, caplog: pytest.LogCaptureFixture
) -> None:
    policy = sign(minio, expires_in=-60)  # signed a minute too late, as a run that outlived it would be
    store = PostPolicyStore(policy, "runs", "team-a", settings=settings_for(minio, retry_total=30))
    with (
        caplog.at_level(logging.INFO, logger="uavtest.store.post_policy"),
        pytest.raises(StoreUnavailable) as e,
    ):
        store.put(f"{RUN}replica-0/result.json", b"{}")
    assert "AccessDenied" in str(e.value) and "expired" in str(e.value)
    assert not [r for r in caplog.records if "retry" in r.getMessage()]  # a refusal is not retried
    assert objects(minio) == []


def test_an_upload_during_an_outage_retries_and_arrives_when_minio_is_back(minio: MinioServer) -> None:
    policy = sign(minio)
    settings = settings_for(minio, retry_total=90, retry_initial=0.2, retry_max=1.0, timeout=2)
    store = PostPolicyStore(policy, "runs", "team-a", settings=settings)
    minio.stop()  # our own root: the data dir stays
    assert not _live(minio.endpoint)
    seen = _RetrySeen(wanted=4)
    logger = logging.getLogger("uavtest.store.post_policy")
    logger.addHandler(seen)
    logger.setLevel(logging.INFO)
    outcome: dict[str, object] = {}
    payload = os.urandom(256 * 1024)
    key = f"{RUN}replica-0/flight.ulg"

    def upload() -> None:
        try:
            store.put(key, payload)
            outcome["ok"] = True
        except Exception as e:  # reported by the assertion below
            outcome["error"] = e

    thread = threading.Thread(target=upload)
    thread.start()
    restarted = None
    try:
        assert seen.event.wait(60), "the upload did not keep retrying"
        assert thread.is_alive()
        restarted = restart_same(minio)
        thread.join(90)
        assert not thread.is_alive()
        assert outcome == {"ok": True}, outcome
        assert minio.client().get_object("runs", f"team-a/{key}").read() == payload
    finally:
        logger.removeHandler(seen)
        thread.join(1)
        if restarted is not None:
            restarted.terminate()
            restarted.wait(10)
    retries = [m for m in seen.messages if "retry" in m]
    assert len(retries) >= 4 and all(key in m for m in retries)
    secret_bits = (policy.fields["x-amz-signature"], policy.fields["policy"], minio.secret_key)
    assert not any(bit in m for bit in secret_bits for m in seen.messages)
