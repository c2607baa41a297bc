"""The ``uavtest sitl`` process: UDP links, the clock (lockstep or speed factor), signals, log files.

This is the I/O edge around the pure ``Vehicle``:

- two MAVLink links like PX4 SITL's: the API link sends from local port ``api_port + 40``
  (14580) to ``host:api_port`` (14540), the GCS link from 18570 to ``host:gcs_port`` (14550).
  Each link answers wherever its client's packets come from. Each streams its own telemetry
  from boot at PX4's rates for its mode (``telemetry.MODES``, as ``px4-rc.mavlink`` starts
  them: the API link ONBOARD, the GCS link NORMAL with its SITL 50 Hz streams), as PX4 SITL
  streams to 127.0.0.1:14550 before any ground station has spoken.
- lockstep (``--lockstep``): the vehicle clock moves only when a client grants time. The sim
  announces ``NAMED_VALUE_INT(time_boot_ms=T, name="LOCKSTEP", value=T)`` once everything due
  at T is sent; a grant is ``NAMED_VALUE_INT(name="LOCKSTEP", value=T_until)``; messages that
  arrive before a grant are handled first, in order. While waiting, protocols are answered and
  the announce (with a heartbeat) is repeated every ``REANNOUNCE_S`` of wall time
  (``SEARCH_REANNOUNCE_S`` until a client has spoken: a runner started at the same time finds
  the simulator as soon as it has bound its port). Each step's
  telemetry and its announce leave in one datagram per link (several only past
  ``DATAGRAM_BYTES``); a link no client has spoken on (the GCS link under the engine) gets the
  announce only with the wall-clock re-announce, not every step.
- a lockstep simulator ends by itself, closing its log, when no client has sent anything for
  ``--idle-exit`` wall seconds (default 60) after one was heard, or when its parent process
  dies (checked on the re-announce timer): a client that vanished leaves no process behind.
- free-running (default): the vehicle clock runs at ``speed_factor`` times the wall clock.
- logs: ``<log_dir>/seed<S>-<n>.ulg`` (``.ulg.part`` while open); SIGTERM/SIGINT close the log
  cleanly and end the process with exit code 0, at once: a wake-up pipe
  (``signal.set_wakeup_fd``) ends the ``select`` wait as the signal arrives. Finished logs can
  also be downloaded over MAVLink as from PX4 (``uavtest.sitl.logserver``), streamed to the link
  that asked in batches every ``LOG_PACE_S``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import os
import select
import signal
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType

from uavtest.errors import BadInput, InfrastructureError
from uavtest.sitl.logserver import LogServer, log_folder
from uavtest.sitl.mav import Msg
from uavtest.sitl.mavlink_io import Codec
from uavtest.sitl.telemetry import ONBOARD
from uavtest.sitl.ulog_writer import ULogFile
from uavtest.sitl.vehicle import STEP_US, SimConfig, Vehicle

__all__ = ["IDLE_EXIT_S", "LOCKSTEP_NAME", "FileLogSink", "run_sitl"]

log = logging.getLogger(__name__)

LOCKSTEP_NAME = "LOCKSTEP"
REANNOUNCE_S = 0.2
SEARCH_REANNOUNCE_S = 0.02  # ... until a client has spoken (it may bind its port just after we start)
IDLE_EXIT_S = 60.0  # lockstep: wall seconds without client traffic before the simulator ends
DATAGRAM_BYTES = 1400
LOG_PACE_S = 0.002  # one batch of LOG_DATA (32 x 90 bytes) per 2 ms: ~1.4 MB/s, as a client can read
_ALWAYS = frozenset({"HEARTBEAT", "STATUSTEXT", "NAMED_VALUE_INT"})
#: px4-rc.mavlink: the API/offboard link in mode ONBOARD, the GCS link NORMAL + its 50 Hz streams
LINK_MODES = (("api", ONBOARD), ("gcs", "sitl_gcs"))
#: the host clock at boot (Unix µs); the UAVTEST_SITL_UTC environment variable pins it (seconds)
UTC_ENV = "UAVTEST_SITL_UTC"


def utc_boot_us() -> int:
    """Unix time of boot in µs, for SYSTEM_TIME: the host clock, or ``$UAVTEST_SITL_UTC`` (s)."""
    pinned = os.environ.get(UTC_ENV)
    if pinned:
        return int(float(pinned) * 1e6)
    return time.time_ns() // 1000


class FileLogSink:
    """Writes each log to ``<dir>/seed<S>-<n>.ulg`` through a ``.part`` file."""

    def __init__(self, directory: Path, seed: int) -> None:
        self.directory = directory
        self.seed = seed
        self.count = 0
        self._file: ULogFile | None = None
        self.closed: list[Path] = []

    def open(self, header: bytes) -> None:
        self.count += 1
        path = self.directory / f"seed{self.seed}-{self.count}.ulg"
        self._file = ULogFile(path, header)

    def write(self, chunk: bytes) -> None:
        if self._file is not None:
            self._file.write(chunk)

    def close(self) -> None:
        if self._file is not None:
            self.closed.append(self._file.close())
            log.info("flight log %s closed", self.closed[-1])
            self._file = None


@dataclass
class Link:
    """One MAVLink link: a socket, where it sends to, and messages queued for one datagram batch.

    Messages are sent packed into datagrams of up to ``DATAGRAM_BYTES`` (as PX4 buffers its UDP
    output); MAVLink parsers (pymavlink, MAVSDK, QGC) read every message of a datagram.
    """

    name: str
    sock: socket.socket
    dest: tuple[str, int]
    codec: Codec = field(default_factory=Codec)
    peer_seen: bool = False
    always_stream: bool = True
    announce: bool = True  # lockstep announces every step (the GCS link: only once a client spoke)
    _buf: bytearray = field(default_factory=bytearray)

    def queue(self, msg: Msg) -> None:
        if not (self.always_stream or self.peer_seen or msg.name in _ALWAYS):
            return
        packet = self.codec.encode(msg)
        if len(self._buf) + len(packet) > DATAGRAM_BYTES:
            self.flush()
        self._buf += packet

    def flush(self) -> None:
        if not self._buf:
            return
        with contextlib.suppress(OSError):  # nobody listening (ICMP refused), buffer full: UDP may drop
            self.sock.sendto(self._buf, self.dest)
        self._buf.clear()


def load_config(test: Path | None, seed: int) -> SimConfig:
    """The simulator's world and boot parameters from a test file (native, manifest or Aerialist)."""
    if test is None:
        return SimConfig(seed=seed)
    from uavtest.spec.loaders import load_test

    return SimConfig.from_spec(load_test(test).spec, seed)


