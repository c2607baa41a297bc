"""One replica, start to end: the stages in order, and the exit code (``uavtest runner``).

connect → params → mission → flight (the core, over UDP) → collect the log → analyse → store.
Whatever happens, a ``ReplicaResult`` comes out: bench faults are ``error`` with the reason, it is
stored as ``result.json`` when the store can take it, and printed as the last line on stdout.
Exit code: 0 pass, 1 fail, 3 error (2 when the test file itself is wrong).
"""

from __future__ import annotations

import logging
import signal
import sys
import tempfile
import time
from pathlib import Path
from types import FrameType

from pydantic import BaseModel, ConfigDict, Field

from uavtest.analysis.models import InjectedFault, ReplicaResult, Verdict
from uavtest.errors import BadInput, ExitCode, InfrastructureError, UavTestError
from uavtest.runner.analyse import Analysis, analyse
from uavtest.runner.artifacts import ReplicaPlace, store_artifacts
from uavtest.runner.core import Ending, FlightReport, ReplicaCore
from uavtest.runner.grants import DEFAULT_STEP_MS
from uavtest.runner.link import UdpLink
from uavtest.runner.logdir import has_log, wait_for_log
from uavtest.runner.logdownload import LogFetch
from uavtest.runner.plan import plan_flight
from uavtest.runner.session import drive
from uavtest.spec.models import UavTestSpec
from uavtest.store.base import ArtifactStore
from uavtest.store.layout import LOCAL_NAMESPACE
from uavtest.store.open import open_store

__all__ = ["Interrupted", "RunnerOptions", "exit_code", "run_replica", "run_replica_command"]

log = logging.getLogger("uavtest.runner")


class RunnerOptions(BaseModel):
    """The ``uavtest runner`` command line."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    test: Path
    replica: int = Field(0, ge=0)
    seed: int | None = Field(None, ge=0, description="default: the spec's seed for this replica")
    connect: str = "udpin:127.0.0.1:14540"
    store: str
    run_id: str
    namespace: str = LOCAL_NAMESPACE
    test_name: str | None = None
    log_dir: Path | None = Field(None, description="shared directory the simulator writes its .ulg to")
    timeout: float | None = Field(None, gt=0, description="vehicle seconds; default: the spec's timeout")
    connect_timeout: float = Field(30.0, gt=0, description="wall seconds to wait for the first heartbeat")
    log_timeout: float = Field(15.0, gt=0, description="wall seconds to wait for the finished log")
    step_ms: int = Field(
        DEFAULT_STEP_MS, ge=1, le=10_000, description="largest lockstep grant, vehicle milliseconds"
    )
    arm_settle: float | None = Field(
        None, ge=0, description="vehicle seconds ready-to-arm before arming; default by simulator"
    )


class Interrupted(InfrastructureError):
    """SIGTERM / SIGINT while the replica ran."""


def _on_signal(signum: int, frame: FrameType | None) -> None:
    # one-shot: the replica still stores an error result; a second signal ends the process
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    raise Interrupted(f"runner stopped by {signal.Signals(signum).name}")


def exit_code(result: ReplicaResult) -> ExitCode:
    return {
        Verdict.PASS: ExitCode.PASS,
        Verdict.FAIL: ExitCode.FAIL,
        Verdict.ERROR: ExitCode.INFRASTRUCTURE,
    }[result.verdict]


def injected_faults(report: FlightReport) -> list[InjectedFault]:
    """The faults the flight injected, for result.json."""
    return [InjectedFault.model_validate(f.to_json()) for f in report.faults]


def _collect_log(opts: RunnerOptions, report: FlightReport, since: float) -> tuple[Path | None, str | None]:
    """Stage 6: the flight log's path, or why there is none.

    From the vehicle (downloaded during the session), else from the shared ``--log-dir``; a
    vehicle that armed but left nothing there (a PX4 image writing its log elsewhere) gets its
    log downloaded over MAVLink instead."""
    if report.log_data is not None:
        return _temp_log(report.log_data), None
    if opts.log_dir is None:
        return None, report.error or "log missing: no --log-dir and no log downloaded from the vehicle"
    if report.ending in (Ending.ERROR, Ending.REFUSED) and not report.armed_ever:
        return None, "log missing: the vehicle never armed, so its log never closed"
    if report.armed_ever and report.ending is not Ending.ERROR and not has_log(opts.log_dir, since=since):
        log.info("no log in %s: downloading it from the vehicle over MAVLink", opts.log_dir)
        data, error = _download_log(opts)
        if data is not None:
            report.log_data = data  # like a log downloaded during the session: a temporary file
            return _temp_log(data), None
        return None, f"log missing: none in {opts.log_dir}, and the MAVLink download failed: {error}"
    try:
        return wait_for_log(opts.log_dir, since=since, timeout_s=opts.log_timeout), None
    except InfrastructureError as e:
        return None, str(e)


def _temp_log(data: bytes) -> Path:
    tmp = tempfile.NamedTemporaryFile(prefix="uavtest-", suffix=".ulg", delete=False)  # noqa: SIM115
    with tmp:
        tmp.write(data)
    return Path(tmp.name)


def _download_log(opts: RunnerOptions, *, tick_s: float = 0.02) -> tuple[bytes | None, str | None]:
    """The vehicle's newest log over MAVLink, after the flight (I/O edge of ``LogFetch``)."""
    fetch = LogFetch(connect_timeout_s=opts.connect_timeout)
    with UdpLink(opts.connect) as link:
        link.send(fetch.start(time.monotonic()))
        while not fetch.done:
            events = link.receive(tick_s)
            now = time.monotonic()
            for event in events:
                link.send(fetch.handle(event, now))
            link.send(fetch.tick(now))
    return fetch.data, fetch.error


