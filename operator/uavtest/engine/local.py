"""The local engine: N replicas of a test, J at a time, on this machine; then aggregation.

Artifacts go to a ``LocalStore`` under ``--out`` with the object-store layout (namespace
``local``): ``local/<test>/<run-id>/replica-<i>/...`` and ``.../aggregate/...``.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import secrets
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field
from pydantic_settings import BaseSettings, SettingsConfigDict
from rich.console import Console, Group, RenderableType
from rich.live import Live
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from uavtest.analysis.models import ReplicaResult, RunSummary
from uavtest.engine.bytecode import replica_environ
from uavtest.engine.launch import ExecLauncher, Launcher, WarmLauncher
from uavtest.engine.ports import PX4_MAX_INSTANCES
from uavtest.engine.replica import DEFAULT_RETRIES, ReplicaJob, run_replica
from uavtest.engine.side_by_side import Shared
from uavtest.engine.speed import (
    available_cores,
    px4_speed_choice,
    speed_factor_notice,
    wall_timeout,
)
from uavtest.errors import BadInput
from uavtest.spec.aerialist import upstream_simulator_notice
from uavtest.spec.models import Simulator, UavTest
from uavtest.spec.px4_params import unmodelled_notice, unmodelled_params
from uavtest.store import ArtifactStore
from uavtest.store.layout import aggregate_key, replica_prefix, run_prefix

__all__ = [
    "NAMESPACE",
    "EngineSettings",
    "LocalRun",
    "RunOptions",
    "aerialist_simulator_notice",
    "new_run_id",
    "preflight",
    "run_local",
    "wait_for_first_line",
]

NAMESPACE = "local"
_AERIALIST_SIMULATORS = {"ros", "gazebo", "jmavsim"}


class EngineSettings(BaseSettings):
    """Environment of the local engine.

    ``UAVTEST_PX4_BIN`` names a PX4 SITL binary (for ``vehicle.simulator: px4``);
    ``UAVTEST_LAUNCH`` is ``fork`` (default: with several replicas, or several tests in one
    ``uavtest run``, their processes are forked from a warm fork server, no import cost per
    process) or ``exec`` (each process started from scratch; always so for a single replica of a
    single test and for PX4).
    """

    model_config = SettingsConfigDict(env_prefix="UAVTEST_", extra="ignore")

    px4_bin: Path | None = None
    launch: Literal["fork", "exec"] = "fork"


class RunOptions(BaseModel):
    """``uavtest run`` options for the local engine."""

    model_config = ConfigDict(frozen=True)

    test: Path
    replicas: int | None = Field(None, description="overrides spec.replicas")
    jobs: int | None = Field(None, description="replicas at once; default spec.parallelism or cores")
    out: Path = Path("runs")
    seed: int | None = Field(None, description="base seed; overrides spec.seed")
    replica: int | None = Field(None, description="fly only this replica (a replay)")
    retries: int = Field(DEFAULT_RETRIES, ge=0)
    warm: bool = Field(
        False,
        description="fork even a single replica from the warm server: more runs follow in this process",
    )


@dataclass(slots=True)
class LocalRun:
    """A finished local run: its summary and where its artifacts are."""

    summary: RunSummary
    run_dir: Path
    summary_path: Path
    plot_path: Path | None
    notices: list[str] = field(default_factory=list)


def new_run_id(now: datetime | None = None) -> str:
    """A run id: UTC timestamp plus a short random suffix, e.g. ``20250101-120000-a1b2``."""
    now = now or datetime.now(UTC)
    return f"{now:%Y%m%d-%H%M%S}-{secrets.token_hex(2)}"


def aerialist_simulator_notice(path: Path) -> str | None:
    """A notice when an Aerialist / competition file names a simulator we replace by builtin."""
    try:
        raw: Any = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return None  # load_test has already reported what is wrong with the file
    if not isinstance(raw, dict) or raw.get("kind") == "UavTest":
        return None
    simulation = raw.get("simulation")
    simulator = simulation.get("simulator") if isinstance(simulation, dict) else None
    if isinstance(simulator, str) and simulator.strip().lower() in _AERIALIST_SIMULATORS:
        name = simulator.strip()
        return f"{path.name} asks for the '{name}' simulator; {upstream_simulator_notice(name.lower())}"
    return None


def _bad(field_name: str, message: str, value: object, allowed: str) -> BadInput:
    return BadInput(message, field=field_name, value=value, allowed=allowed)


def _px4_bin(test: UavTest, settings: EngineSettings, source: Path) -> Path | None:
    if test.spec.vehicle.simulator != Simulator.PX4:
        return None
    path = settings.px4_bin
    if path is None:
        raise BadInput(
            "vehicle.simulator px4 needs a PX4 SITL binary: set UAVTEST_PX4_BIN "
            "(e.g. PX4-Autopilot/build/px4_sitl_default/bin/px4), or use simulator: builtin",
            file=str(source),
            field="spec.vehicle.simulator",
            value="px4",
        )
    if not (path.is_file() and os.access(path, os.X_OK)):
        raise BadInput(
            "UAVTEST_PX4_BIN does not name an executable file",
            field="UAVTEST_PX4_BIN",
            value=str(path),
            allowed="the path of PX4's bin/px4 from a px4_sitl build",
        )
    return path


def preflight(path: Path) -> UavTest:
    """Read and check a test file as ``run_local`` does before flying; BadInput when it is wrong."""
    from uavtest.spec.loaders import load_test

    test = load_test(path)
    _px4_bin(test, EngineSettings(), path)
    return test


def _last_line(path: Path, limit: int = 400) -> str:
    """The last line a process wrote to its log (its latest stage), cheaply."""
    try:
        with path.open("rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - limit))
            lines = [ln for ln in f.read().decode(errors="replace").splitlines() if ln.strip()]
    except OSError:
        return ""
    return lines[-1].strip()[:80] if lines and not lines[-1].startswith("--- attempt") else ""


class _Board:
    """Live display: a bar over all replicas and one status line per replica.

    While a replica flies, its line shows the runner's latest log line (its stage).
    """

    def __init__(self, seeds: dict[int, int], logs: dict[int, Path], name: str = "") -> None:
        self.seeds = seeds
        self.logs = logs
        self.name = name
        self.status: dict[int, str] = dict.fromkeys(seeds, "waiting")
        self.progress = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
        )
        self.task = self.progress.add_task("replicas", total=len(seeds))

    def set(self, index: int, status: str) -> None:
        self.status[index] = status

    def done(self, result: ReplicaResult) -> None:
        m = result.metrics
        detail = ""
        if result.reason:
            detail = f" · {result.reason[:90]}"
        elif m is not None and m.min_obstacle_distance is not None:
            detail = f" · min distance {m.min_obstacle_distance:.2f} m"
        self.status[result.index] = f"{result.verdict.value}{detail}"
        self.progress.advance(self.task)

    def line(self, index: int) -> str:
        """One replica's row as plain text: ``replica 3  seed 1003  pass · min distance 1.62 m``."""
        return f"replica {index}  seed {self.seeds[index]}  {self.status[index]}"

    def __rich__(self) -> RenderableType:
        lines = Table.grid(padding=(0, 2))
        lines.add_column(justify="right")
        lines.add_column(justify="right")
        lines.add_column()
        for i, status in self.status.items():
            if status.startswith("flying"):
                stage = _last_line(self.logs[i])
                status = f"{status} · {stage}" if stage else status
            colour = {"pass": "green", "fail": "red", "error": "yellow"}.get(status.split(" ")[0], "")
            text = f"[{colour}]{status}[/]" if colour else status
            lines.add_row(f"replica {i}", f"seed {self.seeds[i]}", text)
        return Group(self.progress, lines)


