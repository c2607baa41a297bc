"""The ``uavtest`` command line: thin typer commands that delegate to the packages.

This module is the one boundary where ``UavTestError`` becomes a message and an exit code
(0 pass, 1 test failed, 2 bad input, 3 infrastructure error); no traceback reaches a user.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from uavtest.errors import ExitCode, UavTestError

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


def main() -> None:
    """Entry point: run the app, translate known errors to messages and exit codes."""
    try:
        app(standalone_mode=True)
    except UavTestError as e:
        err.print(f"[bold red]error:[/] {e}", highlight=False, soft_wrap=True)
        sys.exit(int(e.exit_code))
    except KeyboardInterrupt:
        err.print("interrupted")
        sys.exit(int(ExitCode.INFRASTRUCTURE))


if __name__ == "__main__":
    main()
