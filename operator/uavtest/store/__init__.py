"""Artifact storage behind one small interface: a local directory and S3 (MinIO client).

``open_store(url)`` gives an ``ArtifactStore``; ``uavtest.store.layout`` says where each artifact
of a run goes. The store knows nothing about what the artifacts mean.
"""

from uavtest.store.base import ArtifactStore
from uavtest.store.errors import ArtifactNotFound, StoreUnavailable
from uavtest.store.layout import aggregate_key, replica_key
from uavtest.store.local import LocalStore
from uavtest.store.open import open_store

__all__ = [
    "ArtifactNotFound",
    "ArtifactStore",
    "LocalStore",
    "S3Settings",
    "S3Store",
    "StoreUnavailable",
    "aggregate_key",
    "open_store",
    "replica_key",
]


def __getattr__(name: str) -> object:
    # S3 pulls in minio, urllib3 and pydantic-settings: import it only when asked for
    if name == "S3Store":
        from uavtest.store.s3 import S3Store

        return S3Store
    if name == "S3Settings":
        from uavtest.store.settings import S3Settings

        return S3Settings
    raise AttributeError(name)
