"""Free loopback UDP ports for replicas that run at the same time.

Each replica's runner binds one API port (``udpin:127.0.0.1:<port>``) and its simulator sends
to it; a second port is the GCS port the simulator sends to (nobody listens there; a distinct
port per replica keeps N simulators from spraying one QGroundControl). The allocator hands out
ports that are free *now* (checked by binding them) and that no other replica of this engine
holds, so concurrent replicas never share a port. Ports come from below the kernel's ephemeral
range, so a simulator binding "any" port (0) cannot take one. A process outside this engine can
still grab a port between the check and the runner's bind: the runner then fails with a bench
error and the replica is retried on new ports — a taken port becomes a retry, not a verdict.

A PX4 SITL replica gets an instance number ``i`` instead (``px4 -i i``): PX4 derives all its
ports from it (``PX4_INSTANCE_PORTS``, from its px4-rc.mavlink) and holds the lock file
``/tmp/px4_lock-i`` while it runs (another PX4 with the same instance refuses to start: "PX4
server already running for instance i"). An instance is handed out only when none of its ports
is bound and its lock is free, so PX4s started by something else on the machine are skipped.
"""

from __future__ import annotations

import fcntl
import os
import random
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from uavtest.errors import InfrastructureError

__all__ = [
    "PX4_API_PORT",
    "PX4_GCS_LOCAL_PORT",
    "PortAllocator",
    "ReplicaPorts",
    "port_is_free",
    "px4_lock_is_free",
]

PX4_API_PORT = 14540  # PX4 SITL instance i sends its onboard (API) link to 14540 + i
PX4_API_LOCAL_PORT = 14580  # ... from local port 14580 + i
PX4_GCS_LOCAL_PORT = 18570  # PX4 SITL instance i binds its GCS link to 18570 + i
PX4_MAX_INSTANCES = 10
#: the UDP ports PX4 SITL instance i binds, as offsets added to i (PX4 v1.15 px4-rc.mavlink)
PX4_INSTANCE_PORTS = (
    PX4_API_LOCAL_PORT,  # onboard (API) link, sends to 14540 + i
    PX4_GCS_LOCAL_PORT,  # GCS link
    14280,  # onboard payload link
    13030,  # gimbal link
    19450,  # SIH display link (sihsim)
)
PX4_LOCK = "/tmp/px4_lock-{}"  # PX4 holds a POSIX lock on it while instance {} runs


@dataclass(frozen=True, slots=True)
class ReplicaPorts:
    """The ports of one replica: the API port the runner binds, the GCS port the sim sends to.

    ``instance`` is the PX4 SITL instance number (``px4 -i``) when the vehicle is PX4, else None.
    """

    api: int
    gcs: int
    instance: int | None = None


def px4_lock_is_free(instance: int, template: str = PX4_LOCK) -> bool:
    """True when no running PX4 holds instance ``instance``'s lock file (fcntl, as PX4 takes it)."""
    try:
        fd = os.open(template.format(instance), os.O_RDWR)
    except FileNotFoundError:
        return True
    except OSError:
        return False  # someone else's lock file: PX4 could not open it either
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False
    else:
        fcntl.lockf(fd, fcntl.LOCK_UN)
        return True
    finally:
        os.close(fd)


def port_is_free(port: int, host: str = "127.0.0.1") -> bool:
    """True when a UDP socket can bind ``host:port`` right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


class PortAllocator:
    """Hands out UDP ports that are free and held by no other replica of this process.

    Thread-safe: replicas run in threads of one engine. ``lease()`` is a context manager that
    returns the ports to the pool when the replica's processes have ended.
    """

    def __init__(
        self,
        low: int = 20000,
        high: int = 32000,
        host: str = "127.0.0.1",
        *,
        rng: random.Random | None = None,
        px4_lock: str = PX4_LOCK,
    ) -> None:
        if not 0 < low < high <= 65535:
            raise ValueError(f"bad port range {low}-{high}")
        self.low, self.high, self.host = low, high, host
        self._lock = threading.Lock()
        self._held: set[int] = set()
        self._instances: set[int] = set()
        self._px4_lock = px4_lock
        # A random start so two engines on one machine rarely probe the same ports first.
        self._next = (rng or random.SystemRandom()).randrange(low, high)

    @property
    def held(self) -> frozenset[int]:
        with self._lock:
            return frozenset(self._held)

    def _take_port(self) -> int:
        span = self.high - self.low
        for _ in range(span):
            port = self._next
            self._next = self.low + (self._next - self.low + 1) % span
            if port in self._held:
                continue
            if port_is_free(port, self.host):
                self._held.add(port)
                return port
        raise InfrastructureError(f"no free UDP port on {self.host} in {self.low}-{self.high}")

    def _take_instance(self) -> int:
        for i in range(PX4_MAX_INSTANCES):
            if i in self._instances:
                continue
            ports = (PX4_API_PORT + i, *(base + i for base in PX4_INSTANCE_PORTS))
            if all(port_is_free(p, self.host) for p in ports) and px4_lock_is_free(i, self._px4_lock):
                self._instances.add(i)
                return i
        raise InfrastructureError(
            f"no free PX4 SITL instance: ports {PX4_API_PORT}-{PX4_API_PORT + PX4_MAX_INSTANCES - 1} "
            "are all taken or their /tmp/px4_lock-N held (other PX4 SITLs or a ground station running?)"
        )

    def allocate(self, *, px4: bool = False) -> ReplicaPorts:
        """Ports for one replica; PX4 replicas get an instance number and PX4's fixed ports."""
        with self._lock:
            if px4:
                i = self._take_instance()
                return ReplicaPorts(api=PX4_API_PORT + i, gcs=0, instance=i)
            return ReplicaPorts(api=self._take_port(), gcs=self._take_port())

    def release(self, ports: ReplicaPorts) -> None:
        with self._lock:
            if ports.instance is not None:
                self._instances.discard(ports.instance)
            else:
                self._held.discard(ports.api)
                self._held.discard(ports.gcs)

    @contextmanager
    def lease(self, *, px4: bool = False) -> Iterator[ReplicaPorts]:
        ports = self.allocate(px4=px4)
        try:
            yield ports
        finally:
            self.release(ports)