def _fly_all(
    jobs: list[ReplicaJob],
    parallel: int,
    store: ArtifactStore,
    launcher: Launcher,
    board: _Board,
    console: Console,
    shared: Shared,
) -> None:
    """Fly the replicas, ``parallel`` at a time within the shared slots, under a live board; side
    by side with other tests, a line per finished replica instead (one live display per console)."""

    def fly(job: ReplicaJob) -> ReplicaResult:
        with shared.slots:
            return run_replica(
                job,
                ports=shared.ports,
                store=store,
                on_status=board.set,
                cancel=shared.cancel,
                launcher=launcher,
            )

    live = not shared.side_by_side
    board_display = Live(board, console=console, refresh_per_second=4, transient=False)
    with (
        board_display if live else contextlib.nullcontext(),
        ThreadPoolExecutor(max_workers=parallel, thread_name_prefix="replica") as pool,
    ):
        futures: list[Future[ReplicaResult]] = [pool.submit(fly, job) for job in jobs]
        try:
            for future in as_completed(futures):
                result = future.result()
                board.done(result)
                if not live:  # a line, kept out of other tests' blocks
                    with shared.output:
                        console.print(f"{board.name} · {board.line(result.index)}", highlight=False)
        except BaseException:
            shared.cancel.set()  # every replica stops its processes; the pool then drains
            for f in futures:
                f.cancel()
            raise
    if live and not console.is_terminal:
        console.line()  # a live display ends its last frame without a newline when not on a terminal


