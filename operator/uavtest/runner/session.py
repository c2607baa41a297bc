"""The receive loop: moves bytes between a ``UdpLink`` and the ``ReplicaCore`` until it is done.

This is the hot path of a lockstep run (one round trip per granted step), so it does nothing but
receive, hand events to the core and send what it answers; wall-clock work happens in ticks.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from uavtest.runner.core import FlightReport, ReplicaCore
from uavtest.runner.link import UdpLink

__all__ = ["drive"]


def drive(
    core: ReplicaCore,
    link: UdpLink,
    *,
    clock: Callable[[], float] = time.monotonic,
    tick_s: float = 0.02,
) -> FlightReport:
    """Run the core over the link until it is done; returns its report."""
    send, receive, handle, tick, end_batch = link.send, link.receive, core.handle, core.tick, core.end_batch
    now = clock()
    send(core.start(now))
    next_tick = now
    while not core.done:
        now = clock()
        if now >= next_tick:
            out = tick(now)
            if out:
                send(out)
            next_tick = now + tick_s
            continue
        events = receive(next_tick - now)
        if not events:
            continue
        now = clock()
        for event in events:
            out = handle(event, now)
            if out:
                send(out)
            if core.done:
                break
        out = end_batch(now)
        if out:
            send(out)
    return core.report
