"""`uavtest runner` against the real built-in simulator (`uavtest sitl`) over real UDP.

Both are started as processes on free loopback ports, as the local engine and a Kubernetes pod
start them (contract 4): the sim sends to the runner's bound port, in lockstep, and writes its
ULog into a shared directory; the runner stores its artifacts in a LocalStore.
"""

from __future__ import annotations

import contextlib
import json
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import yaml

from harness.sitl import stop_process
from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.analysis.trajectory import Trajectory

pytestmark = pytest.mark.integration

UAVTEST = [sys.executable, "-m", "uavtest.cli"]
RUN_TIMEOUT = 180  # wall seconds a whole replica may take before the test gives up


def udp_ports(n: int) -> list[int]:
    """N distinct UDP ports free on 127.0.0.1 right now."""
    socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(n)]
    try:
        for s in socks:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def write_test(path: Path, name: str, spec: dict[str, Any]) -> Path:
    doc = {"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest", "metadata": {"name": name}, "spec": spec}
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


SHORT_MISSION: dict[str, Any] = {
    "timeout": 120,
    "vehicle": {"params": {"MPC_XY_CRUISE": 5.0, "NAV_ACC_RAD": 1.0}},
    "mission": {"takeoffAltitude": 5, "waypoints": [{"x": 12, "y": 0, "z": -5}]},
}


@dataclass
class Replica:
    """One replica's processes and folders."""

    test: Path
    api_port: int
    gcs_port: int
    log_dir: Path
    store: Path
    run_id: str = "it"
    seed: int = 1

    def sim_cmd(self) -> list[str]:
        return [
            *UAVTEST, "sitl", "--test", str(self.test), "--seed", str(self.seed),
            "--host", "127.0.0.1", "--api-port", str(self.api_port), "--gcs-port", str(self.gcs_port),
            "--api-local-port", "0", "--gcs-local-port", "0", "--log-dir", str(self.log_dir), "--lockstep",
        ]  # fmt: skip

    def runner_cmd(self, *extra: str) -> list[str]:
        return [
            *UAVTEST, "runner", "--test", str(self.test), "--replica", "0", "--seed", str(self.seed),
            "--connect", f"udpin:127.0.0.1:{self.api_port}", "--store", str(self.store),
            "--run-id", self.run_id, "--log-dir", str(self.log_dir), *extra,
        ]  # fmt: skip

    def artifact(self, name: str) -> Path:
        test_name = yaml.safe_load(self.test.read_text())["metadata"]["name"]
        return self.store / "local" / test_name / self.run_id / "replica-0" / name


