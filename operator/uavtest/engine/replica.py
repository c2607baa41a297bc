"""One replica: a simulator process and a runner process on free ports, retried on bench errors.

The simulator is ``uavtest sitl --lockstep`` (or PX4 SITL from ``UAVTEST_PX4_BIN``); the runner
is ``uavtest runner`` (process contract 4 in DESIGN.md). Both write their stderr to files in the
replica's output folder. When the runner ends, the simulator is stopped. The runner's exit code
says pass (0), fail (1) or bench error (3); ``result.json`` in the store is the source of truth.
A bench error — runner exit 3, a crashed process, a wall-clock overrun — is retried with the
same seed a bounded number of times; a replica that still errors is reported ``error`` with its
reason, never dropped.
"""

from __future__ import annotations

import contextlib
import logging
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.engine.launch import ENTRY_MODULE, ExecLauncher, Launcher, Started
from uavtest.engine.ports import PortAllocator, ReplicaPorts
from uavtest.engine.px4home import px4_home_env, px4_search_path, px4_start_files, sih_latlon_is_int
from uavtest.engine.speed import px4_speed_env
from uavtest.errors import UavTestError
from uavtest.spec.models import Home, Simulator
from uavtest.store import ArtifactStore
from uavtest.store.layout import replica_key

__all__ = [
    "DEFAULT_RETRIES",
    "ExitOutcome",
    "ProcessPlan",
    "ReplicaJob",
    "StatusCallback",
    "classify_exit",
    "plan_processes",
    "px4_etc_dir",
    "run_replica",
    "sitl_command",
]

log = logging.getLogger(__name__)

DEFAULT_RETRIES = 2
SIM_DEATH_GRACE = 15.0  # wall seconds the runner gets to notice a simulator that died
STOP_GRACE = 5.0  # wall seconds between SIGTERM and SIGKILL
POLL = 0.05

StatusCallback = Callable[[int, str], None]


class ReplicaJob(BaseModel):
    """Everything one replica needs: which test, which seed, where artifacts and logs go."""

    model_config = ConfigDict(frozen=True)

    test_path: Path = Field(description="the test file as the user gave it (runner and sim load it)")
    test_name: str
    namespace: str = "local"
    run_id: str
    index: int = Field(ge=0)
    seed: int
    store_url: str = Field(description="what the runner's --store gets (a path or s3:// URL)")
    out_dir: Path = Field(description="this replica's folder for the processes' stderr")
    simulator: Simulator = Simulator.BUILTIN
    px4_bin: Path | None = None
    home: Home = Field(default_factory=Home, description="where PX4 SITL starts (world.home)")
    speed_factor: float | None = Field(
        None, gt=0, description="PX4_SIM_SPEED_FACTOR for PX4 SITL (None: PX4's own, real time)"
    )
    wall_timeout: float = Field(gt=0, description="wall seconds one attempt may take before it is killed")
    retries: int = Field(DEFAULT_RETRIES, ge=0)
    sim_death_grace: float = Field(
        SIM_DEATH_GRACE, gt=0, description="wall seconds the runner gets to notice a dead simulator"
    )
    python: str = Field(default_factory=lambda: sys.executable)


@dataclass(frozen=True, slots=True)
class ProcessPlan:
    """The two command lines of one attempt, where the simulator runs, and the files it needs."""

    sim: list[str]
    runner: list[str]
    sim_cwd: Path | None = None
    sim_env: dict[str, str] | None = None
    sim_files: dict[Path, str] = field(default_factory=dict)  # written before the simulator starts
    sim_stdout: Path | None = None  # where the simulator's stdout goes (None: discarded)


PlanBuilder = Callable[[ReplicaJob, ReplicaPorts, Path], ProcessPlan]


def px4_etc_dir(px4_bin: Path) -> Path:
    """PX4's ROMFS folder next to the binary's bin/ (build/px4_sitl_default/etc)."""
    return px4_bin.resolve().parent.parent / "etc"


def sitl_command(
    python: str, test: Path | str, seed: int, *, api_port: int, log_dir: Path, gcs_port: int | None = None
) -> list[str]:
    """The ``uavtest sitl`` command line of one lockstep replica on loopback (process contract 4).

    The simulator sends from any free local port; ``gcs_port`` None keeps PX4's 14550.
    """
    argv = [python, "-m", ENTRY_MODULE, "sitl", "--test", str(test), "--seed", str(seed)]
    argv += ["--host", "127.0.0.1", "--api-port", str(api_port)]
    if gcs_port is not None:
        argv += ["--gcs-port", str(gcs_port)]
    argv += ["--api-local-port", "0", "--gcs-local-port", "0", "--gcs-quiet", "--log-dir", str(log_dir)]
    argv += ["--lockstep"]
    return argv


