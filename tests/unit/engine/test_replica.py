"""One replica's process handling and retries, with tiny real child processes.

The runner here is a ``python -c`` child that writes ``result.json`` into a real LocalStore and
exits with a scripted code per attempt; the simulator is a ``python -c`` child that waits to be
stopped (or dies). This exercises the engine's own process management, not the real runner.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import pytest

from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.engine.ports import PortAllocator, ReplicaPorts
from uavtest.engine.replica import ProcessPlan, ReplicaJob, classify_exit, plan_processes, run_replica
from uavtest.spec.models import Simulator
from uavtest.store import LocalStore
from uavtest.store.layout import replica_key

RUNNER = r"""
import json, pathlib, sys
result, counter, codes, index, seed, sim_pid = sys.argv[1:7]
import time
deadline = time.monotonic() + 30
while "sim_dies" not in codes and not pathlib.Path(sim_pid).exists() and time.monotonic() < deadline:
    time.sleep(0.01)  # like a real runner waiting for the simulator's heartbeat
counter = pathlib.Path(counter)
n = int(counter.read_text()) if counter.exists() else 0
counter.write_text(str(n + 1))
with open(str(counter) + ".seeds", "a") as f:
    f.write(seed + "\n")
code = int(codes.split(",")[min(n, len(codes.split(",")) - 1)])
verdict = {0: "pass", 1: "fail", 3: "error"}.get(code)
print(f"runner attempt {n + 1} on stderr", file=sys.stderr)
if verdict and "noresult" not in codes:
    p = pathlib.Path(result)
    p.parent.mkdir(parents=True, exist_ok=True)
    reason = "" if code == 0 else f"{verdict} reason of attempt {n + 1}"
    p.write_text(json.dumps({"index": int(index), "seed": int(seed), "verdict": verdict, "reason": reason}))
if "hang" in codes:
    import time
    time.sleep(600)
