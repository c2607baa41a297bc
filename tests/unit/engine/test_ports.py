"""Port allocation: concurrent replicas never share a port; taken ports are skipped."""

from __future__ import annotations

import random
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from uavtest.engine.ports import PortAllocator, port_is_free, px4_lock_is_free
from uavtest.errors import InfrastructureError


def test_concurrent_allocations_are_distinct_and_bindable() -> None:
    alloc = PortAllocator(rng=random.Random(1))
    got: list[tuple[int, int]] = []
    lock = threading.Lock()

    def take() -> None:
        for _ in range(10):
            p = alloc.allocate()
            with lock:
                got.append((p.api, p.gcs))

    threads = [threading.Thread(target=take) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    ports = [p for pair in got for p in pair]
    assert len(ports) == 160
    assert len(set(ports)) == len(ports)
    assert all(port_is_free(p) for p in ports)
    assert all(20000 <= p < 32000 for p in ports)  # below the kernel's ephemeral range


def test_a_port_taken_by_another_process_is_skipped() -> None:
    low = 20000 + random.SystemRandom().randrange(0, 11000)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", low + 1))
        alloc = PortAllocator(low, low + 4, rng=random.Random(0))
        a = alloc.allocate()
        assert low + 1 not in (a.api, a.gcs)
        assert not port_is_free(low + 1)


def test_released_ports_return_to_the_pool_and_exhaustion_is_a_bench_error() -> None:
    low = 20000 + random.SystemRandom().randrange(0, 11000)
    alloc = PortAllocator(low, low + 2)
    with alloc.lease() as p:
        assert {p.api, p.gcs} == {low, low + 1}
        with pytest.raises(InfrastructureError, match="no free UDP port"):
            alloc.allocate()
    assert alloc.held == frozenset()
    again = alloc.allocate()
    assert {again.api, again.gcs} == {low, low + 1}


LOCK_HOLDER = r"""
import fcntl, os, sys, time
fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT, 0o644)
fcntl.lockf(fd, fcntl.LOCK_EX)  # as a running PX4 holds /tmp/px4_lock-<instance>
print("locked", flush=True)
time.sleep(60)
"""


def test_a_px4_instance_whose_lock_another_process_holds_is_skipped(tmp_path: Path) -> None:
    template = str(tmp_path / "px4_lock-{}")
    holder = subprocess.Popen(
        [sys.executable, "-c", LOCK_HOLDER, template.format(0)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "locked"
        assert not px4_lock_is_free(0, template)
        assert px4_lock_is_free(1, template)  # no lock file yet: free
        alloc = PortAllocator(px4_lock=template)
        ports = alloc.allocate(px4=True)
        assert ports.instance != 0
        assert ports.api == 14540 + (ports.instance or 0)
    finally:
        holder.kill()
        holder.wait()
    assert px4_lock_is_free(0, template)  # the lock dies with its process