def plan_processes(job: ReplicaJob, ports: ReplicaPorts, log_dir: Path) -> ProcessPlan:
    """The simulator and runner command lines for one attempt (process contract 4)."""
    test = str(job.test_path)
    runner = [
        job.python,
        "-m",
        ENTRY_MODULE,
        "runner",
        "--test",
        test,
        "--replica",
        str(job.index),
        "--seed",
        str(job.seed),
        "--connect",
        f"udpin:127.0.0.1:{ports.api}",
        "--store",
        job.store_url,
        "--run-id",
        job.run_id,
        "--namespace",
        job.namespace,
        "--test-name",
        job.test_name,
        "--log-dir",
        str(log_dir),
    ]
    if job.simulator == Simulator.PX4:
        if job.px4_bin is None or ports.instance is None:
            raise ValueError("a PX4 replica needs px4_bin and a PX4 instance number")
        env = dict(os.environ)
        env.setdefault("PX4_SIM_MODEL", "sihsim_quadx")
        env.update(px4_home_env(job.home, int_latlon=sih_latlon_is_int(job.px4_bin)))
        env["PATH"] = px4_search_path(log_dir, env.get("PATH", ""))
        if job.speed_factor is not None:
            env.update(px4_speed_env(job.speed_factor))
        sim = [str(job.px4_bin), "-i", str(ports.instance), "-d", str(px4_etc_dir(job.px4_bin))]
        # PX4 writes its logs under <working dir>/log/<date>/; the runner collects them there.
        runner[runner.index("--log-dir") + 1] = str(log_dir / "log")
        files = px4_start_files(log_dir, job.home)
        return ProcessPlan(
            sim=sim,
            runner=runner,
            sim_cwd=log_dir,
            sim_env=env,
            sim_files=files,
            sim_stdout=job.out_dir / "sim.stdout.log",  # PX4's console: its start-up and errors
        )
    sim = sitl_command(job.python, test, job.seed, api_port=ports.api, gcs_port=ports.gcs, log_dir=log_dir)
    return ProcessPlan(sim=sim, runner=runner)


# --------------------------------------------------------------------------- exit codes


@dataclass(frozen=True, slots=True)
class ExitOutcome:
    """What a runner's exit code says: a verdict, or an error and whether a retry may help."""

    verdict: Verdict
    retryable: bool
    reason: str = ""


def _signal_name(code: int) -> str:
    try:
        return signal.Signals(-code).name
    except ValueError:
        return f"signal {-code}"


def classify_exit(code: int) -> ExitOutcome:
    """Map a runner exit code: 0 pass, 1 fail, 3 bench error (retry), 2 bad input, else a crash."""
    if code == 0:
        return ExitOutcome(Verdict.PASS, retryable=False)
    if code == 1:
        return ExitOutcome(Verdict.FAIL, retryable=False)
    if code == 3:
        return ExitOutcome(Verdict.ERROR, retryable=True, reason="runner reported a bench error")
    if code == 2:
        return ExitOutcome(Verdict.ERROR, retryable=False, reason="runner rejected the test (exit 2)")
    if code < 0:
        return ExitOutcome(Verdict.ERROR, retryable=True, reason=f"runner killed by {_signal_name(code)}")
    return ExitOutcome(Verdict.ERROR, retryable=True, reason=f"runner crashed (exit {code})")


# --------------------------------------------------------------------------- processes


@dataclass(slots=True)
class _AttemptFiles:
    runner_out: Path
    runner_err: Path
    sim_err: Path


@dataclass(slots=True)
class _AttemptEnd:
    runner_code: int | None
    sim_code: int | None
    note: str = ""  # why the engine stopped the runner (timeout, simulator died, cancelled)
    sim_note: str = ""  # the simulator exited by itself with an error before the runner ended
    cancelled: bool = False
    sim: Started | None = None  # the simulator, when it was still running after the runner


def _signal(proc: Started, sig: signal.Signals) -> None:
    """Signal the process's session (it is a session leader), else the process itself."""
    if proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, sig)
        return
    except ProcessLookupError:
        pass  # a forked process may not have called setsid yet
    with contextlib.suppress(ProcessLookupError):
        os.kill(proc.pid, sig)


def _stop(proc: Started) -> int:
    """SIGTERM the process, SIGKILL after a grace; return its exit code."""
    if (code := proc.poll()) is not None:
        return code
    for sig in (signal.SIGTERM, signal.SIGKILL):
        _signal(proc, sig)
        try:
            return proc.wait(timeout=STOP_GRACE)
        except subprocess.TimeoutExpired:
            continue
    return proc.wait()


def _tail(path: Path, lines: int = 1) -> str:
    """The last non-empty lines of a log file, for a reason."""
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return ""
    kept = [ln.strip() for ln in text.splitlines() if ln.strip() and not ln.startswith("--- attempt")]
    return " | ".join(kept[-lines:])[:300]