sys.exit(code)
"""

SIM_WAITS = r"""
import pathlib, sys, time, os
pathlib.Path(sys.argv[1]).write_text(str(os.getpid()))
print("sim up", file=sys.stderr, flush=True)
time.sleep(600)
"""

SIM_DIES = r"""
import sys
print("Traceback: the simulator broke", file=sys.stderr)
sys.exit(7)
"""


def _job(tmp_path: Path, **kw: object) -> ReplicaJob:
    base: dict[str, object] = {
        "test_path": tmp_path / "test.yaml",
        "test_name": "t",
        "run_id": "r1",
        "index": 2,
        "seed": 42,
        "store_url": str(tmp_path / "store"),
        "out_dir": tmp_path / "out",
        "wall_timeout": 60.0,
    }
    base.update(kw)
    return ReplicaJob.model_validate(base)


def _planner(tmp_path: Path, codes: str, sim: str = SIM_WAITS):
    store = LocalStore(tmp_path / "store")

    def plan(job: ReplicaJob, ports: ReplicaPorts, log_dir: Path) -> ProcessPlan:
        result = store.path(replica_key(job.namespace, job.test_name, job.run_id, job.index, "result.json"))
        runner = [sys.executable, "-c", RUNNER, str(result), str(tmp_path / "count"), codes]
        runner += [str(job.index), str(job.seed), str(tmp_path / "sim.pid")]
        return ProcessPlan(sim=[sys.executable, "-c", sim, str(tmp_path / "sim.pid")], runner=runner)

    return store, plan


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_pass_reads_result_from_store_and_stops_the_simulator(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "0")
    statuses: list[str] = []
    result = run_replica(
        _job(tmp_path),
        ports=PortAllocator(),
        store=store,
        plan=plan,
        on_status=lambda i, s: statuses.append(s),
    )
    assert result.verdict == Verdict.PASS and result.attempts == 1 and result.seed == 42
    assert result.wall_time is not None and result.wall_time > 0
    sim_pid = int((tmp_path / "sim.pid").read_text())
    deadline = time.monotonic() + 30  # the simulator is stopped (reaped) off the replica's clock
    while _pid_alive(sim_pid) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not _pid_alive(sim_pid)
    assert statuses[0] == "flying" and statuses[-1] == "pass"
    assert "runner attempt 1 on stderr" in (tmp_path / "out" / "runner.stderr.log").read_text()
    assert "sim up" in (tmp_path / "out" / "sim.stderr.log").read_text()
    stored = ReplicaResult.model_validate_json(store.get(replica_key("local", "t", "r1", 2, "result.json")))
    assert stored == result


def test_fail_is_not_retried(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "1")
    result = run_replica(_job(tmp_path), ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.FAIL and result.attempts == 1
    assert result.reason == "fail reason of attempt 1"


def test_bench_errors_are_retried_with_the_same_seed(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "3,3,0")
    result = run_replica(_job(tmp_path), ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.PASS and result.attempts == 3
    assert (tmp_path / "count.seeds").read_text().split() == ["42", "42", "42"]
    assert (tmp_path / "out" / "runner.stderr.log").read_text().count("--- attempt") == 3


def test_a_replica_that_keeps_erroring_is_reported_with_its_reason(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "3")
    result = run_replica(_job(tmp_path, retries=1), ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.ERROR and result.attempts == 2
    assert result.reason == "error reason of attempt 2 (after 2 attempts)"
    stored = json.loads(store.get(replica_key("local", "t", "r1", 2, "result.json")))
    assert stored["verdict"] == "error" and stored["attempts"] == 2


def test_a_crash_without_result_is_an_error_with_the_stderr_tail(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "7")
    result = run_replica(_job(tmp_path, retries=0), ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.ERROR
    assert result.reason == "runner crashed (exit 7): runner attempt 1 on stderr"


def test_exit_0_without_result_json_is_an_error_not_a_pass(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "0,noresult")
    result = run_replica(_job(tmp_path, retries=0), ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.ERROR
    assert "runner exited 0 but runner wrote no result.json" in result.reason


def test_bad_input_from_the_runner_is_not_retried(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "2")
    result = run_replica(_job(tmp_path), ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.ERROR and result.attempts == 1
    assert "rejected the test" in result.reason


def test_a_dead_simulator_ends_a_hanging_runner(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "0,hang,sim_dies", sim=SIM_DIES)
    job = _job(tmp_path, retries=0, sim_death_grace=0.5)
    result = run_replica(job, ports=PortAllocator(), store=store, plan=plan)
    assert result.verdict == Verdict.ERROR
    assert result.reason == "simulator exited with code 7: Traceback: the simulator broke"


def test_a_runner_over_its_wall_time_is_killed(tmp_path: Path) -> None:
    store, plan = _planner(tmp_path, "0,hang")
    result = run_replica(
        _job(tmp_path, retries=0, wall_timeout=1.0), ports=PortAllocator(), store=store, plan=plan
    )
    assert result.verdict == Verdict.ERROR
    assert result.reason == "replica did not finish within 1 s wall time"


@pytest.mark.parametrize(
    ("code", "verdict", "retry"),
    [(0, Verdict.PASS, False), (1, Verdict.FAIL, False), (3, Verdict.ERROR, True), (2, Verdict.ERROR, False)],
)
def test_classify_exit(code: int, verdict: Verdict, retry: bool) -> None:
    out = classify_exit(code)
    assert (out.verdict, out.retryable) == (verdict, retry)


def test_classify_exit_names_the_signal() -> None:
    assert classify_exit(-9).reason == "runner killed by SIGKILL"


def test_process_plan_follows_the_process_contract(tmp_path: Path) -> None:
    job = _job(tmp_path)
    plan = plan_processes(job, ReplicaPorts(api=21000, gcs=21001), tmp_path / "logs")
    sim, runner = " ".join(plan.sim), " ".join(plan.runner)
    assert "uavtest.engine.entry sitl" in sim and "--lockstep" in sim and "--seed 42" in sim
    assert "--api-port 21000" in sim and "--gcs-port 21001" in sim and f"--log-dir {tmp_path / 'logs'}" in sim
    assert "uavtest.engine.entry runner" in runner and "--connect udpin:127.0.0.1:21000" in runner
    assert "--replica 2" in runner and "--seed 42" in runner and "--run-id r1" in runner
    assert f"--store {tmp_path / 'store'}" in runner and "--namespace local" in runner


def test_px4_plan_uses_the_instance_number(tmp_path: Path) -> None:
    px4 = tmp_path / "build" / "bin" / "px4"
    job = _job(tmp_path, simulator=Simulator.PX4, px4_bin=px4)
    plan = plan_processes(job, ReplicaPorts(api=14543, gcs=0, instance=3), tmp_path / "w")
    assert plan.sim[:3] == [str(px4.resolve()), "-i", "3"]
    assert plan.sim[-1] == str((tmp_path / "build" / "etc").resolve())
    assert "udpin:127.0.0.1:14543" in plan.runner and plan.sim_cwd == tmp_path / "w"
