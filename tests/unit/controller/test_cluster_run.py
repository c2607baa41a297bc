"""`uavtest run --engine kubernetes`: exit codes and progress from a UavTest's status (pure parts)."""

from __future__ import annotations

import pytest

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.controller.cluster_run import exit_code_for, progress_text
from uavtest.controller.reconcile import parse_test
from uavtest.controller.status import status_from
from uavtest.controller.views import job_view, pod_view, uavtest_view
from uavtest.errors import BadInput, ExitCode

from .controller_bodies import job_body, pod_body, uavtest_body


def final(*verdicts: Verdict) -> dict[str, object]:
    results = [
        ReplicaResult(
            index=i,
            seed=i,
            verdict=v,
            metrics=None if v == Verdict.ERROR else FlightMetrics(min_obstacle_distance=2),
        )
        for i, v in enumerate(verdicts)
    ]
    summary = summarize(results, test="hover", namespace="team-a", run_id="5f0c3a9e")
    test = uavtest_view(uavtest_body(replicas=len(verdicts)))
    return status_from(test, None, [], store_url="s3://b", summary=summary).dump()


@pytest.mark.parametrize(
    ("verdicts", "code"),
    [
        ((Verdict.PASS, Verdict.PASS), ExitCode.PASS),
        ((Verdict.PASS, Verdict.FAIL), ExitCode.FAIL),
        ((Verdict.FAIL, Verdict.ERROR), ExitCode.FAIL),
        ((Verdict.PASS, Verdict.ERROR), ExitCode.INFRASTRUCTURE),
        ((Verdict.ERROR, Verdict.ERROR), ExitCode.INFRASTRUCTURE),
    ],
)
def test_exit_codes_match_the_local_engine(verdicts: tuple[Verdict, ...], code: ExitCode) -> None:
    assert exit_code_for(final(*verdicts)) == code


def test_a_spec_the_cluster_cannot_run_exits_as_bad_input() -> None:
    status = {
        "phase": "Error",
        "conditions": [{"type": "Complete", "status": "True", "reason": "InvalidSpec", "message": "x"}],
    }
    assert exit_code_for(status) == ExitCode.BAD_INPUT


def test_progress_line_counts_replicas() -> None:
    test = uavtest_view(uavtest_body(replicas=4))
    pods = [pod_view(pod_body(0, "Running")), pod_view(pod_body(1, "Succeeded", exit_code=0))]
    st = status_from(
        test, job_view(job_body(completed="1", active=1)), [p for p in pods if p], store_url="s3://b"
    ).dump()
    assert progress_text(st) == "Running · 1 passed · 0 failed · 0 error · 1 running · 2 pending"


def test_a_body_that_does_not_fit_the_model_names_the_field() -> None:
    with pytest.raises(BadInput, match=r"spec\.replicas"):
        parse_test(uavtest_body(replicas=0))