def _sim_tail(plan: ProcessPlan, files: _AttemptFiles) -> str:
    """The simulator's last words: its stderr, else its stdout (PX4 prints its errors there)."""
    return _tail(files.sim_err) or (_tail(plan.sim_stdout) if plan.sim_stdout else "")


def _fly(
    plan: ProcessPlan,
    files: _AttemptFiles,
    attempt: int,
    job: ReplicaJob,
    launcher: Launcher,
    cancel: threading.Event,
) -> _AttemptEnd:
    """Start runner and simulator, wait for the runner, stop the simulator."""
    where = f": {' '.join(plan.sim)} in {plan.sim_cwd}" if plan.sim_cwd else ""  # e.g. px4 -i 1 in /tmp/...
    for path, header in [
        (files.runner_out, ""),
        (files.runner_err, ""),
        (files.sim_err, where),
        *([(plan.sim_stdout, where)] if plan.sim_stdout else []),
    ]:
        with path.open("a") as f:
            f.write(f"--- attempt {attempt}{header} ---\n")
    try:
        for path, text in plan.sim_files.items():
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
    except OSError as e:
        return _AttemptEnd(None, None, note=f"cannot prepare the simulator's working directory: {e}")
    # The runner binds the API port; start it first so the simulator's first packets land.
    runner = launcher.start(plan.runner, stdout=files.runner_out, stderr=files.runner_err)
    try:
        sim = launcher.start(
            plan.sim, stdout=plan.sim_stdout, stderr=files.sim_err, cwd=plan.sim_cwd, env=plan.sim_env
        )
    except OSError as e:
        _stop(runner)
        return _AttemptEnd(None, None, note=f"cannot start the simulator {plan.sim[0]}: {e}")
    end = _AttemptEnd(None, None)
    deadline = time.monotonic() + job.wall_timeout
    sim_died_at: float | None = None
    try:
        while True:
            try:
                end.runner_code = runner.wait(timeout=POLL)
                break
            except subprocess.TimeoutExpired:
                pass
            now = time.monotonic()
            if cancel.is_set():
                end.cancelled, end.note = True, "cancelled"
                end.runner_code = _stop(runner)
                break
            if sim_died_at is None and sim.poll() not in (None, 0):
                sim_died_at = now
            if sim_died_at is not None and now - sim_died_at > job.sim_death_grace:
                end.note = f"simulator exited with code {sim.poll()}: {_sim_tail(plan, files)}"
                end.runner_code = _stop(runner)
                break
            if now > deadline:
                end.note = f"replica did not finish within {job.wall_timeout:g} s wall time"
                end.runner_code = _stop(runner)
                break
    finally:
        if runner.poll() is None:
            _stop(runner)
        end.sim_code = sim.poll()
        if end.sim_code is None:
            end.sim = sim  # still running: the caller stops it
        elif end.sim_code != 0:
            end.sim_note = f"simulator exited with code {end.sim_code}: {_sim_tail(plan, files)}"
    return end


def _stop_in_background(proc: Started, log_dir: Path) -> None:
    """SIGTERM the simulator now; wait for it and remove its log folder off the replica's clock.

    The wait (the simulator closes its log and exits) costs no CPU, so the replica's slot is
    given to the next replica at once. The thread is not a daemon: the engine does not exit
    before every simulator has.
    """
    _signal(proc, signal.SIGTERM)

    def finish() -> None:
        _stop(proc)
        shutil.rmtree(log_dir, ignore_errors=True)

    threading.Thread(target=finish, name=f"stop-sim-{proc.pid}", daemon=False).start()


# --------------------------------------------------------------------------- results


def _read_result(store: ArtifactStore, job: ReplicaJob) -> ReplicaResult | str:
    """result.json of this replica from the store, or why it cannot be used."""
    key = replica_key(job.namespace, job.test_name, job.run_id, job.index, "result.json")
    try:
        if not store.exists(key):
            return "runner wrote no result.json"
        return ReplicaResult.model_validate_json(store.get(key))
    except ValidationError as e:
        return f"unreadable result.json: {e.errors()[0]['msg']}"
    except UavTestError as e:  # a store failure is a bench error of this replica, not of the run
        return f"cannot read result.json from the store: {e}"


def _last_json_line(path: Path) -> ReplicaResult | None:
    """The runner prints its ReplicaResult as the last stdout line; a fallback to result.json."""
    try:
        lines = [ln for ln in path.read_text(errors="replace").splitlines() if ln.strip()]
    except OSError:
        return None
    if not lines or lines[-1].startswith("--- attempt"):
        return None
    try:
        return ReplicaResult.model_validate_json(lines[-1])
    except ValidationError:
        return None


@dataclass(slots=True)
class _Judged:
    result: ReplicaResult | None  # pass / fail from the store
    reason: str = ""  # error reason otherwise
    retryable: bool = True