@contextlib.contextmanager
def simulator(replica: Replica, tmp_path: Path) -> Iterator[subprocess.Popen[bytes]]:
    log = open(tmp_path / f"sitl-{replica.run_id}.log", "wb")  # noqa: SIM115
    proc = subprocess.Popen(replica.sim_cmd(), stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        yield proc
    finally:
        stop_process(proc, timeout=15.0)
        log.close()


def make_replica(tmp_path: Path, spec: dict[str, Any], name: str = "short-mission", **kw: Any) -> Replica:
    api, gcs = udp_ports(2)
    log_dir = tmp_path / f"logs-{kw.get('run_id', 'it')}"
    log_dir.mkdir()
    return Replica(
        write_test(tmp_path / f"{name}.yaml", name, spec), api, gcs, log_dir, tmp_path / "store", **kw
    )


def run_runner(replica: Replica, *extra: str) -> tuple[int, ReplicaResult, str]:
    done = subprocess.run(
        replica.runner_cmd(*extra),
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT,
        stdin=subprocess.DEVNULL,
    )
    lines = done.stdout.strip().splitlines()
    assert lines, f"runner printed nothing; stderr:\n{done.stderr[-3000:]}"
    return done.returncode, ReplicaResult.model_validate_json(lines[-1]), done.stderr


def fly(tmp_path: Path, replica: Replica) -> tuple[int, ReplicaResult, str]:
    with simulator(replica, tmp_path):
        return run_runner(replica)


def test_a_waypoint_mission_passes_and_stores_the_three_artifacts(tmp_path: Path) -> None:
    replica = make_replica(tmp_path, SHORT_MISSION)
    code, result, stderr = fly(tmp_path, replica)
    assert result.verdict is Verdict.PASS, f"{result.reason}\n{stderr[-3000:]}"
    assert code == 0
    assert result.reason == "" and result.sim_time is not None and result.sim_time > 5
    for name in ("flight.ulg", "trajectory.csv", "result.json"):
        assert replica.artifact(name).is_file(), name
    stored = ReplicaResult.model_validate_json(replica.artifact("result.json").read_text())
    assert stored == result
    traj = Trajectory.from_csv(replica.artifact("trajectory.csv").read_text())
    assert traj.x.max() > 11  # reached the waypoint 12 m north (1 m acceptance radius)
    assert -traj.z.min() > 4  # took off to about 5 m
    assert replica.artifact("flight.ulg").read_bytes()[:7] == b"ULog\x01\x12\x35"
    assert "lockstep" in stderr  # it ran in lockstep with the built-in simulator


def test_a_flight_into_an_obstacle_fails_naming_the_assertion(tmp_path: Path) -> None:
    wall = {"size": {"l": 2, "w": 10, "h": 20}, "position": {"x": 6, "y": 0, "z": 0}}
    spec = {**SHORT_MISSION, "world": {"obstacles": [wall]}}
    replica = make_replica(tmp_path, spec, name="into-a-wall")
    code, result, stderr = fly(tmp_path, replica)
    assert result.verdict is Verdict.FAIL, f"{result.reason}\n{stderr[-3000:]}"
    assert code == 1
    assert "flight ends at vehicle time" in stderr and ": collision" in stderr  # stopped at the contact
    failed = {a.name: a for a in result.assertions if not a.passed}
    # the judged log puts the vehicle at (or within centimetres of) the wall: a hard or a soft fail
    assert {"noCollision", "minObstacleDistance"} & set(failed), result.reason
    assert result.metrics is not None and result.metrics.min_obstacle_distance is not None
    assert result.metrics.min_obstacle_distance < 0.2
    assert "min distance" in result.reason or "collision" in result.reason.lower()
    assert replica.artifact("flight.ulg").is_file() and replica.artifact("trajectory.csv").is_file()


def test_no_simulator_at_all_is_an_error_with_exit_3(tmp_path: Path) -> None:
    replica = make_replica(tmp_path, SHORT_MISSION)
    code, result, _ = run_runner(replica, "--connect-timeout", "2")
    assert code == 3
    assert result.verdict is Verdict.ERROR
    assert result.reason == f"no heartbeat from udpin:127.0.0.1:{replica.api_port} within 2 s"
    stored = json.loads(replica.artifact("result.json").read_text())
    assert stored["verdict"] == "error" and stored["reason"] == result.reason
    assert not replica.artifact("flight.ulg").exists()


def test_a_taken_port_is_an_error_naming_it(tmp_path: Path) -> None:
    replica = make_replica(tmp_path, SHORT_MISSION)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as holder:
        holder.bind(("127.0.0.1", replica.api_port))
        code, result, _ = run_runner(replica)
    assert code == 3 and result.verdict is Verdict.ERROR
    assert result.reason.startswith(f"port {replica.api_port} is taken")


def test_the_simulator_dying_mid_flight_is_an_error_not_a_fail(tmp_path: Path) -> None:
    replica = make_replica(tmp_path, SHORT_MISSION)
    with simulator(replica, tmp_path) as sim:
        runner = subprocess.Popen(
            replica.runner_cmd(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            stdin=subprocess.DEVNULL,
        )
        try:
            assert runner.stderr is not None
            deadline = time.monotonic() + RUN_TIMEOUT
            for line in runner.stderr:  # wait for the flight to start, then kill the simulator
                if "flight starts at vehicle time" in line:
                    sim.kill()
                    break
                assert time.monotonic() < deadline, "the flight never started"
            out, _ = runner.communicate(timeout=RUN_TIMEOUT)
        finally:
            if runner.poll() is None:
                runner.kill()
    result = ReplicaResult.model_validate_json(out.strip().splitlines()[-1])
    assert runner.returncode == 3 and result.verdict is Verdict.ERROR
    assert "went silent" in result.reason
    assert replica.artifact("result.json").is_file()


REBOOTED = re.compile(
    r"^the vehicle rebooted mid-flight \(time since boot went from (\d+\.\d) s to (\d+\.\d) s\): "
    r"simulator restarted; no verdict on a half flight$"
)


def free_running(argv: list[str], speed_factor: float = 3.0) -> list[str]:
    """The simulator's command line without lockstep: it runs on its own clock, as PX4 SITL does."""
    return [a for a in argv if a != "--lockstep"] + ["--speed-factor", str(speed_factor)]


def restart_simulator_mid_flight(
    replica: Replica, tmp_path: Path, sim_argv: list[str]
) -> tuple[int, str, str]:
    """Fly with a simulator that is SIGKILLed once the vehicle is armed and started again on the
    same port (a Kubernetes sidecar restarting); returns the runner's exit code, stdout, stderr."""
    logs = [open(tmp_path / f"sitl-{n}.log", "wb") for n in ("first", "second")]  # noqa: SIM115
    sims = [subprocess.Popen(sim_argv, stdout=logs[0], stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)]
    runner = subprocess.Popen(
        replica.runner_cmd(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        stdin=subprocess.DEVNULL,
    )
    try:
        assert runner.stderr is not None
        seen = []
        for line in runner.stderr:  # wait until the vehicle flies, then crash and restart it
            seen.append(line)
            if re.search(r"vehicle \d+/\d+: .*, armed$", line.rstrip()):
                sims[0].kill()
                sims[0].wait(10)
                sims.append(
                    subprocess.Popen(
                        sim_argv, stdout=logs[1], stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
                    )
                )
                break
        assert len(sims) == 2, "the vehicle never armed:\n" + "".join(seen)[-3000:]
        out, err = runner.communicate(timeout=RUN_TIMEOUT)
        return runner.returncode, out, "".join(seen) + err
    finally:
        for proc in (runner, *sims):
            if proc.poll() is None:
                proc.kill()
                proc.wait(10)
        for f in logs:
            f.close()


@pytest.mark.parametrize("lockstep", [True, False], ids=["lockstep", "free-running"])
def test_a_simulator_restarted_mid_flight_is_an_error_not_a_verdict_on_half_a_flight(
    tmp_path: Path, lockstep: bool
) -> None:
    replica = make_replica(tmp_path, SHORT_MISSION)
    argv = replica.sim_cmd() if lockstep else free_running(replica.sim_cmd())
    code, out, stderr = restart_simulator_mid_flight(replica, tmp_path, argv)
    result = ReplicaResult.model_validate_json(out.strip().splitlines()[-1])
    assert (code, result.verdict) == (3, Verdict.ERROR), f"{result.reason}\n{stderr[-3000:]}"
    times = REBOOTED.match(result.reason)
    assert times is not None, result.reason
    assert float(times[2]) < float(times[1])
    stored = ReplicaResult.model_validate_json(replica.artifact("result.json").read_text())
    assert stored.verdict is Verdict.ERROR and stored.reason == result.reason


def test_a_free_running_simulator_flight_is_judged_as_usual(tmp_path: Path) -> None:
    """Without lockstep (as with PX4) a landing still ends the flight and the verdict is given."""
    replica = make_replica(tmp_path, SHORT_MISSION)
    log = open(tmp_path / "sitl.log", "wb")  # noqa: SIM115
    sim = subprocess.Popen(free_running(replica.sim_cmd()), stdout=log, stderr=subprocess.STDOUT)
    try:
        code, result, stderr = run_runner(replica)
    finally:
        sim.terminate()
        sim.wait(15)
        log.close()
    assert (code, result.verdict) == (0, Verdict.PASS), f"{result.reason}\n{stderr[-3000:]}"
    assert "lockstep" not in stderr and "rebooted" not in stderr


def test_the_same_seed_flies_the_same_trajectory(tmp_path: Path) -> None:
    spec = {**SHORT_MISSION, "world": {"wind": {"meanSpeed": 3, "maxSpeed": 6, "direction": 90}}}
    first = make_replica(tmp_path, spec, name="windy", run_id="a", seed=5)
    second = make_replica(tmp_path, spec, name="windy", run_id="b", seed=5)
    other = make_replica(tmp_path, spec, name="windy", run_id="c", seed=6)
    csv = []
    for replica in (first, second, other):
        _, result, stderr = fly(tmp_path, replica)
        assert result.verdict is not Verdict.ERROR, f"{result.reason}\n{stderr[-3000:]}"
        csv.append(replica.artifact("trajectory.csv").read_text())
    assert csv[0] == csv[1]  # lockstep: identical, sample for sample
    assert csv[0] != csv[2]


def test_the_grant_size_changes_the_cost_not_the_flight(tmp_path: Path) -> None:
    # commands land exactly on their vehicle times and command sequences step in fine grants,
    # so 50 ms grants (one round trip each) and the default large grants fly the same trajectory
    spec = {**SHORT_MISSION, "commands": [{"at": 1, "action": "mode", "mode": "mission"}]}
    spec["commands"].append({"at": 9.37, "action": "speed", "speed": 2.5})
    fine = make_replica(tmp_path, spec, name="grants", run_id="fine", seed=3)
    large = make_replica(tmp_path, spec, name="grants", run_id="large", seed=3)
    grants = []
    for replica, extra in ((fine, ("--step-ms", "50")), (large, ())):
        with simulator(replica, tmp_path):
            _, result, stderr = run_runner(replica, *extra)
        assert result.verdict is Verdict.PASS, f"{result.reason}\n{stderr[-3000:]}"
        counted = re.search(r"; (\d+) grants", stderr)
        assert counted is not None, stderr[-3000:]
        grants.append(int(counted.group(1)))
    assert fine.artifact("trajectory.csv").read_text() == large.artifact("trajectory.csv").read_text()
    assert grants[1] * 4 < grants[0]  # far fewer round trips


def test_without_a_shared_log_folder_the_runner_downloads_the_log_over_mavlink(tmp_path: Path) -> None:
    # as against PX4 without a shared folder: the simulator serves its finished log through the
    # MAVLink log protocol, and the runner stores exactly the bytes the simulator wrote
    replica = make_replica(tmp_path, SHORT_MISSION, name="download")
    cmd = replica.runner_cmd()
    at = cmd.index("--log-dir")
    del cmd[at : at + 2]
    with simulator(replica, tmp_path):
        done = subprocess.run(
            cmd, capture_output=True, text=True, timeout=RUN_TIMEOUT, stdin=subprocess.DEVNULL
        )
    result = ReplicaResult.model_validate_json(done.stdout.strip().splitlines()[-1])
    assert result.verdict is Verdict.PASS, f"{result.reason}\n{done.stderr[-3000:]}"
    assert done.returncode == 0
    assert re.search(r"downloading log 0 \(\d+ bytes\)", done.stderr), done.stderr[-3000:]
    written = sorted(replica.log_dir.glob("*.ulg"))
    assert len(written) == 1
    assert replica.artifact("flight.ulg").read_bytes() == written[0].read_bytes()


def test_a_shared_folder_without_a_log_falls_back_to_the_mavlink_download(tmp_path: Path) -> None:
    # as against a PX4 image that writes its log in its own working directory, not in the pod's
    # shared emptyDir: the runner finds nothing there and downloads the log from the vehicle
    replica = make_replica(tmp_path, SHORT_MISSION, name="fallback")
    elsewhere = tmp_path / "shared-but-empty"
    elsewhere.mkdir()
    cmd = replica.runner_cmd()
    cmd[cmd.index("--log-dir") + 1] = str(elsewhere)
    with simulator(replica, tmp_path):
        done = subprocess.run(
            cmd, capture_output=True, text=True, timeout=RUN_TIMEOUT, stdin=subprocess.DEVNULL
        )
    result = ReplicaResult.model_validate_json(done.stdout.strip().splitlines()[-1])
    assert result.verdict is Verdict.PASS, f"{result.reason}\n{done.stderr[-3000:]}"
    assert "downloading it from the vehicle over MAVLink" in done.stderr
    written = sorted(replica.log_dir.glob("*.ulg"))
    assert len(written) == 1
    assert replica.artifact("flight.ulg").read_bytes() == written[0].read_bytes()
    assert list(elsewhere.iterdir()) == []