def _launcher(settings: EngineSettings, px4_bin: Path | None, replicas: int, warm: bool) -> Launcher:
    """Fork from a warm server when it pays: several replicas of the built-in simulator, in this
    run or (``warm``) in the runs that follow it in this process (``uavtest run`` of several tests).

    One replica alone starts faster exec'd (its two processes import in parallel, while a fork
    server imports once, serially, before the first fork); PX4 is a binary, always exec'd.
    """
    if settings.launch == "fork" and px4_bin is None and (replicas > 1 or warm):
        warm = WarmLauncher()
        warm.warm()  # the server imports while the engine prepares the replicas
        return warm
    # processes started cold compile uavtest each time unless it has bytecode (engine.bytecode);
    # not for PX4 replicas: PX4's boot (~35 s of its clock) dominates their start-up, and a runner
    # ready sooner would only meet PX4 earlier in its boot, which was not shown to be harmless
    return ExecLauncher(environ=replica_environ() if px4_bin is None else None)


def wait_for_first_line(log: Path, wait_s: float, poll_s: float = 0.05) -> bool:
    """Wait until a process has written a line to ``log`` (beyond the attempt header); False
    when ``wait_s`` passed first."""
    deadline = time.monotonic() + wait_s
    while not _last_line(log):
        if time.monotonic() >= deadline:
            return False
        time.sleep(poll_s)
    return True


def _import_aggregation(after: Path | None = None, wait_s: float = 10.0) -> None:
    """Import what aggregation needs (matplotlib) while the replicas fly, not after them.

    ``after``: a runner's log; the import waits until that runner has logged its first line
    (at most ``wait_s``): processes started cold import for about a second, and this import
    would take a core from them on a 2-core machine, while the lockstep flight leaves one free.
    """
    if after is not None:
        wait_for_first_line(after, wait_s)
    for module in ("uavtest.engine.aggregate", "uavtest.analysis.plots"):
        importlib.import_module(module)


