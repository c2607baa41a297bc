"""MAVProxy, the console many PX4 and ArduPilot users fly from, against `uavtest sitl`.

A real ``mavproxy.py`` process on the simulator's API link, driven through its console (stdin)
as a person types: it fetches the parameters, sets one, uploads a QGC WPL mission (``wp load``;
an ArduPilot-style file, home first, is refused as PX4 refuses it), starts it with ``long
MAV_CMD_MISSION_START`` (which arms PX4 and flies the mission) and sees the
vehicle's STATUSTEXTs through to the landing and disarm; a ``long DO_SET_MODE`` into Position
mode without sticks is TEMPORARILY_REJECTED, as PX4 v1.15 does.
"""

from __future__ import annotations

import queue
import re
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from harness.net import free_udp_port
from harness.sitl import free_running_argv, running_sitl

pytestmark = pytest.mark.integration

pytest.importorskip("MAVProxy", reason="MAVProxy is not installed (pip install '.[test]')")

HOME = (47.397742, 8.545594, 488.0)
#: QGC WPL 110 as an ArduPilot user writes it: home as item 0 (a waypoint on the ground), then
#: takeoff to 5 m, 20 m North, land there. MAVProxy sends item 0 as it is: PX4 v1.15 refuses the
#: mission ("Mission rejected: takeoff not first waypoint item")
ARDUPILOT_STYLE = """QGC WPL 110
0\t1\t0\t16\t0\t0\t0\t0\t47.397742\t8.545594\t488.0\t1
1\t0\t3\t22\t0\t0\t0\t0\t47.397742\t8.545594\t5.0\t1
2\t0\t3\t16\t0\t0\t0\t0\t47.397922\t8.545594\t5.0\t1
3\t0\t3\t21\t0\t0\t0\t0\t47.397922\t8.545594\t0.0\t1
"""
#: the same mission as PX4 flies it: the takeoff first (frame 3: relative altitude)
MISSION = """QGC WPL 110
0\t1\t3\t22\t0\t0\t0\t0\t47.397742\t8.545594\t5.0\t1
1\t0\t3\t16\t0\t0\t0\t0\t47.397922\t8.545594\t5.0\t1
2\t0\t3\t21\t0\t0\t0\t0\t47.397922\t8.545594\t0.0\t1
"""


class Console:
    """A ``mavproxy.py`` process: ``type`` a line into its console, ``expect`` a line out of it."""

    def __init__(self, port: int, workdir: Path) -> None:
        exe = shutil.which("mavproxy.py")
        if exe is None:
            pytest.skip("mavproxy.py is not on PATH")
        self.proc = subprocess.Popen(
            [exe, f"--master=udpin:127.0.0.1:{port}", f"--state-basedir={workdir}", "--aircraft=uavtest"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            cwd=workdir,
            bufsize=1,
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip())

    def type(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def expect(self, pattern: str, seconds: float) -> str:
        """The first console line from now on that matches ``pattern`` (a regular expression)."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                line = self.lines.get(timeout=0.2)
            except queue.Empty:
                continue
            self.seen.append(line)
            if re.search(pattern, line):
                return line
        last = self.seen[-15:]
        raise AssertionError(f"MAVProxy never printed /{pattern}/ in {seconds} s; last lines: {last}")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


@pytest.fixture
def mavproxy(tmp_path: Path) -> Iterator[Console]:
    port = free_udp_port()
    # MAVProxy first, listening, then the simulator: free-running, it says "Ready for takeoff"
    # once, which a MAVProxy still starting on a busy machine would miss
    console = Console(port, tmp_path)
    try:
        console.expect(r"Waiting for heartbeat", 60)
        with running_sitl(free_running_argv(port, tmp_path / "log", 5)):
            yield console
    finally:
        console.close()


def test_mavproxy_sets_a_parameter_uploads_and_flies_a_mission(mavproxy: Console, tmp_path: Path) -> None:
    c = mavproxy
    c.expect(r"Detected vehicle 1:1", 30)
    c.expect(r"Ready for takeoff", 30)
    # MAVProxy asks for the parameters over MAVLink FTP first: refused at once, it falls back
    c.expect(r"MAVLink FTP not supported", 30)
    c.expect(r"Received \d+ parameters", 30)
    c.type("param set MIS_TAKEOFF_ALT 5")
    time.sleep(1.0)  # the PARAM_VALUE that confirms it updates MAVProxy's copy
    c.type("param show MIS_TAKEOFF_ALT")
    c.expect(r"MIS_TAKEOFF_ALT\s+5(\.0*)?$", 10)
    (tmp_path / "ardupilot.txt").write_text(ARDUPILOT_STYLE)
    c.type(f"wp load {tmp_path / 'ardupilot.txt'}")
    c.expect(r"MISSION_ACK: TYPE_MISSION: ACCEPTED", 10)  # stored, but not valid:
    c.expect(r"Mission rejected: takeoff not first waypoint item", 10)
    # MAVProxy's `mode MISSION` fails for PX4 in MAVProxy itself (pymavlink's set_mode_px4 gets
    # px4_map's tuple): PX4 users send the command; MISSION_START arms and starts the mission
    c.type("long MAV_CMD_MISSION_START 0 0")
    c.expect(r"Mission start denied! No valid mission", 10)
    (tmp_path / "mission.txt").write_text(MISSION)
    c.type(f"wp load {tmp_path / 'mission.txt'}")
    c.expect(r"MISSION_ACK: TYPE_MISSION: ACCEPTED", 10)
    c.type("long MAV_CMD_MISSION_START 0 0")
    c.expect(r"COMMAND_ACK: MISSION_START: ACCEPTED", 10)
    c.expect(r"Climb to 5\.0 meters above home", 10)  # the takeoff item, from the ground
    c.expect(r"Takeoff detected", 30)
    c.type("long MAV_CMD_DO_SET_MODE 1 3 0")  # from component 0: the ACK alone, as PX4 does
    c.expect(r"COMMAND_ACK: DO_SET_MODE: TEMPORARILY_REJECTED", 10)
    c.expect(r"Landing detected", 60)
    c.expect(r"Disarmed by landing", 20)
