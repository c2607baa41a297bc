"""The write-only store of replica pods: opened from UAVTEST_S3_UPLOAD_POLICY, refuses reads, never
shows the signature. Its uploads against a real MinIO are in tests/integration/test_store_post_policy.py.
"""

from __future__ import annotations

import logging
import socket
from datetime import UTC, datetime, timedelta

import pytest

from uavtest.errors import BadInput
from uavtest.store import S3Settings, StoreUnavailable, open_store
from uavtest.store.post_policy import PostPolicyStore, UploadPolicy, WriteOnlyStore

SIGNATURE = "f00dfeed" * 8
EXPIRES = datetime.now(UTC) + timedelta(hours=1)


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def policy(url: str = "http://minio.example:9000/runs", prefix: str = "arch/ci/hover/r1/") -> UploadPolicy:
    return UploadPolicy(
        url=url,
        bucket="runs",
        key_prefix=prefix,
        expires=EXPIRES,
        max_bytes=1000,
        fields={"policy": "eyJleHBpcmF0aW9uIjoi", "x-amz-signature": SIGNATURE},
    )


def test_the_upload_policy_in_the_environment_opens_a_write_only_store(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("UAVTEST_S3_UPLOAD_POLICY", policy().model_dump_json())
    store = open_store("s3://runs/arch")
    assert isinstance(store, PostPolicyStore)
    assert (
        store.url("ci/hover/r1/replica-0/result.json") == "s3://runs/arch/ci/hover/r1/replica-0/result.json"
    )
    shown = repr(store) + repr(store.policy) + repr(store.settings) + str(store.settings.model_dump())
    assert SIGNATURE not in shown
    for read in (lambda: store.get("k"), lambda: store.exists("k"), lambda: store.list("")):
        with pytest.raises(WriteOnlyStore, match="can only upload"):
            read()


def test_without_a_policy_an_s3_url_still_opens_the_keyed_store(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("UAVTEST_S3_UPLOAD_POLICY", raising=False)
    assert not isinstance(open_store("s3://runs"), PostPolicyStore)


def test_a_store_url_naming_another_bucket_than_the_policy_is_bad_input(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("UAVTEST_S3_UPLOAD_POLICY", policy().model_dump_json())
    with pytest.raises(BadInput, match="bucket") as e:
        open_store("s3://elsewhere")
    assert "s3://runs" in str(e.value)


@pytest.mark.parametrize("text", ["not json", '{"url": "http://x/runs"}', policy().model_dump_json()[:-20]])
def test_a_broken_policy_is_bad_input_naming_the_variable_never_its_value(
    monkeypatch: pytest.MonkeyPatch, text: str
) -> None:
    monkeypatch.setenv("UAVTEST_S3_UPLOAD_POLICY", text)
    with pytest.raises(BadInput) as e:
        open_store("s3://runs")
    assert "UAVTEST_S3_UPLOAD_POLICY" in str(e.value)
    assert SIGNATURE not in str(e.value) and "eyJleHBp" not in str(e.value)


def test_keys_outside_the_policy_or_over_its_size_are_refused_before_sending() -> None:
    store = PostPolicyStore(policy(f"http://127.0.0.1:{_closed_port()}/runs"), "runs", "arch")
    with pytest.raises(StoreUnavailable, match="outside the upload policy's prefix"):
        store.put("ci/hover/r2/replica-0/result.json", b"{}")
    with pytest.raises(StoreUnavailable, match="over the upload policy's 1000"):
        store.put("ci/hover/r1/replica-0/flight.ulg", b"x" * 1001)


def test_an_unreachable_server_is_retried_then_given_up_naming_the_key_not_the_signature(
    caplog: pytest.LogCaptureFixture,
) -> None:
    settings = S3Settings(retry_total=0.6, retry_initial=0.05, retry_max=0.1, timeout=1)
    store = PostPolicyStore(
        policy(f"http://127.0.0.1:{_closed_port()}/runs"), "runs", "arch", settings=settings
    )
    key = "ci/hover/r1/replica-0/result.json"
    with (
        caplog.at_level(logging.WARNING, logger="uavtest.store.post_policy"),
        pytest.raises(StoreUnavailable) as e,
    ):
        store.put(key, b"{}")
    assert f"s3://runs/arch/{key}" in str(e.value) and "gave up after 0.6 s" in str(e.value)
    retries = [r.getMessage() for r in caplog.records if "retry" in r.getMessage()]
    assert len(retries) >= 2 and all(key in m for m in retries)
    assert SIGNATURE not in caplog.text + str(e.value)


def test_form_values_that_would_break_the_multipart_body_are_refused_before_sending() -> None:
    store = PostPolicyStore(policy(f"http://127.0.0.1:{_closed_port()}/runs"), "runs", "arch")
    with pytest.raises(BadInput):
        store.put("ci/hover/r1/replica-0/result.json", b"{}", 'text/plain\r\nx-amz-meta-a: "b"')
