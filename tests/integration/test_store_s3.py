"""S3Store against a real MinIO server (tests/harness/minio.py), including an outage mid-upload."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/ -> `import harness`
from harness.minio import MinioError, MinioServer, minio_binary, start_minio
from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.runner.artifacts import ReplicaPlace, store_artifacts
from uavtest.store import ArtifactNotFound, S3Settings, StoreUnavailable, open_store
from uavtest.store.s3 import S3Store

pytestmark = pytest.mark.integration

READY_S = 60.0


def minio_binary_or_skip() -> Path:
    """The built MinIO binary; skips the test when it is not built."""
    try:
        return minio_binary(build=False)
    except MinioError as e:
        pytest.skip(f"MinIO binary not built: {e}")


@pytest.fixture
def minio(tmp_path: Path) -> Iterator[MinioServer]:
    minio_binary_or_skip()
    server = start_minio(tmp_path / "minio")  # a root of our own: its data survives a stop
    try:
        yield server
    finally:
        server.stop()


def settings_for(server: MinioServer, **kw: object) -> S3Settings:
    return S3Settings(
        endpoint=server.endpoint,
        access_key=server.access_key,
        secret_key=server.secret_key,
        **kw,  # type: ignore[arg-type]
    )


def _live(endpoint: str) -> bool:
    try:
        with urllib.request.urlopen(f"http://{endpoint}/minio/health/live", timeout=2) as r:
            return bool(r.status == 200)
    except (urllib.error.URLError, OSError):
        return False


def restart_same(server: MinioServer) -> subprocess.Popen[bytes]:
    """Start MinIO again on the same address, data dir and credentials; return once it is live."""
    env = {
        **os.environ,
        "MINIO_ROOT_USER": server.access_key,
        "MINIO_ROOT_PASSWORD": server.secret_key,
        "MINIO_BROWSER": "off",
        "MINIO_UPDATE": "off",
        "HOME": str(server.root),
    }
    cmd = [
        str(minio_binary_or_skip()),
        "server",
        str(server.root / "data"),
        "--address",
        server.endpoint,
        "--quiet",
    ]
    cmd += ["--certs-dir", str(server.root / "certs")]
    with open(server.root / "minio-restart.log", "wb") as log:
        proc = subprocess.Popen(cmd, env=env, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + READY_S
    while not _live(server.endpoint):
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            pytest.fail("MinIO did not come back: " + (server.root / "minio-restart.log").read_text()[-2000:])
        time.sleep(0.1)
    return proc


class _RetrySeen(logging.Handler):
    """Sets ``event`` once ``wanted`` retries have been logged."""

    def __init__(self, wanted: int) -> None:
        super().__init__()
        self.wanted = wanted
        self.event = threading.Event()
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())
        if sum("retry" in m for m in self.messages) >= self.wanted:
            self.event.set()


def test_artifacts_round_trip_and_the_bucket_is_created(minio: MinioServer) -> None:
    store = S3Store("uavtest-artifacts", "team-a", settings=settings_for(minio))
    key = "ci/hover/run-1/replica-0/result.json"
    store.put(key, b'{"verdict": "pass"}', "application/json")
    store.put("ci/hover/run-1/replica-1/result.json", b"{}")
    assert minio.client().bucket_exists("uavtest-artifacts")
    assert store.get(key) == b'{"verdict": "pass"}'
    assert store.exists(key) and not store.exists("ci/hover/run-1/replica-9/result.json")
    assert store.list("ci/hover/run-1/") == [key, "ci/hover/run-1/replica-1/result.json"]
    assert store.url(key) == f"s3://uavtest-artifacts/team-a/{key}"
    assert minio.client().stat_object("uavtest-artifacts", f"team-a/{key}").content_type == "application/json"
    with pytest.raises(ArtifactNotFound):
        store.get("ci/hover/run-1/replica-9/result.json")


def test_a_store_url_with_credentials_from_the_environment_takes_a_replicas_artifacts(
    minio: MinioServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("UAVTEST_S3_ENDPOINT", f"http://{minio.endpoint}")
    monkeypatch.setenv("UAVTEST_S3_ACCESS_KEY", minio.access_key)
    monkeypatch.setenv("UAVTEST_S3_SECRET_KEY", minio.secret_key)
    store = open_store("s3://runs")
    place = ReplicaPlace("ci", "mission2", "r7", 3)
    result = ReplicaResult(index=3, seed=10, verdict=Verdict.PASS)
    stored, ok = store_artifacts(store, place, result, log_bytes=b"ULog\x01", trajectory=None)
    assert ok and stored.verdict is Verdict.PASS
    assert store.list("ci/mission2/r7/") == [
        "ci/mission2/r7/replica-3/flight.ulg",
        "ci/mission2/r7/replica-3/result.json",
    ]


def test_an_upload_during_an_outage_retries_and_arrives_when_minio_is_back(minio: MinioServer) -> None:
    settings = settings_for(minio, retry_total=90, retry_initial=0.2, retry_max=1.0, timeout=2)
    store = S3Store("outage", settings=settings)
    store.put("before/result.json", b"stored before the outage")
    minio.stop()  # our own root: the data dir stays
    assert not _live(minio.endpoint)

    seen = _RetrySeen(wanted=4)  # MinIO stays down through 4 retries (backoff 0.2 s doubling: a few s)
    logger = logging.getLogger("uavtest.store.s3")
    logger.addHandler(seen)
    logger.setLevel(logging.INFO)
    outcome: dict[str, object] = {}
    payload = os.urandom(256 * 1024)  # a log-sized object

    def upload() -> None:
        try:
            store.put("ns/t/r/replica-0/flight.ulg", payload)
            outcome["ok"] = True
        except Exception as e:  # reported by the assertion below
            outcome["error"] = e

    thread = threading.Thread(target=upload)
    thread.start()
    restarted = None
    try:
        assert seen.event.wait(60), "the upload did not keep retrying"
        assert thread.is_alive()  # still retrying while MinIO is down
        restarted = restart_same(minio)
        thread.join(90)
        assert not thread.is_alive()
        assert outcome == {"ok": True}
        assert store.get("ns/t/r/replica-0/flight.ulg") == payload
        assert store.get("before/result.json") == b"stored before the outage"
    finally:
        logger.removeHandler(seen)
        thread.join(1)
        if restarted is not None:
            restarted.terminate()
            restarted.wait(10)
    retries = [m for m in seen.messages if "retry" in m]
    assert len(retries) >= 4 and all("ns/t/r/replica-0/flight.ulg" in m for m in retries)
    assert not any(minio.secret_key in m or minio.access_key in m for m in seen.messages)


def test_wrong_credentials_fail_without_retrying_or_showing_them(
    minio: MinioServer, caplog: pytest.LogCaptureFixture
) -> None:
    settings = S3Settings(
        endpoint=minio.endpoint, access_key="nobody-key", secret_key="wrong-secret-123", retry_total=60
    )
    with caplog.at_level(logging.INFO, logger="uavtest.store.s3"), pytest.raises(StoreUnavailable) as e:
        S3Store("denied", settings=settings).put("k/result.json", b"{}")
    assert "InvalidAccessKeyId" in str(e.value) or "AccessDenied" in str(e.value)
    assert not [r for r in caplog.records if "retry" in r.getMessage()]  # a refusal is not retried
    assert "wrong-secret-123" not in str(e.value) + caplog.text
