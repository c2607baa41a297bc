"""`uavtest sitl` as a process: it ends promptly on SIGTERM, and never outlives its client or parent.

Each test waits for a condition with a generous deadline; the deadlines are far shorter than
what the simulator would take without the behaviour under test (its select timeout at a tiny
speed factor, or forever).
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink2
from pyulog import ULog

from harness.net import free_udp_port

pytestmark = pytest.mark.integration

DEADLINE_S = 15.0


def wait_for(condition: Callable[[], bool], deadline_s: float = DEADLINE_S, poll_s: float = 0.05) -> bool:
    end = time.monotonic() + deadline_s
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(poll_s)
    return condition()


class Client:
    """A bound UDP socket like a runner's (udpin), speaking MAVLink as a ground station."""

    def __init__(self) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(1.0)
        self.port = self.sock.getsockname()[1]
        self.mav = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
        self.peer: tuple[str, int] | None = None

    def wait_heartbeat(self) -> None:
        parser = mavlink2.MAVLink(None)
        parser.robust_parsing = True
        end = time.monotonic() + DEADLINE_S
        while time.monotonic() < end:
            try:
                data, self.peer = self.sock.recvfrom(65535)
            except TimeoutError:
                continue
            for m in parser.parse_buffer(data) or []:
                if m.get_type() == "HEARTBEAT":
                    return
        raise AssertionError("no heartbeat from the simulator")

    def send_heartbeat(self) -> None:
        assert self.peer is not None
        self.sock.sendto(self.mav.heartbeat_encode(6, 8, 0, 0, 4).pack(self.mav), self.peer)

    def close(self) -> None:
        self.sock.close()


def sitl_argv(port: int, log_dir: Path, *extra: str) -> list[str]:
    return [
        sys.executable,
        "-m",
        "uavtest.cli",
        "sitl",
        "--seed",
        "3",
        "--api-port",
        str(port),
        "--api-local-port",
        "0",
        "--gcs-port",
        str(free_udp_port()),
        "--gcs-local-port",
        "0",
        "--log-dir",
        str(log_dir),
        *extra,
    ]


@pytest.fixture
def client() -> Iterator[Client]:
    c = Client()
    yield c
    c.close()


def log_closed(log_dir: Path) -> bool:
    return bool(list(log_dir.glob("*.ulg"))) and not list(log_dir.glob("*.part"))


def test_sigterm_ends_a_slow_simulator_at_once(client: Client, tmp_path: Path):
    # at speed factor 0.001 the simulator waits 20 s in select between steps: only the wake-up
    # pipe lets a SIGTERM end that wait
    proc = subprocess.Popen(sitl_argv(client.port, tmp_path, "--speed-factor", "0.001"))
    try:
        client.wait_heartbeat()
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=10) == 0
        assert log_closed(tmp_path)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_lockstep_simulator_exits_when_its_client_goes_silent(client: Client, tmp_path: Path):
    proc = subprocess.Popen(sitl_argv(client.port, tmp_path, "--lockstep", "--idle-exit", "1"))
    try:
        client.wait_heartbeat()
        client.send_heartbeat()  # a client was heard; then it vanishes
        assert wait_for(lambda: proc.poll() is not None), "the simulator kept waiting for its client"
        assert proc.returncode == 0
        assert log_closed(tmp_path)
        (log,) = tmp_path.glob("*.ulg")
        assert ULog(str(log)).get_dataset("vehicle_local_position").data["x"].size > 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _running(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie (a reparented child may not be reaped here)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    state = next((ln for ln in status.splitlines() if ln.startswith("State:")), "")
    return "Z" not in state.split(":", 1)[-1][:3]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_lockstep_simulator_exits_when_its_parent_dies(client: Client, tmp_path: Path):
    # a parent that starts the simulator and is then killed, like an engine killed with SIGKILL
    starter = (
        "import subprocess, sys, time; "
        f"p = subprocess.Popen({sitl_argv(client.port, tmp_path, '--lockstep')!r}); "
        "print(p.pid, flush=True); time.sleep(600)"
    )
    parent = subprocess.Popen([sys.executable, "-c", starter], stdout=subprocess.PIPE, text=True)
    assert parent.stdout is not None
    pid = int(parent.stdout.readline())
    try:
        client.wait_heartbeat()
        client.send_heartbeat()
        assert _running(pid)
        parent.kill()
        parent.wait()
        assert wait_for(lambda: not _running(pid)), "the simulator outlived its parent"
        assert wait_for(lambda: log_closed(tmp_path))
    finally:
        parent.kill()
        parent.wait()
        if _running(pid):
            os.kill(pid, signal.SIGKILL)
