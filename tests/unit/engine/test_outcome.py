"""Exit codes and the printed summary of a run."""

from __future__ import annotations

import pytest
from rich.console import Console

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.engine.outcome import exit_code, results_table, summary_line
from uavtest.errors import ExitCode


def _r(i: int, verdict: Verdict, reason: str = "", dist: float | None = 2.0) -> ReplicaResult:
    metrics = None
    if verdict != Verdict.ERROR:
        metrics = FlightMetrics(flight_time=40.0 + i, min_obstacle_distance=dist)
    return ReplicaResult(index=i, seed=100 + i, verdict=verdict, reason=reason, metrics=metrics)


@pytest.mark.parametrize(
    ("verdicts", "code"),
    [
        ([Verdict.PASS, Verdict.PASS], ExitCode.PASS),
        ([Verdict.PASS, Verdict.FAIL], ExitCode.FAIL),
        ([Verdict.FAIL, Verdict.ERROR], ExitCode.FAIL),
        ([Verdict.ERROR, Verdict.ERROR], ExitCode.INFRASTRUCTURE),
        ([Verdict.PASS, Verdict.ERROR], ExitCode.INFRASTRUCTURE),  # not trustworthy: documented
    ],
)
def test_exit_code(verdicts: list[Verdict], code: ExitCode) -> None:
    summary = summarize([_r(i, v) for i, v in enumerate(verdicts)], test="t", namespace="local", run_id="r")
    assert exit_code(summary) == code


def test_table_and_summary_line_show_each_replica_and_flakiness() -> None:
    results = [
        _r(0, Verdict.PASS, dist=2.31),
        _r(1, Verdict.FAIL, "min distance 1.20 m < 1.5 m (short by 0.30 m)", dist=1.2),
        _r(2, Verdict.ERROR, "simulator exited with code 1: boom"),
    ]
    summary = summarize(results, test="near-miss", namespace="local", run_id="r1")
    console = Console(width=200, record=True, color_system=None)
    console.print(results_table(summary))
    text = console.export_text()
    assert "2.31 m" in text and "1.20 m" in text
    assert "short by 0.30 m" in text and "simulator exited with code 1: boom" in text
    assert "101" in text  # seeds are shown
    line = summary_line(summary)
    assert "1 passed · 1 failed · 1 error" in line
    assert "flakiness 0.50" in line and "flaky yes" in line


def test_the_run_output_warns_about_unmodelled_params() -> None:
    from uavtest.engine.outcome import unmodelled_line

    summary = summarize([_r(0, Verdict.PASS)], test="t", namespace="local", run_id="r")
    assert unmodelled_line(summary) is None
    summary = summary.model_copy(update={"unmodelled_params": ["EKF2_GPS_DELAY"]})
    assert unmodelled_line(summary) == (
        "warning: 1 PX4 parameter set by the test has no effect in the built-in simulator: EKF2_GPS_DELAY"
    )
