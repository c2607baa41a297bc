"""How a finished run is shown and what it exits with: pure functions of a ``RunSummary``.

Exit codes of ``uavtest run``:
  0  every replica passed;
  1  at least one replica failed (an assertion did not hold), whatever else happened;
  3  bench errors and no failure — including a mix of passes and errors: an errored replica
     is a flight that did not happen, so the run cannot vouch for the test;
  2  bad input (raised before any replica flies).
"""

from __future__ import annotations

from rich.table import Table

from uavtest.analysis.models import ReplicaResult, RunSummary, Stats, Verdict
from uavtest.errors import ExitCode

__all__ = ["exit_code", "results_table", "run_warnings", "summary_line", "unmodelled_line"]

_STYLE = {Verdict.PASS: "green", Verdict.FAIL: "red", Verdict.ERROR: "yellow"}


def exit_code(summary: RunSummary) -> ExitCode:
    """0 all passed, 1 any failed, 3 errors without failures (see the module doc)."""
    if summary.failed > 0:
        return ExitCode.FAIL
    if summary.errors > 0 or summary.passed == 0:
        return ExitCode.INFRASTRUCTURE
    return ExitCode.PASS


def _metres(v: float | None) -> str:
    return "-" if v is None else f"{v:.2f} m"


def _seconds(v: float | None) -> str:
    return "-" if v is None else f"{v:.1f} s"


def _points(v: int | None) -> str:
    return "-" if v is None else str(v)


def _row(r: ReplicaResult) -> list[str]:
    m = r.metrics
    verdict = f"[{_STYLE[r.verdict]}]{r.verdict.value}[/]"
    if r.attempts > 1:
        verdict += f" ({r.attempts} attempts)"
    return [
        str(r.index),
        str(r.seed),
        verdict,
        _metres(m.min_obstacle_distance if m else None),
        _metres(m.min_obstacle_distance_2d if m else None),
        _points(m.competition_points if m else None),
        _seconds(m.flight_time if m else None),
        r.reason,
    ]


def results_table(summary: RunSummary) -> Table:
    """One row per replica: replica, seed, verdict, min distance (3-D), the competition's 2-D
    distance and points, flight time, reason."""
    table = Table(title=f"{summary.test} · run {summary.run_id}", title_justify="left")
    for name, justify in (
        ("replica", "right"),
        ("seed", "right"),
        ("verdict", "left"),
        ("3-D distance", "right"),
        ("2-D distance", "right"),
        ("points", "right"),
        ("flight time", "right"),
        ("reason", "left"),
    ):
        table.add_column(name, justify=justify, overflow="fold")  # type: ignore[arg-type]
    for r in sorted(summary.results, key=lambda r: r.index):
        table.add_row(*_row(r))
    return table


def _stats(name: str, s: Stats | None, unit: str) -> str:
    return "" if s is None else f" · {name} {s.min:.2f}/{s.mean:.2f}/{s.max:.2f} {unit} (min/mean/max)"


def _score(summary: RunSummary) -> str:
    s = summary.competition_points
    if s is None:
        return ""
    return (
        f" · competition points {s.total} ({s.mean:.2f} per replica over {s.count}; "
        f"{s.hard_fails} hard fail, {s.soft_fails} soft fail)"
    )


def summary_line(summary: RunSummary) -> str:
    """passed, failed, error, flakiness, flaky yes/no (and min distance stats and the
    competition's points when known)."""
    flakiness = "n/a" if summary.flakiness is None else f"{summary.flakiness:.2f}"
    return (
        f"{summary.passed} passed · {summary.failed} failed · {summary.errors} error · "
        f"flakiness {flakiness} · flaky {'yes' if summary.flaky else 'no'}"
        + _stats("min distance", summary.min_obstacle_distance, "m")
        + _score(summary)
    )


def unmodelled_line(summary: RunSummary) -> str | None:
    """A warning naming the test's PX4 parameters the built-in simulator ignores (None if none)."""
    from uavtest.spec.px4_params import unmodelled_notice

    notice = unmodelled_notice(summary.unmodelled_params)
    return f"warning: {notice}" if notice else None


def run_warnings(summary: RunSummary) -> list[str]:
    """What the run could not simulate, each once: the simulator's limits (e.g. PX4 SIH has no
    obstacles and no wind) and the PX4 parameters the built-in simulator ignores."""
    from uavtest.spec.px4_params import unmodelled_notice

    notice = unmodelled_notice(summary.unmodelled_params)
    return list(dict.fromkeys([*summary.warnings, *([notice] if notice else [])]))
