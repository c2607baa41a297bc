"""Speed of the built-in simulator on the competition's mission2 (prints numbers; no assertions).

1. in-process: the vehicle alone flies mission2 (no sockets), with and without its ULog;
2. over UDP: ``uavtest sitl --lockstep`` as a process and a minimal lockstep client written
   here (params, mission upload, arm, mission mode, fixed grants of 50, 200 and 1000 ms — the
   runner's default is up to 1000 ms, shorter only around commands, sticks and obstacles),
   start-up included. Once connected the client asks for the telemetry it reads, as the runner
   does (``uavtest.runner.streams``); ``--all-streams`` keeps PX4's full ONBOARD default rates
   (~300 messages per simulated second) to show what a client that takes everything costs.

PX4 v1.15 SIH on this machine, for comparison: at most ~18x real time (speed factor 20 uses
1.2 cores), ~36 s of simulated boot before it is ready for takeoff.

Usage: python bench/bench_sitl.py [--data ../shared/data] [--repeat 3] [--all-streams]
"""

from __future__ import annotations

import argparse
import math
import resource
import select
import socket
import subprocess
import sys
import time
from pathlib import Path

from uavtest.engine.replica import sitl_command

try:  # the runner's stream requests (absent from trees older than PX4's per-link rates)
    from uavtest.runner.streams import STREAM_INTERVALS_US
except ImportError:  # pragma: no cover - benchmarking an older tree side by side
    STREAM_INTERVALS_US = {}
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mav import Msg
from uavtest.sitl.mavlink_io import Codec
from uavtest.sitl.mission import from_spec
from uavtest.sitl.params import encode_param_value
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.loaders import load_test
from uavtest.spec.mission import mission_items


def in_process(test: Path, repeat: int) -> None:
    spec = load_test(test).spec
    items = from_spec(mission_items(spec))
    for with_log in (False, True):
        rates, cpus, flights = [], [], []
        for seed in range(repeat):
            sink = MemorySink() if with_log else None
            t0 = time.process_time()
            flight = fly_mission(SimConfig.from_spec(spec, seed), items, sink=sink)
            cpu = time.process_time() - t0
            sim_s = flight.samples[-1][0]
            rates.append(sim_s / cpu)
            cpus.append(cpu)
            flights.append(flight.flight_time or math.nan)
        label = "with ULog" if with_log else "no log   "
        print(
            f"in-process, {label}: {sum(cpus) / repeat:.3f} s CPU per flight "
            f"({sim_s:.1f} s simulated, flight time {sum(flights) / repeat:.1f} s): "
            f"{sum(rates) / repeat:,.0f}x real time"
        )


