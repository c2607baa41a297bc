"""Each run's upload policy and the Secret that carries it into the test's namespace (pure builders).

The policies here are signed by the real minio client (no server: the region is given), and decoded
back to check the conditions MinIO and S3 enforce.
"""

from __future__ import annotations

import base64
import json
from datetime import UTC, datetime, timedelta
from typing import Any

import pytest
import yaml
from minio import Minio

from uavtest.controller import names
from uavtest.controller.jobs import (
    MAX_UPLOAD_POLICY_SECONDS,
    build_upload_secret,
    deadline_seconds,
    owned_by,
    pod_endpoint_url,
    upload_expires,
    upload_prefix,
    upload_secret_name,
    upload_window,
)
from uavtest.controller.reconcile import parse_test
from uavtest.controller.settings import OperatorSettings
from uavtest.errors import BadInput
from uavtest.spec.models import UavTest
from uavtest.store import S3Settings
from uavtest.store.post_policy import UploadPolicy
from uavtest.store.s3 import post_policy_for

from .controller_bodies import RUN, UID, uavtest_body

ACCESS, SECRET = "AKIAEXAMPLE", "s3cr3t-value-never-shown"
NOW = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)


def signed(test: UavTest, expires: datetime, max_bytes: int = 1 << 20) -> UploadPolicy:
    client = Minio(
        "minio.storage:9000", access_key=ACCESS, secret_key=SECRET, secure=False, region="us-east-1"
    )
    prefix = "team-x/" + upload_prefix(test, RUN)
    fields = client.presigned_post_policy(post_policy_for("uavtest", prefix, expires, max_bytes))
    return UploadPolicy(
        url="http://10.0.0.7:9000/uavtest",
        bucket="uavtest",
        key_prefix=prefix,
        expires=expires,
        max_bytes=max_bytes,
        fields=fields,
    )


def conditions(policy: UploadPolicy) -> tuple[str, list[Any]]:
    doc = json.loads(base64.b64decode(policy.fields["policy"]))
    return doc["expiration"], doc["conditions"]


def test_the_policy_allows_one_runs_prefix_one_bucket_bounded_sizes_until_it_expires() -> None:
    test = parse_test(uavtest_body())
    policy = signed(test, NOW + timedelta(hours=2), max_bytes=5000)
    expiration, conds = conditions(policy)
    assert expiration == "2026-11-23T14:00:00.000Z"
    assert ["eq", "$bucket", "uavtest"] in conds
    assert ["starts-with", "$key", f"team-x/team-a/hover/{RUN}/"] in conds
    assert ["content-length-range", 0, 5000] in conds
    assert ["starts-with", "$Content-Type", ""] in conds
    # nothing else may be chosen by the holder: every other condition pins a signing field
    free = [c for c in conds if c[0] == "starts-with"]
    assert sorted(c[1] for c in free) == ["$Content-Type", "$key"]
    assert policy.allows(f"team-x/team-a/hover/{RUN}/replica-0/flight.ulg")
    assert not policy.allows(f"team-x/team-a/hover/{RUN}")  # the run's own folder, not a sibling
    assert not policy.allows("team-x/team-a/hover/other/replica-0/flight.ulg")
    assert policy.where() == f"s3://uavtest/team-x/team-a/hover/{RUN}/"


def test_a_policy_prefix_must_be_a_folder_and_its_expiry_absolute() -> None:
    with pytest.raises(BadInput):
        post_policy_for("uavtest", "team-a/hover/run", NOW, 10)
    with pytest.raises(BadInput):
        post_policy_for("uavtest", "team-a/hover/run/", NOW.replace(tzinfo=None), 10)


def test_the_policy_outlives_the_jobs_deadline_by_the_margin() -> None:
    spec = parse_test(uavtest_body(replicas=10, parallelism=4, timeout=100)).spec
    settings = OperatorSettings(upload_margin_seconds=600)
    window = upload_window(spec, settings, NOW)
    assert deadline_seconds(spec, settings) == 1200
    assert window.expires == NOW + timedelta(seconds=1200 + 600)
    assert not window.clamped


def test_a_deadline_beyond_s3s_seven_days_is_clamped_and_says_so() -> None:
    # 1000 replicas one at a time, 3 attempts each, 600 s: a 20-day worst case
    spec = parse_test(uavtest_body(replicas=1000, parallelism=1, timeout=600)).spec
    window = upload_window(spec, OperatorSettings(), NOW)
    assert window.expires == NOW + timedelta(seconds=MAX_UPLOAD_POLICY_SECONDS)
    assert window.clamped and window.wanted > window.expires


def test_pods_reach_the_store_at_the_pod_endpoint() -> None:
    s3 = S3Settings(endpoint="minio.storage:9000", access_key=ACCESS, secret_key=SECRET)
    assert pod_endpoint_url(OperatorSettings(), s3) == "http://minio.storage:9000"
    assert pod_endpoint_url(OperatorSettings(pod_s3_endpoint="10.0.0.7:9000"), s3) == "http://10.0.0.7:9000"
    assert pod_endpoint_url(OperatorSettings(pod_s3_secure=True), s3) == "https://minio.storage:9000"
    assert pod_endpoint_url(OperatorSettings(), S3Settings(endpoint="https://s3.example")) == (
        "https://s3.example"
    )


def test_the_upload_secret_is_owned_by_the_test_and_says_only_when_and_where_outside_its_data() -> None:
    body = uavtest_body()
    test = parse_test(body)
    policy = signed(test, NOW + timedelta(hours=2))
    secret = build_upload_secret(test, RUN, policy, body)
    meta = secret["metadata"]
    assert meta["name"] == upload_secret_name("hover", RUN) == f"hover-{RUN}-upload"
    assert meta["namespace"] == "team-a"
    assert [(r["kind"], r["uid"], r["controller"]) for r in meta["ownerReferences"]] == [
        ("UavTestRun", UID, True)
    ]
    assert owned_by(meta, UID) and not owned_by(meta, "another-uid")
    assert meta["labels"][names.LABEL_RUN] == RUN
    assert upload_expires(meta) == NOW + timedelta(hours=2)
    assert meta["annotations"][names.UPLOAD_PREFIX_ANNOTATION] == f"s3://uavtest/team-x/team-a/hover/{RUN}/"
    # the signature is in the data only; the store's secret key is nowhere
    assert set(secret["stringData"]) == {"policy"}
    assert UploadPolicy.model_validate_json(secret["stringData"]["policy"]) == policy
    signature = policy.fields["x-amz-signature"]
    outside_data = yaml.safe_dump({k: v for k, v in secret.items() if k != "stringData"})
    assert signature not in outside_data and SECRET not in yaml.safe_dump(secret)
    assert signature not in repr(policy) and signature not in str(policy)


def test_an_upload_secret_without_a_readable_expiry_says_none() -> None:
    assert upload_expires({}) is None
    assert upload_expires({"annotations": {names.UPLOAD_EXPIRES_ANNOTATION: "soon"}}) is None
    assert upload_expires({"annotations": {names.UPLOAD_EXPIRES_ANNOTATION: "2026-11-23T12:00:00"}}) is None
