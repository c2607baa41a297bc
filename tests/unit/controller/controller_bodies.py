"""Bodies of UavTests, UavTestRuns, Jobs and pods as the API server returns them (camelCase dicts).

``uavtest_body`` is a run (``UavTestRun``) of the test ``name``: the object that owns the Job and
carries the run's status; ``test_body`` is the ``UavTest`` itself.
"""

from __future__ import annotations

from typing import Any

UID = "5f0c3a9e-1b2c-4d5e-8f90-123456789abc"
RUN = "5f0c3a9e"


def uavtest_body(
    name: str = "hover",
    namespace: str = "team-a",
    *,
    replicas: int = 4,
    seed: int = 10,
    status: dict[str, Any] | None = None,
    **spec: Any,
) -> dict[str, Any]:
    body_spec: dict[str, Any] = {
        "replicas": replicas,
        "seed": seed,
        "timeout": 120,
        "mission": {"waypoints": [{"x": 0, "y": 0, "z": -10}, {"x": 20, "y": 0, "z": -10}]},
        "world": {"obstacles": [{"size": {"l": 2, "w": 2, "h": 20}, "position": {"x": 10, "y": 4}}]},
    }
    body_spec.update(spec)
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTestRun",
        "metadata": {
            "name": f"{name}-g1",
            "namespace": namespace,
            "uid": UID,
            "generation": 1,
            "creationTimestamp": "2025-01-01T10:00:00Z",
            "labels": {"team": "a"},
        },
        "spec": {"testName": name, "testGeneration": 1, "trigger": "create", "testSpec": body_spec},
        "status": status or {},
    }


def test_body(
    name: str = "hover",
    namespace: str = "team-a",
    *,
    generation: int = 1,
    status: dict[str, Any] | None = None,
    annotations: dict[str, str] | None = None,
    created: str = "2025-01-01T10:00:00Z",
    **spec: Any,
) -> dict[str, Any]:
    """A UavTest body (the long-lived test)."""
    run = uavtest_body(name, namespace)
    body_spec = {**run["spec"]["testSpec"], **spec}
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {
            "name": name,
            "namespace": namespace,
            "uid": "0a1b2c3d-0000-4000-8000-000000000001",
            "generation": generation,
            "creationTimestamp": created,
            "annotations": annotations or {},
        },
        "spec": body_spec,
        "status": status or {},
    }


test_body.__test__ = False  # type: ignore[attr-defined]


def job_body(
    *,
    test: str = "hover",
    completions: int = 4,
    completed: str = "",
    failed: str = "",
    active: int = 0,
    ready: int = 0,
    terminal: tuple[str, str] | None = None,
) -> dict[str, Any]:
    status: dict[str, Any] = {"startTime": "2025-01-01T10:00:00Z", "active": active, "ready": ready}
    if completed:
        status["completedIndexes"] = completed
    if failed:
        status["failedIndexes"] = failed
    if terminal:
        status["conditions"] = [
            {
                "type": terminal[0],
                "status": "True",
                "reason": terminal[1],
                "message": f"{terminal[1]} happened",
            }
        ]
    return {
        "metadata": {
            "name": f"{test}-{RUN}",
            "namespace": "team-a",
            "labels": {"uavtest.io/test": test, "uavtest.io/run": RUN},
        },
        "spec": {"completions": completions, "completionMode": "Indexed"},
        "status": status,
    }


def pod_body(
    index: int,
    phase: str,
    *,
    exit_code: int | None = None,
    created: str = "2025-01-01T10:00:01Z",
    suffix: str = "abcde",
    test: str = "hover",
) -> dict[str, Any]:
    statuses: list[dict[str, Any]] = [{"name": "sitl", "state": {"running": {"startedAt": created}}}]
    if exit_code is not None:
        statuses.append(
            {
                "name": "runner",
                "state": {
                    "terminated": {
                        "exitCode": exit_code,
                        "reason": "Completed" if exit_code == 0 else "Error",
                        "startedAt": "2025-01-01T10:00:05Z",
                        "finishedAt": "2025-01-01T10:01:05Z",
                    }
                },
            }
        )
    elif phase == "Running":
        statuses.append({"name": "runner", "state": {"running": {"startedAt": "2025-01-01T10:00:05Z"}}})
    return {
        "metadata": {
            "name": f"{test}-{RUN}-{index}-{suffix}",
            "namespace": "team-a",
            "creationTimestamp": created,
            "labels": {
                "uavtest.io/test": test,
                "uavtest.io/run": RUN,
                "batch.kubernetes.io/job-completion-index": str(index),
            },
        },
        "status": {"phase": phase, "containerStatuses": statuses},
    }
