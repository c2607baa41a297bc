"""The ``uavtest`` command line: thin typer commands that delegate to the packages.

This module is the one boundary where ``UavTestError`` becomes a message and an exit code
(0 pass, 1 test failed, 2 bad input, 3 infrastructure error); no traceback reaches a user.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from uavtest.engine.entry import runner, sitl
from uavtest.errors import run_at_boundary
from uavtest.process_exit import run_then_end
from uavtest.run_options import Engine, ignored_options, ignored_warning

app = typer.Typer(
    name="uavtest",
    help="Fly system-level drone tests in simulation, N replicas in parallel.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
err = Console(stderr=True)


@app.command()
def validate(
    test: Annotated[Path, typer.Argument(help="UavTest YAML, Aerialist or competition test YAML")],
) -> None:
    """Check a test file; exit 2 with the file, field, value and what is allowed when it is wrong."""
    from uavtest.spec.cli_support import validate_command

    raise typer.Exit(validate_command(test))


@app.command()
def render(
    test: Annotated[Path, typer.Argument(help="test file to render")],
    name: Annotated[str | None, typer.Option(help="metadata.name of the rendered UavTest")] = None,
    namespace: Annotated[str | None, typer.Option(help="metadata.namespace")] = None,
) -> None:
    """Print a self-contained UavTest manifest (plan, params, commands inlined) for kubectl apply."""
    from uavtest.spec.cli_support import render_command

    raise typer.Exit(render_command(test, name=name, namespace=namespace))


@app.command()
def crd() -> None:
    """Print the CustomResourceDefinition generated from the spec models."""
    from uavtest.spec.cli_support import crd_command

    raise typer.Exit(crd_command())


@app.command()
def report(
    log: Annotated[Path, typer.Argument(help="PX4 ULog (.ulg) of one flight")],
    test: Annotated[Path | None, typer.Option(help="test file: obstacles and assertions to judge by")] = None,
    reference: Annotated[Path | None, typer.Option(help="reference ULog for DTW / Fréchet distance")] = None,
    plot: Annotated[Path | None, typer.Option(help="write a PNG plot here")] = None,
    json_out: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    """Print the metrics and the verdict of one flight log."""
    from uavtest.analysis.report import report_command

    raise typer.Exit(report_command(log, test=test, reference=reference, plot=plot, json_out=json_out))


@app.command()
def run(
    tests: Annotated[
        list[Path],
        typer.Argument(
            help="test files (UavTest, Aerialist or competition YAML) or folders of them (*.yaml, *.yml)",
            metavar="TEST",
            show_default=False,
        ),
    ],
    replicas: Annotated[int | None, typer.Option(help="how many replicas (overrides spec.replicas)")] = None,
    jobs: Annotated[
        int | None,
        typer.Option(
            help="local: replicas at once (default: number of cores); several tests fly that many "
            "side by side, sharing as many replica slots"
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(
            help="artifact folder (store layout); local default runs/. kubernetes: download the run's "
            "artifacts here (needs UAVTEST_S3_ENDPOINT, _ACCESS_KEY, _SECRET_KEY)"
        ),
    ] = None,
    seed: Annotated[int | None, typer.Option(help="base seed; replica i flies with seed + i")] = None,
    replica: Annotated[
        int | None, typer.Option(help="local: fly only replica I with its seed (seed + I): an exact replay")
    ] = None,
    engine: Annotated[
        Engine, typer.Option(help="local (this machine) or kubernetes (the cluster)", case_sensitive=False)
    ] = Engine.LOCAL,
    namespace: Annotated[str | None, typer.Option(help="kubernetes: namespace of the UavTest")] = None,
    wait: Annotated[
        bool | None, typer.Option(help="kubernetes: wait until the run is final (default: wait)")
    ] = None,
    timeout: Annotated[
        float | None,
        typer.Option(help="kubernetes: seconds to wait for the final status; then exit 3, the test runs on"),
    ] = None,
    json_out: Annotated[
        bool,
        typer.Option("--json", help="print the RunSummary as JSON (several tests: a list of them)"),
    ] = False,
    junit: Annotated[
        Path | None,
        typer.Option(help="write a JUnit XML report here: a suite per test, a case per replica"),
    ] = None,
) -> None:
    """Fly tests' replicas in simulation and report verdicts, flakiness and the averaged trajectory.

    Exit codes: 0 every replica passed; 1 any replica failed; 2 bad input; 3 bench errors and no
    failure — also when some replicas passed and others errored, since the run cannot vouch for
    the test then. Errored replicas are retried twice with the same seed first.

    Artifacts: OUT/local/<test>/<run-id>/replica-<i>/ and .../aggregate/. Environment:
    UAVTEST_PX4_BIN (PX4 SITL binary for vehicle.simulator px4), UAVTEST_LAUNCH=fork|exec,
    UAVTEST_PYCACHE=off|DIR (bytecode of replica processes started cold, see the README).

    --engine kubernetes creates a new UavTest and follows its status (same exit codes); --out then
    downloads the run's artifacts to OUT/<namespace>/<test>/<run-id>/ with the operator's S3
    settings (checked before anything is created: exit 2 without them). A download that fails
    after the run makes a passing run exit 3; a failing run still exits 1. --timeout running out
    exits 3 and leaves the UavTest running.

    Several tests (files, or a folder's *.yaml / *.yml): all are checked first (a wrong one: exit 2,
    nothing flies), then flown side by side, --jobs at a time sharing as many replica slots (one
    after the other with a PX4 test among them; kubernetes: all created, then followed
    together); one table, one exit code: 1 if any test failed, else 2 if any was bad input, else 3
    if any had bench errors, else 0. --junit FILE writes JUnit XML, one suite per test and a case
    per replica (also aggregate/junit.xml in the store); --json prints a list then.
    """
    given = {
        "--jobs": jobs,
        "--replica": replica,
        "--namespace": namespace,
        "--wait": wait,
        "--timeout": timeout,
        "--out": out,
        "--json": json_out or None,
        "--junit": junit,
    }
    waits = wait is not False
    warning = ignored_warning(engine, ignored_options(engine, given, wait=waits), wait=waits)
    if warning:
        err.print(f"[yellow]warning:[/] {warning}", highlight=False, soft_wrap=True)
    from uavtest.run_many import check_junit_path, expand_tests

    files = expand_tests(tests)
    if junit is not None:
        check_junit_path(junit)
    if engine is Engine.KUBERNETES:
        from uavtest.controller.cluster_run import ClusterRunOptions, run_in_cluster

        options = ClusterRunOptions(
            files,
            namespace=namespace,
            wait=waits,
            replicas=replicas,
            seed=seed,
            out=out if waits else None,
            json_out=json_out and waits,
            timeout=timeout if waits else None,
            junit=junit if waits else None,
        )
        raise typer.Exit(run_in_cluster(options))
    from uavtest.engine import run_command

    raise typer.Exit(
        run_command(
            files,
            replicas=replicas,
            jobs=jobs,
            out=out if out is not None else Path("runs"),
            seed=seed,
            replica=replica,
            json_out=json_out,
            junit=junit,
        )
    )


@app.command(name="operator")
def operator_(
    namespace: Annotated[
        list[str] | None, typer.Option("--namespace", "-n", help="namespace to watch (repeat); default all")
    ] = None,
    metrics_port: Annotated[
        int | None, typer.Option(help="/metrics port (default: UAVTEST_OPERATOR_METRICS_PORT or 8080)")
    ] = None,
    liveness_port: Annotated[int | None, typer.Option(help="serve a liveness probe at :PORT/healthz")] = None,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="log every handler step")] = False,
) -> None:
    """Run the Kubernetes operator: UavTest → Indexed Job of replicas → status, Events, metrics."""
    from uavtest.controller.main import run_operator

    run_operator(
        namespaces=namespace or (), metrics_port=metrics_port, liveness_port=liveness_port, verbose=verbose
    )


app.command()(runner)
app.command()(sitl)


def main() -> None:
    """Entry point: run the app, translate known errors to messages and exit codes."""

    def say(text: str) -> None:
        head, _, rest = text.partition(": ")
        err.print(f"[bold red]{head}:[/] {rest}" if rest else text, highlight=False, soft_wrap=True)

    run_at_boundary(lambda: app(standalone_mode=True), say)


def script() -> None:
    """The ``uavtest`` console script: ``main``, then the process ends without the interpreter's
    teardown (``uavtest.process_exit``: ~0.45 s of a ``uavtest run`` on a 2-core machine)."""
    run_then_end(main)


if __name__ == "__main__":
    script()
