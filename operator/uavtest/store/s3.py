"""An artifact store in an S3 bucket (MinIO or any S3), through the ``minio`` client.

Every operation retries transient faults (server unreachable, 5xx, slow down) with exponential
backoff until ``retry_total`` seconds have passed; each retry is logged with the operation, the key
and the error, never the credentials. The bucket is created on the first write when it is missing.
"""

from __future__ import annotations

import io
import logging
from collections.abc import Callable
from typing import TypeVar

import certifi
import urllib3
from minio import Minio
from minio.error import InvalidResponseError, S3Error, ServerError
from tenacity import (
    RetryCallState,
    Retrying,
    retry_if_exception,
    stop_after_delay,
    wait_exponential,
    wait_random,
)

from uavtest.store.errors import ArtifactNotFound, StoreUnavailable
from uavtest.store.settings import S3Settings

__all__ = ["S3Store", "is_transient"]

log = logging.getLogger(__name__)

T = TypeVar("T")

# S3 error codes that mean "try again later", not "you are wrong"
_TRANSIENT_CODES = frozenset(
    {
        "InternalError",
        "RequestTimeout",
        "ServiceUnavailable",
        "SlowDown",
        "XMinioServerNotInitialized",
        "XMinioIAMNotInitialized",  # MinIO answers before its IAM is up: restarting, not refusing
        "XMinioReadQuorum",
        "XMinioWriteQuorum",
    }
)
_MISSING_CODES = frozenset({"NoSuchKey", "NoSuchBucket", "NoSuchObject"})


def is_transient(error: BaseException) -> bool:
    """Whether an error from the minio client is worth retrying."""
    if isinstance(error, S3Error):
        return error.code in _TRANSIENT_CODES
    return isinstance(error, ServerError | InvalidResponseError | urllib3.exceptions.HTTPError | OSError)


def _describe(error: BaseException) -> str:
    if isinstance(error, S3Error):
        return f"S3 error {error.code}: {error.message}"
    text = str(error) or type(error).__name__
    return f"{type(error).__name__}: {text}"


class S3Store:
    """Artifacts as objects ``<prefix>/<key>`` in ``bucket``."""

    def __init__(
        self,
        bucket: str,
        prefix: str = "",
        *,
        settings: S3Settings | None = None,
        client: Minio | None = None,
    ) -> None:
        self.bucket = bucket
        self.prefix = prefix.strip("/")
        self.settings = settings if settings is not None else S3Settings()
        self._client = client if client is not None else self._make_client(self.settings)
        self._bucket_ready = False

    def __repr__(self) -> str:
        return f"S3Store(bucket={self.bucket!r}, prefix={self.prefix!r}, endpoint={self.settings.endpoint!r})"

    @staticmethod
    def _make_client(settings: S3Settings) -> Minio:
        host, secure = settings.host_and_secure()
        # No urllib3 retries and short timeouts: tenacity does the retrying, and logs it.
        timeout = urllib3.Timeout(connect=settings.timeout, read=settings.timeout)
        http = urllib3.PoolManager(
            timeout=timeout,
            retries=False,
            maxsize=8,
            cert_reqs="CERT_REQUIRED" if secure else "CERT_NONE",
            ca_certs=certifi.where() if secure else None,
        )
        return Minio(
            host,
            access_key=settings.access_key.get_secret_value() if settings.access_key else None,
            secret_key=settings.secret_key.get_secret_value() if settings.secret_key else None,
            secure=secure,
            region=settings.region,
            http_client=http,
        )

    # ------------------------------------------------------------------ retry

    def _retry(self, operation: str, key: str, call: Callable[[], T]) -> T:
        def before_sleep(state: RetryCallState) -> None:
            error = state.outcome.exception() if state.outcome else None
            wait = state.next_action.sleep if state.next_action else 0.0
            log.warning(
                "store %s %s failed (%s); retry %d in %.1f s",
                operation,
                key,
                _describe(error) if error else "?",
                state.attempt_number,
                wait,
            )

        s = self.settings
        jitter = wait_random(0, s.retry_initial)
        backoff = wait_exponential(multiplier=s.retry_initial, max=s.retry_max) + jitter
        retrying = Retrying(
            stop=stop_after_delay(s.retry_total),
            wait=backoff,
            retry=retry_if_exception(is_transient),
            before_sleep=before_sleep,
            reraise=True,
        )
        try:
            return retrying(call)
        except S3Error as e:
            if e.code in _MISSING_CODES:
                raise ArtifactNotFound(key, self.url("")) from e
            raise StoreUnavailable(operation, self.url(key), _describe(e)) from e
        except (ServerError, InvalidResponseError, urllib3.exceptions.HTTPError, OSError) as e:
            raise StoreUnavailable(
                operation, self.url(key), f"{_describe(e)} (gave up after {s.retry_total:g} s)"
            ) from e

    # ------------------------------------------------------------------ keys

    def _object(self, key: str) -> str:
        return f"{self.prefix}/{key}" if self.prefix else key

    def _ensure_bucket(self) -> None:
        if self._bucket_ready:
            return
        if not self._client.bucket_exists(self.bucket):
            try:
                self._client.make_bucket(self.bucket)
                log.info("created bucket %s", self.bucket)
            except S3Error as e:
                if e.code not in {"BucketAlreadyOwnedByYou", "BucketAlreadyExists"}:
                    raise
        self._bucket_ready = True

    # ------------------------------------------------------------------ ArtifactStore

    def put(self, key: str, data: bytes, content_type: str = "application/octet-stream") -> None:
        name = self._object(key)

        def call() -> None:
            self._ensure_bucket()
            self._client.put_object(self.bucket, name, io.BytesIO(data), len(data), content_type=content_type)

        self._retry("put", key, call)

    def get(self, key: str) -> bytes:
        name = self._object(key)

        def call() -> bytes:
            response = self._client.get_object(self.bucket, name)
            try:
                return response.read()
            finally:
                response.close()
                response.release_conn()

        return self._retry("get", key, call)

    def exists(self, key: str) -> bool:
        name = self._object(key)

        def call() -> bool:
            try:
                self._client.stat_object(self.bucket, name)
            except S3Error as e:
                if e.code in _MISSING_CODES:
                    return False
                raise
            return True

        return self._retry("exists", key, call)

    def list(self, prefix: str = "") -> list[str]:
        full = self._object(prefix) if prefix else (f"{self.prefix}/" if self.prefix else "")
        cut = len(self.prefix) + 1 if self.prefix else 0

        def call() -> list[str]:
            try:
                objects = self._client.list_objects(self.bucket, prefix=full, recursive=True)
                return sorted(o.object_name[cut:] for o in objects if o.object_name)
            except S3Error as e:
                if e.code == "NoSuchBucket":
                    return []
                raise

        return self._retry("list", prefix, call)

    def url(self, key: str) -> str:
        return f"s3://{self.bucket}/{self._object(key)}" if key else f"s3://{self.bucket}/{self.prefix}"