def _fly(opts: RunnerOptions, spec: UavTestSpec) -> FlightReport:
    config = plan_flight(
        spec,
        endpoint=opts.connect,
        timeout_s=opts.timeout,
        connect_timeout_s=opts.connect_timeout,
        step_ms=opts.step_ms,
        download_log=opts.log_dir is None,
        arm_settle_s=opts.arm_settle,
    )
    core = ReplicaCore(config)
    with UdpLink(opts.connect) as link:
        wall, cpu = time.monotonic(), time.process_time()
        report = drive(core, link)
        wall, cpu = time.monotonic() - wall, time.process_time() - cpu
        codec = link.codec
        log.info(
            "link: %d datagrams in, %d out; %d frames, %d decoded, %d bad",
            link.received,
            link.sent,
            codec.frames,
            codec.decoded,
            codec.bad,
        )
        if report.sim_time:
            per_step = f", {cpu / report.grants * 1e6:.0f} µs runner CPU per step" if report.grants else ""
            flight = report.flight_wall[1] - report.flight_wall[0] if report.flight_wall else wall
            log.info(
                "flew %.1f vehicle s in %.2f wall s (%.0fx real time; %.2f s with connect and setup), "
                "runner CPU %.2f s%s; %d grants",
                report.sim_time,
                flight,
                report.sim_time / flight if flight > 0 else 0.0,
                wall,
                cpu,
                per_step,
                report.grants,
            )
    return report


def run_replica(opts: RunnerOptions, *, store: ArtifactStore | None = None) -> tuple[ReplicaResult, bool]:
    """Fly and judge one replica and store its artifacts; (result, whether result.json was stored).

    Raises BadInput before anything flies when the test file or the options are wrong.
    """
    from uavtest.spec.loaders import load_test
    from uavtest.spec.px4_params import unmodelled_notice, unmodelled_params

    wall0 = time.monotonic()
    since = time.time() - 1.0
    test = load_test(opts.test)
    spec = test.spec
    seed = opts.seed if opts.seed is not None else spec.replica_seed(opts.replica)
    place = ReplicaPlace(opts.namespace, opts.test_name or test.metadata.name, opts.run_id, opts.replica)
    store = store if store is not None else open_store(opts.store)
    log.info("store: %r", store)  # where and how (keys or upload policy), never a credential

    report = FlightReport()
    log_path: Path | None = None
    log_error: str | None = None
    try:
        report = _fly(opts, spec)
        log_path, log_error = _collect_log(opts, report, since)
    except UavTestError as e:
        if isinstance(e, BadInput):
            raise
        report.ending = Ending.ERROR
        report.error = str(e)
    analysis: Analysis = analyse(
        report,
        log_path,
        spec,
        index=opts.replica,
        seed=seed,
        log_error=log_error,
        wall_time=round(time.monotonic() - wall0, 3),
    )
    log_bytes = log_path.read_bytes() if log_path is not None else None
    if log_path is not None and report.log_data is not None:
        log_path.unlink(missing_ok=True)
    unmodelled = unmodelled_params(spec)
    if unmodelled:
        log.warning("%s", unmodelled_notice(unmodelled))
    result, stored = store_artifacts(
        store,
        place,
        analysis.result.model_copy(
            update={"unmodelled_params": unmodelled, "faults": injected_faults(report)}
        ),
        log_bytes=log_bytes,
        trajectory=analysis.trajectory,
    )
    return result, stored


def run_replica_command(
    test: Path,
    *,
    replica: int,
    seed: int | None,
    connect: str,
    store: str,
    run_id: str,
    namespace: str = LOCAL_NAMESPACE,
    test_name: str | None = None,
    log_dir: Path | None = None,
    timeout: float | None = None,
    connect_timeout: float = 30.0,
    step_ms: int = DEFAULT_STEP_MS,
    arm_settle: float | None = None,
) -> int:
    """``uavtest runner``: fly one replica; print its ReplicaResult JSON as the last stdout line."""
    logging.basicConfig(
        level=logging.INFO,
        stream=sys.stderr,
        format="%(asctime)s runner[%(process)d] %(levelname)s %(message)s",
    )
    opts = RunnerOptions(
        test=test,
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
    previous = {s: signal.signal(s, _on_signal) for s in (signal.SIGTERM, signal.SIGINT)}
    code: ExitCode | None = None
    try:
        result, _ = run_replica(opts)
    except Interrupted as e:
        result = ReplicaResult(index=replica, seed=seed or 0, verdict=Verdict.ERROR, reason=str(e))
    except BadInput as e:
        # the test (or an option) is wrong: nothing flew; still leave a result where one is expected
        log.error("%s", e)
        result = ReplicaResult(index=replica, seed=seed or 0, verdict=Verdict.ERROR, reason=f"bad input: {e}")
        code = ExitCode.BAD_INPUT
        _store_bad_input(opts, result)
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    print(result.model_dump_json(), flush=True)
    return int(code if code is not None else exit_code(result))


def _store_bad_input(opts: RunnerOptions, result: ReplicaResult) -> None:
    """Store result.json for a test that could not be read, when its name is known (--test-name)."""
    if opts.test_name is None:
        return
    try:
        place = ReplicaPlace(opts.namespace, opts.test_name, opts.run_id, opts.replica)
        store_artifacts(open_store(opts.store), place, result, log_bytes=None, trajectory=None)
    except UavTestError as e:
        log.error("could not store result.json: %s", e)
