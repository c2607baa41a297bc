"""Several tests of one ``uavtest run`` flown at once, sharing the machine's replica slots.

A generator's output is many tests flown a few times each. One after the other, a one-replica
test leaves all but one core idle: a lockstep flight is its simulator and its runner taking turns.
Side by side, up to J tests fly at once (J: ``--jobs``, default the number of cores), and their
replicas share J slots, so the machine runs J replicas at a time whatever the tests' sizes.

What the runs share (``Shared``): the slots, one ``PortAllocator`` (two allocators would not know
each other's ports), one cancel event (Ctrl-C stops every replica), and a lock around
aggregation (matplotlib is not thread-safe) and around each test's block of output. PX4 tests
always fly one after the other: their speed factor is chosen for the replicas of one test.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import TypeVar

from uavtest.engine.ports import PortAllocator

__all__ = ["Shared", "fly_side_by_side"]

T = TypeVar("T")
R = TypeVar("R")


@dataclass(slots=True)
class Shared:
    """What the runs of one command share while they fly side by side (``alone``: a test flying
    by itself has the same, uncontended, and shows its live board)."""

    slots: AbstractContextManager[object]  # replicas flying at once, over all the tests
    side_by_side: bool = True  # False: one test alone, under its live board
    ports: PortAllocator = field(default_factory=PortAllocator)
    cancel: threading.Event = field(default_factory=threading.Event)
    aggregate: threading.Lock = field(default_factory=threading.Lock)
    output: threading.Lock = field(default_factory=threading.Lock)

    @classmethod
    def for_jobs(cls, jobs: int) -> Shared:
        return cls(threading.BoundedSemaphore(jobs))

    @classmethod
    def alone(cls) -> Shared:
        """One test by itself: no slots beyond its own replicas' pool."""
        return cls(contextlib.nullcontext(), side_by_side=False)


def fly_side_by_side(
    items: Sequence[T],
    jobs: int,
    fly: Callable[[T, Shared], R],
    start: Callable[[T], object] | None = None,
) -> list[R]:
    """``fly(item, shared)`` for every item, up to ``jobs`` at once; the results in ``items``' order.

    ``start(item)`` (say, a heading) runs just before its item flies, in ``items``' order: the
    pool takes items first in, first out, so an item's predecessors have all been taken. Ctrl-C
    (or any exception in this thread) sets the shared cancel event, waits for the runs to stop
    their replicas, and is raised again.
    """
    shared = Shared.for_jobs(jobs)
    turn = threading.Condition()
    started = 0

    def run(k: int, item: T) -> R:
        nonlocal started
        with turn:
            turn.wait_for(lambda: started == k)
            try:
                if start is not None:
                    with shared.output:
                        start(item)
            finally:
                started += 1
                turn.notify_all()
        return fly(item, shared)

    with ThreadPoolExecutor(max_workers=min(jobs, len(items)), thread_name_prefix="test") as pool:
        futures = [pool.submit(run, k, item) for k, item in enumerate(items)]
        try:
            wait(futures)
        except BaseException:
            shared.cancel.set()
            for f in futures:
                f.cancel()
            raise
    return [f.result() for f in futures]
