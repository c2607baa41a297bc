"""Stage 8: the replica's artifacts into the store, ``result.json`` last and always attempted.

``flight.ulg`` and ``trajectory.csv`` go first, so a ``result.json`` in the store means the others
were stored too (or the result says why not). A log that cannot be stored turns the verdict into
``error``: nothing is lost silently.
"""

from __future__ import annotations

import logging

from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import UavTestError
from uavtest.store.base import ArtifactStore
from uavtest.store.layout import FLIGHT_LOG, RESULT, TRAJECTORY, replica_key

__all__ = ["ReplicaPlace", "store_artifacts"]

log = logging.getLogger(__name__)


class ReplicaPlace:
    """Where one replica's artifacts go: namespace, test, run id, index."""

    def __init__(self, namespace: str, test: str, run_id: str, index: int) -> None:
        self.namespace, self.test, self.run_id, self.index = namespace, test, run_id, index
        self.key(RESULT)  # validates the segments now (BadInput naming the field)

    def key(self, name: str) -> str:
        return replica_key(self.namespace, self.test, self.run_id, self.index, name)


def store_artifacts(
    store: ArtifactStore,
    place: ReplicaPlace,
    result: ReplicaResult,
    *,
    log_bytes: bytes | None,
    trajectory: Trajectory | None,
) -> tuple[ReplicaResult, bool]:
    """Put the artifacts; returns the (possibly downgraded) result and whether result.json landed."""
    failures: list[str] = []
    uploads: list[tuple[str, bytes, str]] = []
    if log_bytes is not None:
        uploads.append((FLIGHT_LOG, log_bytes, "application/octet-stream"))
    if trajectory is not None:
        uploads.append((TRAJECTORY, trajectory.to_csv().encode(), "text/csv"))
    for name, data, content_type in uploads:
        try:
            store.put(place.key(name), data, content_type)
            log.info("stored %s (%d bytes)", store.url(place.key(name)), len(data))
        except UavTestError as e:
            log.error("could not store %s: %s", name, e)
            failures.append(f"{name}: {e}")
    if failures:
        reason = "store upload failed: " + "; ".join(failures)
        if result.verdict is not Verdict.ERROR:
            reason += f" (the flight itself was judged {result.verdict.value}"
            reason += f": {result.reason})" if result.reason else ")"
        else:
            reason = f"{result.reason}; {reason}"
        result = result.model_copy(update={"verdict": Verdict.ERROR, "reason": reason})
    try:
        store.put(place.key(RESULT), result.model_dump_json(indent=2).encode(), "application/json")
        log.info("stored %s", store.url(place.key(RESULT)))
    except UavTestError as e:
        log.error("could not store result.json: %s", e)
        reason = f"store upload of result.json failed: {e}"
        if result.verdict is not Verdict.ERROR or not result.reason:
            result = result.model_copy(update={"verdict": Verdict.ERROR, "reason": reason})
        else:
            result = result.model_copy(update={"reason": f"{result.reason}; {reason}"})
        return result, False
    return result, True
