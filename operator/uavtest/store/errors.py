"""What can go wrong with an artifact store, as uavtest errors (exit 3: the bench's fault)."""

from __future__ import annotations

from uavtest.errors import InfrastructureError

__all__ = ["ArtifactNotFound", "StoreUnavailable"]


class ArtifactNotFound(InfrastructureError):
    """A key that should hold an artifact holds nothing (a replica's artifacts went missing)."""

    def __init__(self, key: str, where: str) -> None:
        self.key = key
        super().__init__(f"artifact {key} not found in {where}")


class StoreUnavailable(InfrastructureError):
    """The store did not take or give an artifact, after the retries ran out (or for good)."""

    def __init__(self, operation: str, key: str, cause: str) -> None:
        self.operation = operation
        self.key = key
        self.cause = cause
        super().__init__(f"store {operation} {key} failed: {cause}")