def _judge_attempt(end: _AttemptEnd, files: _AttemptFiles, store: ArtifactStore, job: ReplicaJob) -> _Judged:
    if end.runner_code is None:
        return _Judged(None, end.note or "runner did not start")
    if end.note:
        return _Judged(None, end.note)
    outcome = classify_exit(end.runner_code)
    stored = _read_result(store, job)
    if outcome.verdict in (Verdict.PASS, Verdict.FAIL):
        if isinstance(stored, str):
            return _Judged(None, f"runner exited {end.runner_code} but {stored}")
        if stored.verdict == Verdict.ERROR:
            return _Judged(None, stored.reason or "runner reported a bench error")
        return _Judged(stored)
    # An error: the runner's own reason (result.json, then its last stdout line), else stderr.
    reason = end.sim_note
    if not isinstance(stored, str) and stored.verdict == Verdict.ERROR:
        reason = stored.reason
    if not reason:
        printed = _last_json_line(files.runner_out)
        if printed is not None and printed.verdict == Verdict.ERROR:
            reason = printed.reason
    if not reason:
        tail = _tail(files.runner_err)
        reason = f"{outcome.reason}: {tail}" if tail else outcome.reason
    return _Judged(None, reason, retryable=outcome.retryable)


def _write_result(store: ArtifactStore, job: ReplicaJob, result: ReplicaResult) -> None:
    key = replica_key(job.namespace, job.test_name, job.run_id, job.index, "result.json")
    store.put(key, result.model_dump_json(indent=2).encode(), "application/json")


@dataclass(slots=True)
class _Attempts:
    reasons: list[str] = field(default_factory=list)


def run_replica(
    job: ReplicaJob,
    *,
    ports: PortAllocator,
    store: ArtifactStore,
    plan: PlanBuilder = plan_processes,
    on_status: StatusCallback | None = None,
    cancel: threading.Event | None = None,
    launcher: Launcher | None = None,
) -> ReplicaResult:
    """Fly one replica, retrying bench errors with the same seed; always returns a result.

    The returned result is also what ``result.json`` holds afterwards: the runner's, with
    ``attempts`` and the engine's wall time (start-up included), or an ``error`` the engine
    wrote when the runner could not.
    """
    cancel = cancel or threading.Event()
    launcher = launcher or ExecLauncher()
    status = on_status or (lambda _i, _s: None)
    job.out_dir.mkdir(parents=True, exist_ok=True)
    files = _AttemptFiles(
        runner_out=job.out_dir / "runner.stdout.log",
        runner_err=job.out_dir / "runner.stderr.log",
        sim_err=job.out_dir / "sim.stderr.log",
    )
    history = _Attempts()
    started = time.monotonic()
    attempts = 0
    final: ReplicaResult | None = None
    for attempt in range(1, job.retries + 2):
        attempts = attempt
        status(job.index, "flying" if attempt == 1 else f"flying (attempt {attempt})")
        log_dir = Path(tempfile.mkdtemp(prefix=f"uavtest-replica-{job.index}-"))
        with ports.lease(px4=job.simulator == Simulator.PX4) as p:
            end = _fly(plan(job, p, log_dir), files, attempt, job, launcher, cancel)
            if end.sim is not None and job.simulator == Simulator.BUILTIN and not end.cancelled:
                _stop_in_background(end.sim, log_dir)
            else:  # PX4 holds its instance's ports until it has exited
                if end.sim is not None:
                    end.sim_code = _stop(end.sim)
                shutil.rmtree(log_dir, ignore_errors=True)
        if end.cancelled:
            history.reasons.append("cancelled")
            break
        judged = _judge_attempt(end, files, store, job)
        if judged.result is not None:
            final = judged.result
            break
        history.reasons.append(judged.reason)
        if not judged.retryable or attempt > job.retries:
            break
        log.warning(
            "replica %d (seed %d): attempt %d/%d was a bench error: %s; retrying with the same seed",
            job.index,
            job.seed,
            attempt,
            job.retries + 1,
            judged.reason,
        )
        status(job.index, f"retry {attempt}: {judged.reason[:60]}")
    wall = round(time.monotonic() - started, 3)
    if final is None:
        last = history.reasons[-1] if history.reasons else "no attempt ran"
        reason = last if attempts == 1 else f"{last} (after {attempts} attempts)"
        final = ReplicaResult(
            index=job.index, seed=job.seed, verdict=Verdict.ERROR, reason=reason, attempts=attempts
        )
    final = final.model_copy(update={"attempts": attempts, "wall_time": wall})
    try:
        _write_result(store, job, final)
    except UavTestError as e:  # the verdict still reaches the summary through the return value
        log.error("replica %d: cannot write result.json: %s", job.index, e)
    status(job.index, final.verdict.value)
    return final
