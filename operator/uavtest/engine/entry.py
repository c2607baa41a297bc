"""The replica processes' own entry point: ``python -m uavtest.engine.entry runner|sitl ...``.

The engine starts a replica's simulator and runner with this module, not with ``uavtest.cli``
(the engine knows nothing of the user's command line); ``uavtest runner`` and ``uavtest sitl``
are the same two commands, registered on the CLI from here. Like ``uavtest.cli.main``, ``main``
turns a ``UavTestError`` into a message and its exit code (0 pass, 1 fail, 2 bad input, 3 bench
error), never a traceback.
"""

from __future__ import annotations

import functools
import logging
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

from uavtest.errors import run_at_boundary
from uavtest.process_exit import exit_status, flush_and_exit

__all__ = ["app", "command", "main", "runner", "sitl"]

app = typer.Typer(
    name="uavtest-replica",
    help="A replica's processes: the runner and the built-in simulator.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


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
        Path | None,
        typer.Option(
            help="where the simulator writes its .ulg (else, or when it holds none after the flight: "
            "MAVLink log download)"
        ),
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
    gcs_quiet: Annotated[
        bool,
        typer.Option(
            "--gcs-quiet",
            help="the GCS link streams telemetry only once a ground station has spoken on it "
            "(PX4 SITL streams from boot; the engine's parallel replicas use this)",
        ),
    ] = False,
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
            gcs_quiet=gcs_quiet,
            log_dir=log_dir,
            lockstep=lockstep,
            speed_factor=speed_factor,
            idle_exit_s=idle_exit,
        )
    )


app.command()(runner)
app.command()(sitl)


@functools.cache
def command() -> Callable[..., Any]:
    """The replica command line as a click command, built once: typer builds it from the
    functions' signatures at every call of ``app``; the fork server builds it before forking
    (``uavtest.engine.prefork``)."""
    return typer.main.get_command(app)


def main() -> None:
    """Entry point: run the command, translate known errors to a message and an exit code.

    The process then ends without the interpreter's teardown (numpy, pydantic, pymavlink: tens of
    milliseconds on a replica's clock): by then the command has closed its files and stored or
    printed its result, and only the standard streams and the log handlers are left to flush.
    """
    try:
        run_at_boundary(lambda: command()(standalone_mode=True), lambda text: print(text, file=sys.stderr))
        code = 0
    except SystemExit as e:
        code = exit_status(e.code)
    logging.shutdown()
    flush_and_exit(code)


if __name__ == "__main__":
    main()
