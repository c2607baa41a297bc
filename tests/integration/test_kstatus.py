"""The status the operator writes reads right in kstatus, the library Flux decides health with.

Objects are produced by the operator's own status builders (``status_from`` for a UavTestRun,
``test_status_from`` for a UavTest) and handed, as JSON, to the real kstatus
(sigs.k8s.io/cli-utils, built from Go modules: tests/cluster/go/kstatus). The e2e tier does the
same with objects read back from a real cluster (tests/e2e/test_operator_run.py).
"""

from __future__ import annotations

from typing import Any

import pytest

from harness.kstatus import KstatusUnavailable, kstatus, kstatus_binary
from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.controller.runs import test_status_from
from uavtest.controller.status import status_from
from uavtest.controller.views import job_view, pod_view, run_view, test_view

pytestmark = pytest.mark.integration

RUN_META = {
    "name": "hover-g1",
    "namespace": "ci",
    "uid": "5f0c3a9e-0000-4000-8000-000000000001",
    "generation": 1,
}


@pytest.fixture(scope="module", autouse=True)
def built() -> None:
    try:
        kstatus_binary()
    except KstatusUnavailable as e:
        pytest.skip(str(e))


def run_body(status: dict[str, Any] | None = None) -> dict[str, Any]:
    spec = {"replicas": 2, "mission": {"waypoints": [{"x": 0, "y": 0, "z": -5}]}}
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTestRun",
        "metadata": {**RUN_META, "creationTimestamp": "2026-03-01T10:00:00Z"},
        "spec": {"testName": "hover", "testGeneration": 1, "trigger": "create", "testSpec": spec},
        "status": status or {},
    }


def written(body: dict[str, Any], **kw: Any) -> dict[str, Any]:
    """``body`` with the status the operator would write for it."""
    st = status_from(run_view(body), kw.pop("job", None), kw.pop("pods", []), store_url="s3://b", **kw)
    return {**body, "status": st.dump()}


def replicas(*verdicts: Verdict) -> Any:
    results = [
        ReplicaResult(index=i, seed=i, verdict=v, metrics=FlightMetrics(min_obstacle_distance=2.0))
        for i, v in enumerate(verdicts)
    ]
    return summarize(results, test="hover", namespace="ci", run_id="5f0c3a9e")


def running_run() -> dict[str, Any]:
    job = {
        "metadata": {
            "name": "hover-5f0c3a9e",
            "labels": {"uavtest.io/test": "hover", "uavtest.io/run": "5f0c3a9e"},
        },
        "spec": {"completions": 2},
        "status": {"active": 2, "startTime": "2026-03-01T10:00:01Z"},
    }
    pod = {
        "metadata": {
            "name": "hover-5f0c3a9e-0-x",
            "creationTimestamp": "2026-03-01T10:00:01Z",
            "labels": {"batch.kubernetes.io/job-completion-index": "0"},
        },
        "status": {"phase": "Running"},
    }
    return written(run_body(), job=job_view(job), pods=[pod_view(pod)])


def test_a_run_reads_in_progress_while_flying_current_when_passed_failed_when_failed() -> None:
    assert kstatus(running_run())[0] == "InProgress"
    assert kstatus(written(run_body(), summary=replicas(Verdict.PASS, Verdict.PASS)))[0] == "Current"
    failed = written(run_body(), summary=replicas(Verdict.PASS, Verdict.FAIL))
    assert kstatus(failed)[0] == "Failed"
    errors = written(run_body(), summary=replicas(Verdict.ERROR, Verdict.ERROR))
    assert kstatus(errors)[0] == "Failed"


def test_body(generation: int, status: dict[str, Any]) -> dict[str, Any]:
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": "hover", "namespace": "ci", "uid": "u", "generation": generation},
        "spec": {"replicas": 2},
        "status": status,
    }


test_body.__test__ = False  # type: ignore[attr-defined]


def test_a_test_reads_like_its_newest_run_and_in_progress_until_its_new_spec_runs() -> None:
    passed = run_view(written(run_body(), summary=replicas(Verdict.PASS, Verdict.PASS)))
    failed_body = written(run_body(), summary=replicas(Verdict.PASS, Verdict.FAIL))
    failed_body["metadata"] = {
        **failed_body["metadata"],
        "name": "hover-s1",
        "creationTimestamp": "2026-03-01T11:00:00Z",
    }
    failed = run_view(failed_body)
    flying_body = running_run()
    flying_body["metadata"] = {
        **flying_body["metadata"],
        "name": "hover-s2",
        "creationTimestamp": "2026-03-01T12:00:00Z",
    }
    flying = run_view(flying_body)

    def test_obj(generation: int, runs: list[Any]) -> dict[str, Any]:
        seen = {"observedGeneration": 1, "specHash": "x"}
        st = test_status_from(test_view(test_body(generation, seen)), runs)
        return test_body(generation, st.dump())

    assert kstatus(test_obj(1, [passed]))[0] == "Current"
    assert kstatus(test_obj(1, [passed, failed]))[0] == "Failed"
    assert kstatus(test_obj(1, [passed, failed, flying]))[0] == "InProgress"
    # a new spec not yet picked up (observedGeneration behind): InProgress, whatever the last run said
    assert kstatus(test_obj(2, [passed]))[0] == "InProgress"
