"""A write-only artifact store: uploads through a signed S3 POST policy (browser-form upload).

The operator holds the store's credentials; a replica pod gets only an ``UploadPolicy``: a policy
document signed by the operator that lets whoever holds it POST objects whose names start with one
run's prefix, each at most ``max_bytes``, until ``expires``. MinIO and AWS S3 both check it. The
policy is not a credential that works anywhere else: it cannot read, list, delete, or write outside
the prefix, and it expires.

``PostPolicyStore.put`` sends ``multipart/form-data`` (the policy's fields, ``key``,
``Content-Type``, then the file) with bounded, logged retries like ``S3Store``; ``get``, ``exists``
and ``list`` raise ``WriteOnlyStore``. The form fields (signature, policy) never show in a repr, a
log line or an error message.
"""

from __future__ import annotations

import logging
import secrets
import xml.etree.ElementTree as ET
from datetime import datetime
from typing import NoReturn

import certifi
import urllib3
from pydantic import AwareDatetime, BaseModel, ConfigDict, Field, ValidationError

from uavtest.errors import BadInput, InfrastructureError
from uavtest.store.errors import StoreUnavailable
from uavtest.store.retry import retrying
from uavtest.store.settings import S3Settings

__all__ = [
    "POLICY_ENV",
    "PostPolicyStore",
    "PostRefused",
    "UploadPolicy",
    "WriteOnlyStore",
    "parse_policy",
    "post_object",
]

log = logging.getLogger(__name__)

POLICY_ENV = "UAVTEST_S3_UPLOAD_POLICY"

# S3 error codes (and HTTP statuses) that mean "try again later"
_TRANSIENT_CODES = frozenset(
    {
        "InternalError",
        "RequestTimeout",
        "ServiceUnavailable",
        "SlowDown",
        "XMinioServerNotInitialized",
        "XMinioIAMNotInitialized",
        "XMinioReadQuorum",
        "XMinioWriteQuorum",
    }
)


class UploadPolicy(BaseModel):
    """A signed POST policy for one run: where to POST, what it allows, and the form fields to send."""

    model_config = ConfigDict(frozen=True, extra="forbid", hide_input_in_errors=True)

    url: str = Field(description="http(s)://host:port/bucket: the form's action (path-style)")
    bucket: str
    key_prefix: str = Field(description="object names the policy allows start with this")
    expires: AwareDatetime
    max_bytes: int = Field(ge=0, description="largest object the policy allows")
    fields: dict[str, str] = Field(repr=False, description="policy, x-amz-*: sent as they are")

    def allows(self, object_name: str) -> bool:
        return object_name.startswith(self.key_prefix)

    def where(self) -> str:
        """The prefix the policy allows, as an s3:// URI (no secrets)."""
        return f"s3://{self.bucket}/{self.key_prefix}"


class WriteOnlyStore(InfrastructureError):
    """A read asked of a store that can only upload (a replica pod's upload policy)."""

    def __init__(self, operation: str, where: str) -> None:
        super().__init__(
            f"store {operation} is not possible with an upload policy ({where}): it can only upload; "
            "read artifacts with the store's credentials (the operator, or uavtest report)"
        )


class PostRefused(Exception):
    """The S3 server answered the POST with an error (code and message from its XML body)."""

    def __init__(self, status: int, code: str, message: str) -> None:
        self.status, self.code, self.message = status, code, message
        super().__init__(f"HTTP {status} {code}: {message}" if message else f"HTTP {status} {code}")


def parse_policy(text: str) -> UploadPolicy:
    """The policy in ``UAVTEST_S3_UPLOAD_POLICY``; BadInput naming the field (never the value)."""
    try:
        return UploadPolicy.model_validate_json(text)
    except ValidationError as e:
        first = e.errors(include_input=False)[0]
        where = ".".join(str(p) for p in first["loc"]) or "(the document)"
        raise BadInput(
            f"not an upload policy: {where}: {first['msg']}",
            field=POLICY_ENV,
            allowed='JSON {"url", "bucket", "key_prefix", "expires", "max_bytes", "fields"}',
        ) from None


def _pool(url: str, settings: S3Settings) -> urllib3.PoolManager:
    secure = url.startswith("https://")
    return urllib3.PoolManager(
        timeout=urllib3.Timeout(connect=settings.timeout, read=settings.timeout),
        retries=False,  # tenacity retries, and logs it
        maxsize=4,
        cert_reqs="CERT_REQUIRED" if secure else "CERT_NONE",
        ca_certs=certifi.where() if secure else None,
    )


def _error_of(status: int, body: bytes) -> PostRefused:
    code, message = f"HTTP{status}", ""
    try:
        root = ET.fromstring(body)
        code = root.findtext("Code") or code
        message = root.findtext("Message") or ""
    except ET.ParseError:
        message = body[:200].decode(errors="replace")
    return PostRefused(status, code, message)


