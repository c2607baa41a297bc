"""A throwaway MinIO server for tests: the cached `minio` binary on a free 127.0.0.1 port.

    with minio_server() as s:            # or: s = start_minio(); ...; s.stop()
        client = s.client()              # a minio.Minio client (the `minio` package)
        client.make_bucket("artifacts")

The binary is built once by tests/cluster/build.sh (`build.sh minio`, about 3-5 min from nothing) into
$UAVTEST_CACHE/bin/minio; UAVTEST_MINIO_BIN names another one. Data and certs dirs are temporary, the
root credentials random; stop() ends the process and removes the data.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import secrets
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .cluster import BIN_DIR, ClusterError, build_binaries, free_ports

__all__ = ["MinioError", "MinioServer", "minio_binary", "minio_server", "start_minio"]

READY_TIMEOUT = 60.0


class MinioError(ClusterError):
    """MinIO could not be built or started."""


def minio_binary(build: bool = True) -> Path:
    """The minio server binary: $UAVTEST_MINIO_BIN, else the cached one (built now if missing and BUILD)."""
    env = os.environ.get("UAVTEST_MINIO_BIN")
    if env:
        return Path(env)
    path = BIN_DIR / "minio"
    if build:
        build_binaries("minio")  # a no-op when the cached binary has the pinned version
    if not path.exists():
        raise MinioError(f"{path} missing: run tests/cluster/build.sh minio")
    return path


def _die_with_parent() -> None:  # pragma: no cover - runs in the child between fork and exec
    """Ask the kernel to SIGTERM the server if the test process dies without stopping it."""
    with contextlib.suppress(Exception):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


@dataclass
class MinioServer:
    """A running MinIO server; `endpoint` is host:port as the minio client wants it (plain http)."""

    endpoint: str
    access_key: str
    secret_key: str
    root: Path
    process: subprocess.Popen[bytes] = field(repr=False)
    owns_root: bool = True

    @property
    def url(self) -> str:
        return f"http://{self.endpoint}"

    @property
    def log_path(self) -> Path:
        return self.root / "minio.log"

    def client(self) -> Any:
        """A `minio.Minio` client for this server."""
        from minio import Minio

        return Minio(self.endpoint, access_key=self.access_key, secret_key=self.secret_key, secure=False)

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self) -> None:
        """Terminate the server (KILL after 10 s) and remove its data."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)
        if self.owns_root:
            shutil.rmtree(self.root, ignore_errors=True)


def _live(url: str) -> bool:
    try:
        with urllib.request.urlopen(f"{url}/minio/health/live", timeout=2) as r:
            return bool(r.status == 200)
    except (urllib.error.URLError, OSError):
        return False


def _initializing(e: Exception) -> bool:
    code = getattr(e, "code", "") or ""
    return code.startswith("XMinio") and "NotInitialized" in code


def _serving(server: MinioServer) -> bool:
    """True once MinIO answers S3 calls as a settled server would.

    /minio/health/live answers 200 while MinIO is still initializing its object layer and IAM; calls
    made then fail with XMinioServerNotInitialized / XMinioIAMNotInitialized. Readiness is a real
    ListBuckets with the root credentials, then one with credentials MinIO does not know: root's
    are checked without IAM, so the first can succeed while IAM would still answer any other key
    with XMinioIAMNotInitialized (a test of wrong credentials once met that instead of
    InvalidAccessKeyId).
    """
    from minio import Minio
    from minio.error import S3Error
    from urllib3.exceptions import HTTPError

    try:
        server.client().list_buckets()
    except S3Error as e:
        if _initializing(e):
            return False
        raise MinioError(f"minio at {server.endpoint} refused its root credentials: {e.code}") from e
    except (HTTPError, OSError):  # not listening yet, or the connection dropped
        return False
    stranger = Minio(server.endpoint, access_key="uavtest-nobody", secret_key="not-a-secret-0", secure=False)
    try:
        stranger.list_buckets()
    except S3Error as e:
        return not _initializing(e)  # InvalidAccessKeyId: IAM has looked the key up
    except (HTTPError, OSError):
        return False
    raise MinioError(f"minio at {server.endpoint} let unknown credentials list its buckets")


def start_minio(
    root: Path | str | None = None, *, binary: Path | str | None = None, attempts: int = 3
) -> MinioServer:
    """Start MinIO on a free 127.0.0.1 port with random root credentials; return once it serves S3.

    ROOT (default: a new temp dir, removed on stop) holds data/, certs/ and minio.log.
    """
    exe = str(binary or minio_binary())
    owns_root = root is None
    base = Path(tempfile.mkdtemp(prefix="uavtest-minio-")) if root is None else Path(root)
    (base / "data").mkdir(parents=True, exist_ok=True)
    (base / "certs").mkdir(exist_ok=True)
    access_key = "uavtest-" + secrets.token_hex(6)
    secret_key = secrets.token_urlsafe(24)
    env = {
        **os.environ,
        "MINIO_ROOT_USER": access_key,
        "MINIO_ROOT_PASSWORD": secret_key,
        "MINIO_BROWSER": "off",
        "MINIO_UPDATE": "off",
        "MINIO_CALLHOME_ENABLE": "off",
        "HOME": str(base),  # MinIO would otherwise create ~/.minio
    }
    last_log = ""
    for _ in range(attempts):
        port, console = free_ports(2)
        endpoint = f"127.0.0.1:{port}"
        with open(base / "minio.log", "wb") as log:
            proc = subprocess.Popen(
                [
                    exe,
                    "server",
                    str(base / "data"),
                    "--address",
                    endpoint,
                    "--console-address",
                    f"127.0.0.1:{console}",
                    "--certs-dir",
                    str(base / "certs"),
                    "--quiet",
                ],
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                preexec_fn=_die_with_parent,
            )
        server = MinioServer(endpoint, access_key, secret_key, base, proc, owns_root=False)
        deadline = time.monotonic() + READY_TIMEOUT
        while proc.poll() is None and time.monotonic() < deadline:
            if _live(server.url) and _serving(server):
                server.owns_root = owns_root
                return server
            time.sleep(0.1)
        server.stop()
        last_log = (base / "minio.log").read_text(errors="replace")[-2000:]
        # a port taken between choosing and binding: try again on another one
    if owns_root:
        shutil.rmtree(base, ignore_errors=True)
    raise MinioError(f"minio did not become live after {attempts} attempts:\n{last_log}")


@contextlib.contextmanager
def minio_server(
    root: Path | str | None = None, *, binary: Path | str | None = None
) -> Iterator[MinioServer]:
    """Context manager around start_minio / stop."""
    server = start_minio(root, binary=binary)
    try:
        yield server
    finally:
        server.stop()