class LockstepClient:
    """Just enough of a ground station to fly a mission against ``uavtest sitl --lockstep``."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.codec = Codec(255, 190)
        self.peer: tuple[str, int] | None = None
        self.t_ms = -1
        self.received = 0
        self.owed = False  # an announce not yet answered with a grant

    def send(self, msg_name: str, /, **fields: object) -> None:
        assert self.peer is not None
        self.sock.sendto(self.codec.encode(Msg(msg_name, fields)), self.peer)

    def messages(self, timeout: float = 10.0) -> list[Msg]:
        ready, _, _ = select.select([self.sock], [], [], timeout)
        if not ready:
            raise TimeoutError("the simulator is silent")
        data, self.peer = self.sock.recvfrom(65535)
        msgs = self.codec.decode(data)
        self.received += len(msgs)
        for m in msgs:
            if m.name == "NAMED_VALUE_INT" and m.fields["name"] == "LOCKSTEP":
                self.t_ms = max(self.t_ms, int(m.fields["value"]))
        return msgs

    def until(self, cond, *, grant: bool = True, step_ms: int = 50) -> Msg:
        """The first message for which ``cond`` holds; grants time on each announce while waiting.

        An announce that arrives while the client is not granting (or in the same datagram as the
        awaited message) is owed a grant: it is sent when the client next grants, else the
        simulator would wait for it forever.
        """
        while True:
            if grant and self.owed:
                self.owed = False
                self.send(
                    "NAMED_VALUE_INT", time_boot_ms=self.t_ms, name="LOCKSTEP", value=self.t_ms + step_ms
                )
            found = None
            for m in self.messages():
                if m.name == "NAMED_VALUE_INT" and m.fields["name"] == "LOCKSTEP":
                    self.owed = True
                if found is None and cond(m):
                    found = m
            if found is not None:
                return found


def over_udp(
    test: Path, seed: int, step_ms: int = 50, *, all_streams: bool = False
) -> tuple[float, float, float, int, float, float]:
    spec = load_test(test).spec
    items = from_spec(mission_items(spec))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    wall0 = time.monotonic()
    cpu0 = time.process_time()
    children0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    client = LockstepClient(port)
    proc = subprocess.Popen(
        sitl_command(sys.executable, test, seed, api_port=port, log_dir=Path("/tmp/uavtest-bench-log")),
        stderr=subprocess.DEVNULL,
    )
    try:
        client.until(lambda m: m.name == "HEARTBEAT", grant=False)
        startup = time.monotonic() - wall0
        for msg_id, interval in ({} if all_streams else STREAM_INTERVALS_US).items():
            client.send(
                "COMMAND_LONG",
                target_system=1,
                target_component=1,
                command=511,
                param1=msg_id,
                param2=interval,
            )
            client.until(lambda m: m.name == "COMMAND_ACK", grant=False)
        for name, value in spec.vehicle.params.items():
            ptype = 6 if isinstance(value, int) else 9
            client.send(
                "PARAM_SET",
                target_system=1,
                target_component=1,
                param_id=name,
                param_value=encode_param_value(value, ptype),
                param_type=ptype,
            )
            client.until(lambda m, n=name: m.name == "PARAM_VALUE" and m.fields["param_id"] == n, grant=False)
        client.send("MISSION_COUNT", target_system=1, target_component=1, count=len(items), mission_type=0)
        while True:
            m = client.until(lambda m: m.name in ("MISSION_REQUEST_INT", "MISSION_ACK"), grant=False)
            if m.name == "MISSION_ACK":
                break
            it = items[m.fields["seq"]]
            client.send(
                "MISSION_ITEM_INT",
                target_system=1,
                target_component=1,
                seq=it.seq,
                frame=it.frame,
                command=it.command,
                current=0,
                autocontinue=1,
                param1=it.param1,
                param2=it.param2,
                param3=it.param3,
                param4=it.param4,
                x=it.x,
                y=it.y,
                z=it.z,
                mission_type=0,
            )
        client.until(lambda m: m.name == "STATUSTEXT" and "Ready" in m.fields["text"], step_ms=step_ms)
        client.send("COMMAND_LONG", target_system=1, target_component=1, command=400, param1=1.0)
        client.until(lambda m: m.name == "COMMAND_ACK", grant=False)
        client.send(
            "COMMAND_LONG",
            target_system=1,
            target_component=1,
            command=176,
            param1=1.0,
            param2=4.0,
            param3=4.0,
        )
        client.until(lambda m: m.name == "COMMAND_ACK", grant=False)
        client.until(
            lambda m: m.name == "HEARTBEAT" and not int(m.fields["base_mode"]) & 128 and client.t_ms > 5000,
            step_ms=step_ms,
        )
        wall = time.monotonic() - wall0
        client_cpu = time.process_time() - cpu0
    finally:
        proc.terminate()
        proc.wait(10)
        client.sock.close()
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    sim_cpu = children.ru_utime + children.ru_stime - children0.ru_utime - children0.ru_stime
    return client.t_ms / 1000.0, wall, startup, client.received, sim_cpu, client_cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--all-streams", action="store_true", help="keep PX4's full ONBOARD stream rates")
    args = ap.parse_args()
    test = args.data / "competition" / "snippets" / "case_studies" / "mission2.yaml"
    in_process(test, args.repeat)
    for step_ms in (50, 200, 1000):
        for seed in range(args.repeat):
            sim_s, wall_s, startup, n, sim_cpu, client_cpu = over_udp(
                test, seed, step_ms, all_streams=args.all_streams
            )
            print(
                f"over UDP, lockstep grants of {step_ms} ms, seed {seed}: {sim_s:.1f} s simulated in "
                f"{wall_s:.2f} s wall = {sim_s / wall_s:.0f}x real time, start-up included "
                f"({startup:.2f} s of "
                f"it until the first heartbeat; {sim_s / (wall_s - startup):.0f}x without); "
                f"CPU: sim process {sim_cpu:.2f} s "
                f"(start-up included), client {client_cpu:.2f} s; {n} messages to the client"
            )
    print("PX4 v1.15 SIH here: <= ~18x real time, ~36 s simulated boot before it is ready")


if __name__ == "__main__":
    main()
