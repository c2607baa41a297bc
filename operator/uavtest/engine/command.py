"""``uavtest run`` with the local engine: fly, then print the table, the summary and the paths."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

__all__ = ["run_command"]


def run_command(
    test: Path,
    *,
    replicas: int | None = None,
    jobs: int | None = None,
    out: Path = Path("runs"),
    seed: int | None = None,
    replica: int | None = None,
    json_out: bool = False,
) -> int:
    """Run a test locally and report it; returns the exit code (see ``uavtest.engine.outcome``)."""
    from uavtest.engine.local import RunOptions, run_local
    from uavtest.engine.outcome import exit_code, results_table, summary_line, unmodelled_line

    err = Console(stderr=True)
    options = RunOptions(test=test, replicas=replicas, jobs=jobs, out=out, seed=seed, replica=replica)
    run = run_local(options, console=err)
    summary = run.summary
    if json_out:
        print(summary.model_dump_json(indent=2))
    else:
        stdout = Console(soft_wrap=True)
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
    return int(exit_code(summary))
