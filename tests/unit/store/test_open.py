"""open_store: one URL names a local directory or an S3 bucket."""

from __future__ import annotations

from pathlib import Path

import pytest

from uavtest.errors import BadInput
from uavtest.store import LocalStore, S3Settings, open_store
from uavtest.store.s3 import S3Store


def test_plain_path_and_file_url_open_a_local_store(tmp_path: Path) -> None:
    a = open_store(str(tmp_path))
    b = open_store(tmp_path.as_uri())
    assert isinstance(a, LocalStore) and isinstance(b, LocalStore)
    assert a.root == b.root == tmp_path.resolve()


def test_s3_url_opens_bucket_and_prefix_with_settings_from_the_environment(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("UAVTEST_S3_ENDPOINT", "http://minio.example:9000")
    monkeypatch.setenv("UAVTEST_S3_ACCESS_KEY", "AKIA-visible-nowhere")
    monkeypatch.setenv("UAVTEST_S3_SECRET_KEY", "s3cr3t-visible-nowhere")
    store = open_store("s3://artifacts/team-a/")
    assert isinstance(store, S3Store)
    assert store.url("ns/t/r/replica-0/result.json") == "s3://artifacts/team-a/ns/t/r/replica-0/result.json"
    assert store.settings.host_and_secure() == ("minio.example:9000", False)
    shown = repr(store) + repr(store.settings) + str(store.settings.model_dump())
    assert "visible-nowhere" not in shown


@pytest.mark.parametrize("url", ["ftp://host/dir", "s3://", "file://otherhost/dir", ""])
def test_unusable_urls_are_bad_input(url: str) -> None:
    with pytest.raises(BadInput):
        open_store(url)


def test_https_endpoint_turns_on_tls_and_credentials_in_the_endpoint_are_refused_unechoed() -> None:
    assert S3Settings(endpoint="https://s3.example").host_and_secure() == ("s3.example", True)
    assert S3Settings(endpoint="minio:9000", secure=True).host_and_secure() == ("minio:9000", True)
    with pytest.raises(BadInput) as e:
        S3Settings(endpoint="http://user:hunter2@minio:9000").host_and_secure()
    assert "hunter2" not in str(e.value)
