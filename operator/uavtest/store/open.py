"""Open a store from a URL: ``file:///dir`` or a plain path, or ``s3://bucket[/prefix]``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import unquote, urlsplit

from uavtest.errors import BadInput
from uavtest.store.base import ArtifactStore
from uavtest.store.local import LocalStore

if TYPE_CHECKING:  # pydantic-settings and minio load only for S3 stores
    from uavtest.store.settings import S3Settings

__all__ = ["open_store"]


def open_store(url: str | Path, *, settings: S3Settings | None = None) -> ArtifactStore:
    """The store ``url`` names; S3 endpoint and credentials come from ``UAVTEST_S3_*`` env vars.

    With ``UAVTEST_S3_UPLOAD_POLICY`` set (a replica pod in a cluster), an ``s3://`` URL opens a
    write-only ``PostPolicyStore`` that uploads through that policy instead of with keys.
    """
    text = str(url)
    if "://" not in text:
        if not text:
            raise BadInput(
                "store URL is empty", field="store", allowed="DIR, file:///DIR, s3://BUCKET[/PREFIX]"
            )
        return LocalStore(Path(text))
    parts = urlsplit(text)
    if parts.scheme == "file":
        if parts.netloc not in {"", "localhost"}:
            raise BadInput("file URL must be file:///absolute/dir", field="store", value=text)
        return LocalStore(Path(unquote(parts.path)))
    if parts.scheme == "s3":
        from uavtest.store.settings import S3Settings

        if not parts.netloc:
            raise BadInput("s3 URL needs a bucket", field="store", value=text, allowed="s3://BUCKET[/PREFIX]")
        settings = settings if settings is not None else S3Settings()
        bucket, prefix = parts.netloc, unquote(parts.path).strip("/")
        if settings.upload_policy is not None:
            from uavtest.store.post_policy import PostPolicyStore, parse_policy

            policy = parse_policy(settings.upload_policy.get_secret_value())
            return PostPolicyStore(policy, bucket, prefix, settings=settings)
        from uavtest.store.s3 import S3Store

        return S3Store(bucket, prefix, settings=settings)
    raise BadInput(
        "unknown store URL scheme",
        field="store",
        value=parts.scheme,
        allowed="DIR, file:///DIR, s3://BUCKET[/PREFIX]",
    )
