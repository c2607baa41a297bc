"""Free loopback UDP ports for replicas that run at the same time.

Each replica's runner binds one API port (``udpin:127.0.0.1:<port>``) and its simulator sends
to it; a second port is the GCS port the simulator sends to (nobody listens there; a distinct
port per replica keeps N simulators from spraying one QGroundControl). The allocator hands out
ports that are free *now* (checked by binding them) and that no other replica of this engine
holds, so concurrent replicas never share a port. Ports come from below the kernel's ephemeral
range, so a simulator binding "any" port (0) cannot take one. A process outside this engine can
still grab a port between the check and the runner's bind: the runner then fails with a bench
error and the replica is retried on new ports — a taken port becomes a retry, not a verdict.
"""

from __future__ import annotations

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
]

PX4_API_PORT = 14540  # PX4 SITL instance i sends its onboard (API) link to 14540 + i
PX4_API_LOCAL_PORT = 14580  # ... from local port 14580 + i
PX4_GCS_LOCAL_PORT = 18570  # PX4 SITL instance i binds its GCS link to 18570 + i
PX4_MAX_INSTANCES = 10


@dataclass(frozen=True, slots=True)
class ReplicaPorts:
    """The ports of one replica: the API port the runner binds, the GCS port the sim sends to.

    ``instance`` is the PX4 SITL instance number (``px4 -i``) when the vehicle is PX4, else None.
    """

    api: int
    gcs: int
    instance: int | None = None


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
    ) -> None:
        if not 0 < low < high <= 65535:
            raise ValueError(f"bad port range {low}-{high}")
        self.low, self.high, self.host = low, high, host
        self._lock = threading.Lock()
        self._held: set[int] = set()
        self._instances: set[int] = set()
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
            ports = (PX4_API_PORT + i, PX4_API_LOCAL_PORT + i, PX4_GCS_LOCAL_PORT + i)
            if all(port_is_free(p, self.host) for p in ports):
                self._instances.add(i)
                return i
        raise InfrastructureError(
            f"no free PX4 SITL instance: ports {PX4_API_PORT}-{PX4_API_PORT + PX4_MAX_INSTANCES - 1} "
            "are all taken (another PX4 SITL or a ground station running?)"
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
