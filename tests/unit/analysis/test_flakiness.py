"""Run summary: flakiness and overall verdict per DESIGN.md's words."""

from __future__ import annotations

import pytest

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict

P, F, E = Verdict.PASS, Verdict.FAIL, Verdict.ERROR


def results(*verdicts: Verdict) -> list[ReplicaResult]:
    return [
        ReplicaResult(
            index=i,
            seed=100 + i,
            verdict=v,
            reason="" if v == P else "x",
            metrics=None if v == E else FlightMetrics(flight_time=40.0 + i, min_obstacle_distance=1.0 + i),
        )
        for i, v in enumerate(verdicts)
    ]


@pytest.mark.parametrize(
    ("verdicts", "flakiness", "flaky", "overall"),
    [
        ((P, P, P), 0.0, False, P),
        ((F, F), 1.0, False, F),
        ((P, P, F), 1 / 3, True, F),
        ((P, E, E), 0.0, False, P),  # errors are never failures
        ((F, E), 1.0, False, F),
        ((E, E), None, False, E),  # no valid replica
        ((P, F, E, E), 0.5, True, F),
    ],
)
def test_flakiness_and_verdict(
    verdicts: tuple[Verdict, ...], flakiness: float | None, flaky: bool, overall: Verdict
) -> None:
    s = summarize(results(*verdicts), test="hover", namespace="local", run_id="r1")
    assert s.flakiness == (pytest.approx(flakiness) if flakiness is not None else None)
    assert s.flaky is flaky
    assert s.verdict == overall
    assert (s.passed, s.failed, s.errors, s.replicas) == (
        verdicts.count(P),
        verdicts.count(F),
        verdicts.count(E),
        len(verdicts),
    )


def test_stats_cover_valid_replicas_only() -> None:
    s = summarize(results(E, P, F), test="t", namespace="local", run_id="r")
    assert s.flight_time is not None and s.min_obstacle_distance is not None
    assert (s.flight_time.min, s.flight_time.mean, s.flight_time.max, s.flight_time.count) == (
        41.0,
        41.5,
        42.0,
        2,
    )
    assert s.min_obstacle_distance.min == 2.0
    assert [r.index for r in s.results] == [0, 1, 2]
    assert summarize(results(E), test="t", namespace="local", run_id="r").flight_time is None


def test_summary_json_round_trips() -> None:
    s = summarize(results(P, F, E), test="t", namespace="ns", run_id="r")
    assert type(s).model_validate_json(s.model_dump_json()) == s
