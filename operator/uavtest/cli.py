"""The ``uavtest`` command line: thin typer commands that delegate to the packages.

This module is the one boundary where ``UavTestError`` becomes a message and an exit code
(0 pass, 1 test failed, 2 bad input, 3 infrastructure error); no traceback reaches a user.
"""

from __future__ import annotations

import logging
import os
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


@app.command()
def run(
    test: Annotated[Path, typer.Argument(help="UavTest YAML, Aerialist or competition test YAML")],
    replicas: Annotated[int | None, typer.Option(help="how many replicas (overrides spec.replicas)")] = None,
    jobs: Annotated[int | None, typer.Option(help="replicas at once (default: number of cores)")] = None,
    out: Annotated[Path, typer.Option(help="local artifact folder (store layout)")] = Path("runs"),
    seed: Annotated[int | None, typer.Option(help="base seed; replica i flies with seed + i")] = None,
    replica: Annotated[
        int | None, typer.Option(help="fly only replica I with its seed (seed + I): an exact replay")
    ] = None,
    engine: Annotated[str, typer.Option(help="local (this machine) or kubernetes (the cluster)")] = "local",
    namespace: Annotated[str | None, typer.Option(help="kubernetes: namespace of the UavTest")] = None,
    wait: Annotated[bool, typer.Option(help="kubernetes: wait until the run is final")] = True,
    json_out: Annotated[bool, typer.Option("--json", help="print the RunSummary as JSON")] = False,
) -> None:
    """Fly a test's replicas in simulation and report verdicts, flakiness and the averaged trajectory.

    Exit codes: 0 every replica passed; 1 any replica failed; 2 bad input; 3 bench errors and no
    failure — also when some replicas passed and others errored, since the run cannot vouch for
    the test then. Errored replicas are retried twice with the same seed first.

    Artifacts: OUT/local/<test>/<run-id>/replica-<i>/ and .../aggregate/. Environment:
    UAVTEST_PX4_BIN (PX4 SITL binary for vehicle.simulator px4), UAVTEST_LAUNCH=fork|exec.
    """
    if engine == "kubernetes":
        from uavtest.controller.cluster_run import run_in_cluster

        raise typer.Exit(run_in_cluster(test, namespace=namespace, wait=wait))
    if engine != "local":
        from uavtest.errors import BadInput

        raise BadInput("unknown engine", field="--engine", value=engine, allowed="local, kubernetes")
    from uavtest.engine import run_command

    raise typer.Exit(
        run_command(
            test, replicas=replicas, jobs=jobs, out=out, seed=seed, replica=replica, json_out=json_out
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


@app.command()
def runner(
    test: Annotated[Path, typer.Option(help="test file (native, rendered manifest or Aerialist YAML)")],
    store: Annotated[
        str, typer.Option(help="artifact store: DIR, file:///DIR, s3://BUCKET or s3://BUCKET/PREFIX")
    ],
    run_id: Annotated[str, typer.Option(help="run id: the store folder of this run")],
    replica: Annotated[int, typer.Option(help="replica index")] = 0,
    seed: Annotated[int | None, typer.Option(help="seed (recorded; default spec seed + replica)")] = None,
    connect: Annotated[str, typer.Option(help="MAVLink endpoint to listen on")] = "udpin:127.0.0.1:14540",
    namespace: Annotated[str, typer.Option(help="store namespace")] = "local",
    test_name: Annotated[
        str | None, typer.Option(help="test name in the store (default: metadata.name)")
    ] = None,
    log_dir: Annotated[
        Path | None, typer.Option(help="where the simulator writes its .ulg (else: MAVLink log download)")
    ] = None,
    timeout: Annotated[float | None, typer.Option(help="vehicle seconds the flight may take")] = None,
    connect_timeout: Annotated[float, typer.Option(help="wall seconds to wait for a heartbeat")] = 30.0,
    step_ms: Annotated[
        int,
        typer.Option(
            help="largest lockstep grant, vehicle milliseconds (shorter ones while commands run, "
            "sticks stream or an obstacle is near)"
        ),
    ] = 1000,
    arm_settle: Annotated[
        float | None,
        typer.Option(
            help="vehicle seconds the vehicle must have reported ready-to-arm (SYS_STATUS pre-arm "
            "check) before the runner arms it; default 10 for vehicle.simulator px4, else 0"
        ),
    ] = None,
) -> None:
    """Fly one replica against a MAVLink vehicle; store flight.ulg, trajectory.csv, result.json."""
    from uavtest.runner.main import run_replica_command

    raise typer.Exit(
        run_replica_command(
            test,
            replica=replica,
            seed=seed,
            connect=connect,
            store=store,
            run_id=run_id,
            namespace=namespace,
            test_name=test_name,
            log_dir=log_dir,
            timeout=timeout,
            connect_timeout=connect_timeout,
            step_ms=step_ms,
            arm_settle=arm_settle,
        )
    )


@app.command()
def sitl(
    test: Annotated[
        Path | None, typer.Option(help="test file: world (home, obstacles, wind) and vehicle params")
    ] = None,
    seed: Annotated[int, typer.Option(help="seed of noise, gusts and variations")] = 0,
    host: Annotated[str, typer.Option(help="address the MAVLink links send to")] = "127.0.0.1",
    api_port: Annotated[int, typer.Option(help="API/offboard link: the client's port")] = 14540,
    gcs_port: Annotated[int, typer.Option(help="ground station link: the client's port")] = 14550,
    api_local_port: Annotated[
        int | None, typer.Option(help="local port of the API link (default api-port + 40; 0 = any)")
    ] = None,
    gcs_local_port: Annotated[int, typer.Option(help="local port of the GCS link (0 = any)")] = 18570,
    log_dir: Annotated[Path, typer.Option(help="where flight logs (.ulg) are written")] = Path("log"),
    lockstep: Annotated[
        bool, typer.Option("--lockstep", help="advance the clock only when a client grants time")
    ] = False,
    speed_factor: Annotated[float, typer.Option(help="free-running speed, 1 = real time")] = 1.0,
    idle_exit: Annotated[
        float,
        typer.Option(
            help="lockstep: exit (log closed) after this many wall seconds without client traffic "
            "once a client was heard (0 = never); also exits when the parent process dies"
        ),
    ] = 60.0,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="log to stderr")] = False,
) -> None:
    """Run the built-in PX4-compatible simulator (MAVLink 2 over UDP) until SIGTERM."""
    import logging

    from uavtest.sitl.main import run_sitl

    if verbose:
        logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    raise typer.Exit(
        run_sitl(
            test,
            seed=seed,
            host=host,
            api_port=api_port,
            gcs_port=gcs_port,
            api_local_port=api_local_port,
            gcs_local_port=gcs_local_port,
            log_dir=log_dir,
            lockstep=lockstep,
            speed_factor=speed_factor,
            idle_exit_s=idle_exit,
        )
    )


def main() -> None:
    """Entry point: run the app, translate known errors to messages and exit codes."""
    logging.basicConfig(
        level=os.environ.get("UAVTEST_LOG_LEVEL", "INFO").upper(),
        format="%(levelname)s: %(message)s",
        stream=sys.stderr,
    )
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