def _bind(host: str, port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    bind_host = host if host.startswith("127.") or host == "localhost" else "0.0.0.0"
    try:
        sock.bind((bind_host, port))
    except OSError as e:
        sock.close()
        raise InfrastructureError(f"cannot bind UDP port {port} on {bind_host}: {e}") from e
    sock.setblocking(False)
    return sock


class _Stop:
    """SIGTERM/SIGINT: remember it; the wake-up pipe (``signal.set_wakeup_fd``) ends the wait at once."""

    def __init__(self) -> None:
        self.requested = False

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        self.requested = True


class _WakeupPipe:
    """A self-pipe the C-level signal handler writes to, so ``select`` returns as a signal arrives.

    Python retries ``select`` after running a signal handler (PEP 475), so without it a
    SIGTERM would wait for the select timeout; with it the read end is readable at once.
    """

    def __init__(self) -> None:
        self.rfd, self.wfd = os.pipe()
        os.set_blocking(self.rfd, False)
        os.set_blocking(self.wfd, False)
        self._previous = signal.set_wakeup_fd(self.wfd, warn_on_full_buffer=False)

    def drain(self) -> None:
        with contextlib.suppress(BlockingIOError, InterruptedError):
            while os.read(self.rfd, 512):
                pass

    def close(self) -> None:
        signal.set_wakeup_fd(self._previous)
        os.close(self.rfd)
        os.close(self.wfd)


@dataclass
class _Watch:
    """Why a lockstep simulator should end by itself: its clients went silent, or its parent died."""

    idle_exit_s: float | None
    parent: int = field(default_factory=os.getppid)
    last_traffic: float | None = None  # wall time of the last datagram from any client

    def heard(self, now: float) -> None:
        self.last_traffic = now

    def reason(self, now: float) -> str | None:
        if os.getppid() != self.parent:
            return f"parent process {self.parent} ended"
        if (
            self.idle_exit_s is not None
            and self.last_traffic is not None
            and now - self.last_traffic > self.idle_exit_s
        ):
            return f"no client traffic for {self.idle_exit_s:g} s"
        return None


class _Edge:
    """The simulator's I/O around the vehicle: links, the log server, the lockstep announce."""

    def __init__(self, vehicle: Vehicle, links: list[Link], log_server: LogServer, lockstep: bool) -> None:
        self.vehicle = vehicle
        self.links = links
        for i, link in enumerate(links):  # a quiet link builds no telemetry until a client speaks
            vehicle.streaming[i] = link.always_stream
        self.by_fd = {link.sock.fileno(): link for link in links}
        self.index = {id(link): i for i, link in enumerate(links)}
        self.log_server = log_server
        self.log_link: Link | None = None  # the link a log download was asked on
        self.lockstep = lockstep

    def broadcast(self, msgs: list[Msg]) -> None:
        for msg in msgs:
            for link in self.links:
                link.queue(msg)

    def flush(self) -> None:
        for link in self.links:
            link.flush()

    def send_vehicle_output(self) -> None:
        """The vehicle's messages for each link (broadcasts and that link's telemetry)."""
        for link, msgs in zip(self.links, self.vehicle.drain_links(), strict=True):
            for msg in msgs:
                link.queue(msg)

    def announce(self, *, everywhere: bool) -> None:
        """The lockstep announce, last in the step's datagram; links nobody spoke on get it only
        on the wall-clock re-announce (a client that binds their port later still finds it)."""
        t_ms = self.vehicle.time_us // 1000
        msg = Msg("NAMED_VALUE_INT", {"time_boot_ms": t_ms, "name": LOCKSTEP_NAME, "value": t_ms})
        for link in self.links:
            if everywhere or link.peer_seen or link.announce:
                link.queue(msg)

    def handle(self, link: Link, data: bytes, addr: tuple[str, int]) -> bool:
        """Handle one datagram; True when it held a lockstep grant that advanced the clock."""
        vehicle = self.vehicle
        link.dest = addr
        if not link.peer_seen:
            link.peer_seen = True
            vehicle.streaming[self.index[id(link)]] = True  # a quiet link streams from now on
        granted = False
        for msg in link.codec.decode(data):
            if msg.name == "NAMED_VALUE_INT" and str(msg.get("name", "")).rstrip("\x00") == LOCKSTEP_NAME:
                until_us = int(msg.get("value", 0)) * 1000
                if self.lockstep and until_us > vehicle.time_us:
                    vehicle.advance(until_us, drain=False)
                    self.send_vehicle_output()
                    granted = True
                continue
            replies = self.log_server.handle(msg)
            if replies is not None:
                self.log_link = link
            else:
                replies = vehicle.receive(msg, self.index[id(link)])
            for reply in replies:
                link.queue(reply)
            self.send_vehicle_output()
        return granted

    def receive(self, link: Link, watch: _Watch | None) -> bool:
        """Read every datagram waiting on a link; True when one held a lockstep grant."""
        granted = False
        while True:
            try:
                data, addr = link.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:  # ICMP port unreachable from an earlier send
                continue
            if watch is not None:
                watch.heard(time.monotonic())
            granted |= self.handle(link, data, addr)
        return granted

    def stream_log(self) -> None:
        if self.log_server.streaming and self.log_link is not None:
            for msg in self.log_server.next_batch():
                self.log_link.queue(msg)

    def close(self) -> None:
        self.vehicle.recorder.stop()
        self.log_server.close()
        for link in self.links:
            link.sock.close()


@contextlib.contextmanager
def _signals() -> Iterator[tuple[_Stop, _WakeupPipe]]:
    """SIGTERM/SIGINT set ``stop.requested`` and wake the ``select``; handlers restored after."""
    stop = _Stop()
    previous = {s: signal.signal(s, stop) for s in (signal.SIGTERM, signal.SIGINT)}
    wakeup = _WakeupPipe()
    try:
        yield stop, wakeup
    finally:
        wakeup.close()
        for s, handler in previous.items():
            signal.signal(s, handler)


@dataclass
class _Clock:
    """Free-running: the vehicle clock follows the wall clock times the speed factor."""

    speed_factor: float
    wall0: float
    sim0: int

    def catch_up(self, edge: _Edge, now: float) -> float:
        """Advance the vehicle to the wall clock's time; returns the select timeout."""
        vehicle = edge.vehicle
        target = self.sim0 + int((now - self.wall0) * self.speed_factor * 1e6)
        if target >= vehicle.time_us + STEP_US:
            vehicle.advance(target, drain=False)
            edge.send_vehicle_output()
            edge.flush()
        return max(0.0005, STEP_US * 5 / 1e6 / self.speed_factor)


def _check_args(speed_factor: float, idle_exit_s: float | None) -> None:
    if speed_factor <= 0:
        raise BadInput("the speed factor must be > 0", field="--speed-factor", value=speed_factor)
    if idle_exit_s is not None and idle_exit_s < 0:
        raise BadInput("the idle exit time must be >= 0 s", field="--idle-exit", value=idle_exit_s)


def run_sitl(
    test: Path | None,
    *,
    seed: int = 0,
    host: str = "127.0.0.1",
    api_port: int = 14540,
    gcs_port: int = 14550,
    api_local_port: int | None = None,
    gcs_local_port: int = 18570,
    gcs_quiet: bool = False,
    log_dir: Path = Path("log"),
    lockstep: bool = False,
    speed_factor: float = 1.0,
    idle_exit_s: float | None = IDLE_EXIT_S,
    max_wall_s: float | None = None,
) -> int:
    """Run the simulator until SIGTERM/SIGINT (or ``max_wall_s``); returns the exit code (0).

    In lockstep a simulator also ends by itself (closing its log) when no client has sent
    anything for ``idle_exit_s`` wall seconds after one was heard (None or 0: never), and
    when its parent process dies (the engine that started it is gone). The GCS link streams
    from boot as PX4 SITL's does, unless ``gcs_quiet``: then only once a client spoke on it.
    """
    _check_args(speed_factor, idle_exit_s)
    with _signals() as (stop, wakeup):  # before the log file appears: a SIGTERM from then on closes it
        config = load_config(test, seed)
        sink = FileLogSink(log_dir, seed)
        config = dataclasses.replace(config, utc_boot_us=utc_boot_us(), links=LINK_MODES)
        vehicle = Vehicle(config, sink)
        local_api = api_port + 40 if api_local_port is None else api_local_port
        links = [
            Link("api", _bind(host, local_api), (host, api_port)),
            Link(
                "gcs",
                _bind(host, gcs_local_port),
                (host, gcs_port),
                always_stream=not gcs_quiet,
                announce=False,
            ),
        ]
        edge = _Edge(vehicle, links, LogServer(log_folder(log_dir)), lockstep)
        log.info(
            "uavtest sitl: pid %d seed %d, API %s:%d -> %s:%d, GCS %d -> %d, %s",
            os.getpid(),
            seed,
            host,
            local_api,
            host,
            api_port,
            gcs_local_port,
            gcs_port,
            "lockstep" if lockstep else f"speed factor {speed_factor:g}",
        )
        watch = _Watch(idle_exit_s or None) if lockstep else None
        ended = ""
        try:
            ended = _loop(edge, stop, wakeup, watch, speed_factor, max_wall_s)
        finally:
            if ended:
                log.warning("uavtest sitl: %s; closing the log and exiting", ended)
            edge.close()
    return 0


def _lockstep_step(edge: _Edge, watch: _Watch, *, granted: bool, due: bool, now: float) -> str:
    """After a lockstep wait: announce a granted step, or (when due) check the watch and
    re-announce with a heartbeat; returns why the simulator should end (or "")."""
    if granted:
        edge.announce(everywhere=False)
    elif due:
        ended = watch.reason(now) or ""
        if ended:
            return ended
        edge.broadcast([edge.vehicle.heartbeat()])
        edge.announce(everywhere=True)
    return ""


def _loop(
    edge: _Edge,
    stop: _Stop,
    wakeup: _WakeupPipe,
    watch: _Watch | None,
    speed_factor: float,
    max_wall_s: float | None,
) -> str:
    """The select loop until stopped; returns why a lockstep simulator ended by itself (or "")."""
    vehicle, lockstep, log_server = edge.vehicle, edge.lockstep, edge.log_server
    wall0 = time.monotonic()
    clock = _Clock(speed_factor, wall0, vehicle.time_us)
    edge.send_vehicle_output()
    if lockstep:
        edge.announce(everywhere=True)
    edge.flush()
    last_announce = time.monotonic()
    fds = [wakeup.rfd, *edge.by_fd]
    while not stop.requested:
        now = time.monotonic()
        if max_wall_s is not None and now - wall0 > max_wall_s:
            break
        heard = watch is not None and watch.last_traffic is not None
        period = REANNOUNCE_S if heard else SEARCH_REANNOUNCE_S
        timeout = max(0.0, period - (now - last_announce)) if lockstep else clock.catch_up(edge, now)
        if log_server.streaming:
            timeout = min(timeout, LOG_PACE_S)
        ready, _, _ = select.select(fds, [], [], timeout)
        granted = False
        for fd in ready:
            if fd == wakeup.rfd:
                wakeup.drain()
                continue
            granted |= edge.receive(edge.by_fd[fd], watch)
        if stop.requested:
            break
        edge.stream_log()
        if lockstep:
            now = time.monotonic()
            assert watch is not None
            ended = _lockstep_step(edge, watch, granted=granted, due=now - last_announce >= period, now=now)
            if ended:
                return ended
            if granted or now - last_announce >= period:
                last_announce = now
        edge.flush()
    return ""
