"""An artifact store in an S3 bucket (MinIO or any S3), through the ``minio`` client.

Every operation retries transient faults (server unreachable, 5xx, slow down) with exponential
backoff until ``retry_total`` seconds have passed; each retry is logged with the operation, the key
and the error, never the credentials. The bucket is created on the first write when it is missing.
"""

from __future__ import annotations

import io
import logging
from collections.abc import Callable
from datetime import datetime
from typing import TypeVar

import certifi
import urllib3
from minio import Minio
from minio.datatypes import PostPolicy
from minio.error import InvalidResponseError, S3Error, ServerError

from uavtest.errors import BadInput
from uavtest.store.errors import ArtifactNotFound, StoreUnavailable
from uavtest.store.post_policy import UploadPolicy
from uavtest.store.retry import retrying
from uavtest.store.settings import S3Settings

__all__ = ["S3Store", "is_transient", "post_policy_for"]

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


def post_policy_for(bucket: str, name_prefix: str, expires: datetime, max_bytes: int) -> PostPolicy:
    """The POST policy of one run: this bucket, names under ``name_prefix``, 0..``max_bytes`` bytes, until
    ``expires``.

    Any Content-Type may be sent (artifacts carry theirs); nothing else is allowed.
    """
    if not name_prefix.endswith("/"):
        raise BadInput("an upload prefix must end with '/'", field="name_prefix", value=name_prefix)
    if expires.tzinfo is None:
        raise BadInput("an upload policy's expiry needs a time zone", field="expires", value=str(expires))
    policy = PostPolicy(bucket, expires)
    policy.add_starts_with_condition("key", name_prefix)
    policy.add_starts_with_condition("Content-Type", "")
    policy.add_content_length_range_condition(0, max_bytes)
    return policy


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
        s = self.settings
        retry = retrying(s, operation, key, transient=is_transient, describe=_describe, log=log)
        try:
            return retry(call)
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

    # ------------------------------------------------------------------ upload policies

    def upload_policy(
        self, key_prefix: str, *, expires: datetime, max_bytes: int, endpoint_url: str | None = None
    ) -> UploadPolicy:
        """Sign a POST policy that lets its holder upload under ``key_prefix`` only, until ``expires``.

        ``endpoint_url`` (``http(s)://host:port``) is where the holder reaches the server (a pod may
        reach it by another address than this process); the signature does not depend on it. The
        bucket is created first when missing (an upload policy cannot create it).
        """
        name_prefix = self._object(key_prefix)
        policy = post_policy_for(self.bucket, name_prefix, expires, max_bytes)
        if endpoint_url is None:
            host, secure = self.settings.host_and_secure()
            endpoint_url = f"{'https' if secure else 'http'}://{host}"

        def call() -> dict[str, str]:
            self._ensure_bucket()
            return self._client.presigned_post_policy(policy)

        fields = self._retry("sign upload policy", key_prefix, call)
        return UploadPolicy(
            url=f"{endpoint_url.rstrip('/')}/{self.bucket}",
            bucket=self.bucket,
            key_prefix=name_prefix,
            expires=expires,
            max_bytes=max_bytes,
            fields=fields,
        )

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
