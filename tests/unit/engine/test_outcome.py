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


def test_table_and_summary_line_show_the_competition_points() -> None:
    def scored(i: int, d2: float, points: int, collision: bool = False) -> ReplicaResult:
        metrics = FlightMetrics(
            flight_time=40.0,
            min_obstacle_distance=d2 + 0.1,
            min_obstacle_distance_2d=d2,
            competition_points=points,
            collision=collision,
        )
        return ReplicaResult(index=i, seed=i, verdict=Verdict.FAIL, reason="soft fail: ...", metrics=metrics)

    summary = summarize(
        [scored(0, 0.1, 5, collision=True), scored(1, 1.23, 1), _r(2, Verdict.ERROR, "boom")],
        test="gap",
        namespace="local",
        run_id="r",
    )
    console = Console(width=200, record=True, color_system=None)
    console.print(results_table(summary))
    text = console.export_text()
    assert "2-D distance" in text and "points" in text
    row = next(line for line in text.splitlines() if "1.23 m" in line)
    assert "1.33 m" in row and " 1 " in row  # 3-D, 2-D and its 1 point on the replica's row
    line = summary_line(summary)
    assert "competition points 6 (3.00 per replica over 2; 1 hard fail, 1 soft fail)" in line
    assert "competition" not in summary_line(
        summarize([_r(0, Verdict.PASS)], test="t", namespace="l", run_id="r")
    )