def run_local(
    options: RunOptions, *, console: Console | None = None, shared: Shared | None = None
) -> LocalRun:
    """Fly a test's replicas locally and aggregate them; raises BadInput before flying anything.

    ``shared``: the test flies side by side with others of the same command (``side_by_side``).
    """
    from uavtest.analysis.verdict import simulator_warnings
    from uavtest.engine.aggregate import aggregate_run
    from uavtest.spec.loaders import load_test
    from uavtest.store import LocalStore

    console = console or Console(stderr=True)
    shared = shared if shared is not None else Shared.alone()
    settings = EngineSettings()
    test = load_test(options.test)
    notices = [
        n
        for n in [aerialist_simulator_notice(options.test), unmodelled_notice(unmodelled_params(test.spec))]
        if n
    ]
    # side by side, a test's lines stay together, not inside another test's block
    with shared.output:
        for n in notices:
            console.print(f"[cyan]notice:[/] {n}", highlight=False)
        for w in [*simulator_warnings(test.spec), speed_factor_notice(test.spec)]:
            if w:
                console.print(f"[yellow]warning:[/] {w}", highlight=False)
    px4_bin = _px4_bin(test, settings, options.test)

    replicas = options.replicas if options.replicas is not None else test.spec.replicas
    if replicas < 1:
        raise _bad("--replicas", "need at least one replica", replicas, "1 or more")
    if options.seed is not None and options.seed < 0:
        raise _bad("--seed", "the base seed must not be negative", options.seed, "0 or more")
    if options.replica is not None and not 0 <= options.replica < replicas:
        raise _bad("--replica", "no such replica in this run", options.replica, f"0..{replicas - 1}")
    cores = available_cores()
    jobs_wanted = options.jobs if options.jobs is not None else test.spec.parallelism or cores
    if jobs_wanted < 1:
        raise _bad("--jobs", "need at least one job", jobs_wanted, "1 or more")

    seed = options.seed if options.seed is not None else test.spec.seed
    spec = test.spec.model_copy(update={"replicas": replicas, "seed": seed})
    indices = [options.replica] if options.replica is not None else list(range(replicas))
    launcher = _launcher(settings, px4_bin, len(indices), options.warm)
    parallel = min(jobs_wanted, len(indices))
    if px4_bin is not None:
        parallel = min(parallel, PX4_MAX_INSTANCES)

    name = test.metadata.name
    run_id = new_run_id()
    out = options.out.resolve()
    store = LocalStore(out)
    speed, how = px4_speed_choice(spec, cores=cores, at_once=parallel) if px4_bin is not None else (None, "")
    attempt_wall = wall_timeout(spec.timeout, spec.vehicle.simulator, speed)
    jobs = [
        ReplicaJob(
            test_path=options.test.resolve(),
            test_name=name,
            namespace=NAMESPACE,
            run_id=run_id,
            index=i,
            seed=spec.replica_seed(i),
            store_url=str(out),
            out_dir=store.root / replica_prefix(NAMESPACE, name, run_id, i),
            simulator=spec.vehicle.simulator,
            px4_bin=px4_bin,
            home=spec.world.home,
            speed_factor=speed,
            wall_timeout=attempt_wall,
            retries=options.retries,
        )
        for i in indices
    ]
    pace = ""
    if speed is not None:
        pace = f" PX4 at {speed:g}x real time ({how}),"
    with shared.output:
        console.print(
            f"run [bold]{run_id}[/] of [bold]{name}[/]: {len(indices)} replica(s), {parallel} at a time,"
            f"{pace} artifacts in {store.root / run_prefix(NAMESPACE, name, run_id)}",
            highlight=False,
        )
    board = _Board(
        {j.index: j.seed for j in jobs}, {j.index: j.out_dir / "runner.stderr.log" for j in jobs}, name
    )
    # cold-started built-in replicas import first (forked ones have already). PX4 is not in
    # lockstep: the import runs during its boot, as a core taken from it mid-flight changes it
    cold = isinstance(launcher, ExecLauncher) and px4_bin is None
    first_log = jobs[0].out_dir / "runner.stderr.log" if cold else None
    threading.Thread(
        target=_import_aggregation, args=(first_log,), name="import-aggregation", daemon=True
    ).start()
    _fly_all(jobs, parallel, store, launcher, board, console, shared)

    with shared.aggregate:
        summary = aggregate_run(store, NAMESPACE, name, run_id, indices, spec)
    summary_path = store.path(aggregate_key(NAMESPACE, name, run_id, "summary.json"))
    plot_path = store.path(aggregate_key(NAMESPACE, name, run_id, "trajectories.png"))
    return LocalRun(
        summary=summary,
        run_dir=summary_path.parent.parent,
        summary_path=summary_path,
        plot_path=plot_path if plot_path.exists() else None,
        notices=notices,
    )
