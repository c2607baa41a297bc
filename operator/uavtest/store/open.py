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
    """The store ``url`` names; S3 endpoint and credentials come from ``UAVTEST_S3_*`` env vars."""
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
        from uavtest.store.s3 import S3Store

        if not parts.netloc:
            raise BadInput("s3 URL needs a bucket", field="store", value=text, allowed="s3://BUCKET[/PREFIX]")
        return S3Store(parts.netloc, unquote(parts.path).strip("/"), settings=settings)
    raise BadInput(
        "unknown store URL scheme",
        field="store",
        value=parts.scheme,
        allowed="DIR, file:///DIR, s3://BUCKET[/PREFIX]",
    )
