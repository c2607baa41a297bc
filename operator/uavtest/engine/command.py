"""``uavtest run`` with the local engine: fly each test, then print its table, summary and paths.

Several tests (``uavtest run tests/``) are all read and checked first — a wrong file exits 2
before anything flies — then flown side by side, up to ``--jobs`` at once with their replicas
sharing as many slots (``side_by_side``; one after the other with a PX4 test among them), with
one table over the tests and one exit code (``uavtest.run_many``).
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console

from uavtest.errors import BadInput, UavTestError
from uavtest.spec.models import Simulator

if TYPE_CHECKING:
    from uavtest.engine.local import LocalRun
    from uavtest.engine.side_by_side import Shared
    from uavtest.spec.models import UavTest

__all__ = ["run_command"]


def _print_run(stdout: Console, run: LocalRun) -> None:
    from uavtest.engine.outcome import results_table, summary_line, unmodelled_line

    summary = run.summary
    stdout.print(results_table(summary))
    stdout.print(summary_line(summary), highlight=False)
    warning = unmodelled_line(summary)
    if warning:
        stdout.print(warning, highlight=False)
    for w in summary.warnings:
        stdout.print(f"warning: {w}", highlight=False)
    stdout.print(f"summary: {run.summary_path}", highlight=False)
    if run.plot_path is not None:
        stdout.print(f"plot:    {run.plot_path}", highlight=False)


def _preflight_all(tests: list[Path], err: Console) -> dict[Path, UavTest]:
    """Each file's test; every wrong file said on stderr, then BadInput (nothing flies)."""
    from uavtest.engine.local import preflight

    checked: dict[Path, UavTest] = {}
    wrong: list[str] = []
    for path in tests:
        try:
            checked[path] = preflight(path)
        except BadInput as e:
            wrong.append(str(path))
            if len(tests) > 1:
                err.print(f"[bold red]error:[/] {e}", highlight=False, soft_wrap=True)
            else:
                raise
    if wrong:
        raise BadInput(
            f"{len(wrong)} of {len(tests)} test files are wrong (above); nothing was flown",
            value=", ".join(wrong),
        )
    return checked


def side_by_side_width(tests: dict[Path, UavTest], jobs: int | None, cores: int) -> int:
    """How many of these tests fly at once: up to ``--jobs`` (default the cores), 1 with a PX4
    test among them (its speed factor is chosen for one test's replicas) or a single test."""
    if len(tests) < 2 or any(t.spec.vehicle.simulator == Simulator.PX4 for t in tests.values()):
        return 1
    return max(1, min(jobs if jobs is not None else cores, len(tests)))


def run_command(
    tests: list[Path],
    *,
    replicas: int | None = None,
    jobs: int | None = None,
    out: Path = Path("runs"),
    seed: int | None = None,
    replica: int | None = None,
    json_out: bool = False,
    junit: Path | None = None,
) -> int:
    """Run the tests locally and report them; returns the exit code (``uavtest.run_many``)."""
    from uavtest.engine.aggregate import artifact_links
    from uavtest.engine.local import NAMESPACE, RunOptions, run_local
    from uavtest.engine.outcome import exit_code
    from uavtest.engine.side_by_side import fly_side_by_side
    from uavtest.engine.speed import available_cores
    from uavtest.run_many import (
        TestOutcome,
        combined_exit,
        exit_meaning,
        json_report,
        junit_report,
        suite_table,
        write_junit,
    )
    from uavtest.store import LocalStore

    err = Console(stderr=True)
    stdout = Console(soft_wrap=True)
    checked = _preflight_all(tests, err)
    several = len(tests) > 1
    width = side_by_side_width(checked, jobs, available_cores())

    def heading(item: tuple[int, Path]) -> None:
        n, test = item
        err.rule(f"test {n}/{len(tests)}: {test}", align="left")

    def fly(item: tuple[int, Path], shared: Shared | None) -> TestOutcome:
        n, test = item
        if several and shared is None:
            heading(item)
        options = RunOptions(
            test=test, replicas=replicas, jobs=jobs, out=out, seed=seed, replica=replica, warm=several
        )
        try:
            run = run_local(options, console=err, shared=shared)
        except UavTestError as e:
            # one test: as always, the error and its exit code (with --junit, a bench error is
            # reported first); several: said, recorded, and the next test flies
            if not several and (junit is None or isinstance(e, BadInput)):
                raise
            err.print(f"[bold red]error:[/] {test}: {e}", highlight=False, soft_wrap=True)
            return TestOutcome(
                test, checked[test].metadata.name, int(e.exit_code), message=str(e), namespace=NAMESPACE
            )
        s = run.summary
        links = artifact_links(LocalStore(out), NAMESPACE, s.test, s.run_id, (r.index for r in s.results))
        with shared.output if shared is not None else contextlib.nullcontext():
            if shared is not None:  # side by side: which test this block is
                err.rule(f"test {n}/{len(tests)} done: {test}", align="left")
            if not json_out:
                _print_run(stdout, run)
        return TestOutcome(test, s.test, int(exit_code(s)), s, namespace=NAMESPACE, links=links)

    items = list(enumerate(tests, 1))
    if width > 1:
        err.print(
            f"{len(tests)} tests, {width} at a time (their replicas share {width} slots)", highlight=False
        )
        outcomes = fly_side_by_side(items, width, fly, start=heading)
    else:
        outcomes = [fly(item, None) for item in items]
    if junit is not None:
        write_junit(junit, junit_report(outcomes), err)
    if json_out:
        print(json_report(outcomes))
    elif several:
        stdout.print(suite_table(outcomes))
    code = combined_exit(o.code for o in outcomes)
    if several and not json_out:
        stdout.print(f"exit {int(code)}: {exit_meaning(code)}", highlight=False)
    return int(code)
