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

from uavtest.analysis.models import ReplicaResult, RunSummary, Stats, Verdict

__all__ = ["flakiness", "stats", "summarize"]


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
        flight_time=stats(r.metrics.flight_time for r in valid if r.metrics),
        warnings=list(dict.fromkeys(w for r in ordered for w in r.warnings)),
        results=list(ordered),
    )
