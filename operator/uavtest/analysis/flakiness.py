"""A run's summary over its replicas: counts, flakiness, overall verdict (pure).

Words from DESIGN.md: errors (the bench's fault) are never counted as failures; the valid
replicas are those that passed or failed; flakiness = failed / valid (0 always passes,
1 always fails, None when no replica is valid); a run is flaky iff 0 < flakiness < 1.
Overall verdict: ``fail`` when any valid replica failed, ``pass`` when at least one passed and
none failed, ``error`` when no replica is valid.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from uavtest.analysis.competition import SOFT_FAIL_DISTANCE
from uavtest.analysis.models import CompetitionScore, FlightMetrics, ReplicaResult, RunSummary, Stats, Verdict

__all__ = ["competition_score", "flakiness", "stats", "summarize"]


def flakiness(passed: int, failed: int) -> float | None:
    """failed / (passed + failed); None when there is no valid replica."""
    valid = passed + failed
    return failed / valid if valid else None


def stats(values: Iterable[float | None]) -> Stats | None:
    """min / mean / max of the values that are known (not None, finite); None when none is."""
    arr = np.array([v for v in values if v is not None], dtype=np.float64)
    arr = arr[np.isfinite(arr)]
    if not arr.size:
        return None
    return Stats(min=float(arr.min()), mean=float(arr.mean()), max=float(arr.max()), count=int(arr.size))


def competition_score(metrics: Iterable[FlightMetrics]) -> CompetitionScore | None:
    """Total and mean competition points over the flights that have them, with their hard fails
    (collision) and soft fails (no collision, 2-D distance below 1.5 m); None when none has points."""
    scored = [m for m in metrics if m.competition_points is not None]
    if not scored:
        return None
    total = sum(m.competition_points or 0 for m in scored)
    return CompetitionScore(
        total=total,
        mean=total / len(scored),
        count=len(scored),
        hard_fails=sum(m.collision for m in scored),
        soft_fails=sum(
            not m.collision
            and m.min_obstacle_distance_2d is not None
            and m.min_obstacle_distance_2d < SOFT_FAIL_DISTANCE
            for m in scored
        ),
    )


def summarize(results: Sequence[ReplicaResult], *, test: str, namespace: str, run_id: str) -> RunSummary:
    """Summarize the replicas of one run (``aggregate/summary.json``)."""
    ordered = sorted(results, key=lambda r: r.index)
    passed = sum(r.verdict == Verdict.PASS for r in ordered)
    failed = sum(r.verdict == Verdict.FAIL for r in ordered)
    errors = sum(r.verdict == Verdict.ERROR for r in ordered)
    f = flakiness(passed, failed)
    if failed:
        verdict = Verdict.FAIL
    elif passed:
        verdict = Verdict.PASS
    else:
        verdict = Verdict.ERROR
    valid = [r for r in ordered if r.verdict != Verdict.ERROR and r.metrics is not None]
    return RunSummary(
        test=test,
        namespace=namespace,
        run_id=run_id,
        replicas=len(ordered),
        passed=passed,
        failed=failed,
        errors=errors,
        flakiness=f,
        flaky=f is not None and 0.0 < f < 1.0,
        verdict=verdict,
        min_obstacle_distance=stats(r.metrics.min_obstacle_distance for r in valid if r.metrics),
        min_obstacle_distance_2d=stats(r.metrics.min_obstacle_distance_2d for r in valid if r.metrics),
        competition_points=competition_score(r.metrics for r in valid if r.metrics),
        flight_time=stats(r.metrics.flight_time for r in valid if r.metrics),
        warnings=list(dict.fromkeys(w for r in ordered for w in r.warnings)),
        results=list(ordered),
    )
