"""The one small interface every artifact store offers."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["ArtifactStore"]


@runtime_checkable
class ArtifactStore(Protocol):
    """Bytes under ``/``-separated keys (see ``uavtest.store.layout``).

    ``get`` raises ``ArtifactNotFound`` for a missing key; a store that cannot be reached
    raises ``StoreUnavailable`` once its retries run out.
    """

    def put(self, key: str, data: bytes, content_type: str = "application/octet-stream") -> None:
        """Store ``data`` under ``key``, replacing what was there."""
        ...

    def get(self, key: str) -> bytes:
        """The bytes under ``key``."""
        ...

    def exists(self, key: str) -> bool:
        """Whether ``key`` holds an artifact."""
        ...

    def list(self, prefix: str = "") -> list[str]:
        """Every key that starts with ``prefix``, sorted."""
        ...

    def url(self, key: str) -> str:
        """Where a person finds the artifact (``file://...`` or ``s3://bucket/...``); no secrets."""
        ...
