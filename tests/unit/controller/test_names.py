"""Names the operator writes: kopf's bookkeeping never hides a user's annotation from it."""

from __future__ import annotations

import kopf

from uavtest.controller import names


def test_a_rerun_annotation_is_a_change_kopf_sees() -> None:
    """kopf drops annotations under its storage prefix from the state it diffs: the rerun
    annotation must live outside that prefix, or setting it would trigger nothing."""
    storage = kopf.AnnotationsDiffBaseStorage(prefix=names.PROGRESS_PREFIX, key="last-handled-configuration")
    marker = f"{names.PROGRESS_PREFIX}/kopf-managed"  # kopf brands its storage prefix with this

    def body(rerun: str) -> kopf.Body:
        raw = {
            "metadata": {"name": "t", "annotations": {marker: "yes", names.RERUN_ANNOTATION: rerun}},
            "spec": {"replicas": 1},
        }
        return kopf.Body(raw)

    assert storage.build(body=body("1")) != storage.build(body=body("2"))
