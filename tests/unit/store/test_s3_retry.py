"""S3Store against an endpoint where nothing listens: bounded retries, each logged, no secrets."""

from __future__ import annotations

import logging
import socket

import pytest
from minio.error import S3Error

from uavtest.store import S3Settings, StoreUnavailable
from uavtest.store.s3 import S3Store, is_transient


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_put_to_an_unreachable_server_retries_then_gives_up_naming_the_key(
    caplog: pytest.LogCaptureFixture,
) -> None:
    settings = S3Settings(
        endpoint=f"127.0.0.1:{_closed_port()}",
        access_key="ACCESS-not-in-logs",
        secret_key="SECRET-not-in-logs",
        retry_total=0.6,
        retry_initial=0.05,
        retry_max=0.1,
        timeout=1,
    )
    store = S3Store("bucket", "pre", settings=settings)
    with caplog.at_level(logging.WARNING, logger="uavtest.store.s3"), pytest.raises(StoreUnavailable) as e:
        store.put("ns/t/r/replica-0/result.json", b"{}")
    assert "s3://bucket/pre/ns/t/r/replica-0/result.json" in str(e.value)
    retries = [r.getMessage() for r in caplog.records if "retry" in r.getMessage()]
    assert len(retries) >= 2
    assert all("ns/t/r/replica-0/result.json" in m for m in retries)
    everything = " ".join(r.getMessage() for r in caplog.records) + str(e.value)
    assert "not-in-logs" not in everything


def test_transient_and_permanent_s3_errors_are_told_apart() -> None:
    def s3_error(code: str) -> S3Error:
        return S3Error(None, code, "msg", "/b/k", "req", "host")  # type: ignore[arg-type]

    assert is_transient(s3_error("SlowDown"))
    assert is_transient(s3_error("XMinioServerNotInitialized"))
    assert is_transient(s3_error("XMinioIAMNotInitialized"))  # a (re)starting MinIO, seen in CI
    assert not is_transient(s3_error("AccessDenied"))
    assert not is_transient(s3_error("NoSuchKey"))
    assert is_transient(ConnectionRefusedError())