def _form(
    policy: UploadPolicy, object_name: str, data: bytes, content_type: str
) -> tuple[list[bytes | memoryview], str]:
    """The multipart/form-data body as parts (the file's bytes are not copied) and its Content-Type."""
    boundary = secrets.token_hex(16)
    fields = [*policy.fields.items(), ("key", object_name), ("Content-Type", content_type)]
    head = "".join(
        f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n{value}\r\n'
        for name, value in fields
    )
    filename = object_name.rsplit("/", 1)[-1] or "file"
    head += (
        f'--{boundary}\r\nContent-Disposition: form-data; name="file"; filename="{filename}"\r\n'
        f"Content-Type: {content_type}\r\n\r\n"
    )  # the file goes last: S3 ignores fields after it
    tail = f"\r\n--{boundary}--\r\n"
    return [head.encode(), memoryview(data), tail.encode()], f"multipart/form-data; boundary={boundary}"


def post_object(
    http: urllib3.PoolManager,
    policy: UploadPolicy,
    object_name: str,
    data: bytes,
    content_type: str = "application/octet-stream",
) -> None:
    """One POST of ``data`` as ``object_name`` under ``policy``; raises PostRefused on an S3 error.

    No check of the name here: the server enforces the policy (a test proves it does). The body is
    sent in parts with its length, so a large flight log is not copied in memory.
    """
    if any(c in object_name for c in '"\r\n') or any(c in content_type for c in '"\r\n'):
        raise BadInput("not usable in an upload form", field="key", value=object_name)
    parts, form_type = _form(policy, object_name, data, content_type)
    length = sum(len(p) for p in parts)
    response = http.request(
        "POST",
        policy.url,
        body=parts,
        headers={"Content-Type": form_type, "Content-Length": str(length)},
        preload_content=True,
    )
    if not 200 <= response.status < 300:
        raise _error_of(response.status, response.data)


def _transient(error: BaseException) -> bool:
    if isinstance(error, PostRefused):
        return error.status >= 500 or error.code in _TRANSIENT_CODES
    return isinstance(error, urllib3.exceptions.HTTPError | OSError)


def _describe(error: BaseException) -> str:
    if isinstance(error, PostRefused):
        return f"S3 error {error}"
    return f"{type(error).__name__}: {str(error) or type(error).__name__}"


class PostPolicyStore:
    """Uploads ``<prefix>/<key>`` into the policy's bucket; cannot read (``WriteOnlyStore``)."""

    def __init__(
        self, policy: UploadPolicy, bucket: str, prefix: str = "", *, settings: S3Settings | None = None
    ) -> None:
        if bucket != policy.bucket:
            raise BadInput(
                "the store URL's bucket is not the upload policy's",
                field="store",
                value=f"s3://{bucket}",
                allowed=f"s3://{policy.bucket}/... (the bucket in {POLICY_ENV})",
            )
        self.policy = policy
        self.bucket = bucket
        self.prefix = prefix.strip("/")
        self.settings = settings if settings is not None else S3Settings()
        self._http = _pool(policy.url, self.settings)

    def __repr__(self) -> str:
        return f"PostPolicyStore({self.policy.where()!r}, expires={self.policy.expires.isoformat()})"

    def _object(self, key: str) -> str:
        return f"{self.prefix}/{key}" if self.prefix else key

    def put(self, key: str, data: bytes, content_type: str = "application/octet-stream") -> None:
        name = self._object(key)
        if not self.policy.allows(name):
            raise StoreUnavailable(
                "put", self.url(key), f"outside the upload policy's prefix {self.policy.where()}"
            )
        if len(data) > self.policy.max_bytes:
            raise StoreUnavailable(
                "put", self.url(key), f"{len(data)} bytes, over the upload policy's {self.policy.max_bytes}"
            )
        s = self.settings
        retry = retrying(s, "put", key, transient=_transient, describe=_describe, log=log)
        try:
            retry(lambda: post_object(self._http, self.policy, name, data, content_type))
        except PostRefused as e:
            cause = _describe(e)
            if e.code == "AccessDenied" and datetime.now(self.policy.expires.tzinfo) >= self.policy.expires:
                cause += f" (the upload policy expired at {self.policy.expires.isoformat()})"
            raise StoreUnavailable("put", self.url(key), cause) from e
        except (urllib3.exceptions.HTTPError, OSError) as e:
            raise StoreUnavailable(
                "put", self.url(key), f"{_describe(e)} (gave up after {s.retry_total:g} s)"
            ) from e

    def _refuse(self, operation: str) -> NoReturn:
        raise WriteOnlyStore(operation, self.policy.where())

    def get(self, key: str) -> bytes:
        self._refuse("get")

    def exists(self, key: str) -> bool:
        self._refuse("exists")

    def list(self, prefix: str = "") -> list[str]:
        self._refuse("list")

    def url(self, key: str) -> str:
        return f"s3://{self.bucket}/{self._object(key)}" if key else f"s3://{self.bucket}/{self.prefix}"
