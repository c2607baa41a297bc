"""Several tests of one command flown side by side: order, concurrency, cancellation, width."""

from __future__ import annotations

import signal
import threading
import time
from pathlib import Path

import pytest

from uavtest.engine.command import side_by_side_width
from uavtest.engine.side_by_side import Shared, fly_side_by_side
from uavtest.spec.models import UavTest


def test_results_come_back_in_the_tests_order_and_at_most_jobs_fly_at_once() -> None:
    lock = threading.Lock()
    flying = peak = 0
    started: list[int] = []

    def fly(item: int, shared: Shared) -> int:
        nonlocal flying, peak
        with lock:
            flying += 1
            peak = max(peak, flying)
        time.sleep(0.05 * (5 - item % 5))  # later items finish first
        with lock:
            flying -= 1
        return item * 10

    assert fly_side_by_side(list(range(9)), 3, fly, start=started.append) == [k * 10 for k in range(9)]
    assert peak == 3
    assert started == list(range(9))  # headings in the tests' order, whatever finished first


def test_every_test_shares_the_same_slots_ports_and_cancel_event() -> None:
    seen: list[Shared] = []
    lock = threading.Lock()

    def fly(item: int, shared: Shared) -> None:
        with lock:
            seen.append(shared)

    fly_side_by_side([1, 2, 3, 4], 2, fly)
    assert len(seen) == 4 and all(s is seen[0] for s in seen)


def test_an_interrupt_cancels_every_test_still_flying() -> None:
    """Ctrl-C in the waiting thread: the shared cancel event is set, the runs stop, it is raised."""
    cancelled: list[int] = []
    main = threading.main_thread()

    def fly(item: int, shared: Shared) -> None:
        if item == 0:
            threading.Timer(0.05, lambda: _interrupt(main)).start()
        if shared.cancel.wait(5.0):
            cancelled.append(item)

    # Python's own handler, whatever this process inherited (a background job ignores SIGINT)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            fly_side_by_side([0, 1], 2, fly)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert sorted(cancelled) == [0, 1]


def _interrupt(thread: threading.Thread) -> None:
    """Ctrl-C as the terminal sends it: SIGINT to the main thread (Python raises KeyboardInterrupt)."""
    assert thread.ident is not None
    signal.pthread_kill(thread.ident, signal.SIGINT)


def _test(name: str, simulator: str = "builtin") -> UavTest:
    return UavTest.model_validate(
        {
            "apiVersion": "uavtest.io/v1alpha1",
            "kind": "UavTest",
            "metadata": {"name": name},
            "spec": {
                "vehicle": {"simulator": simulator},
                "mission": {"waypoints": [{"x": 0, "y": 0, "z": -5}]},
            },
        }
    )


@pytest.mark.parametrize(
    ("sims", "jobs", "cores", "width"),
    [
        (["builtin"], None, 4, 1),  # one test: its replicas use the machine
        (["builtin"] * 5, None, 2, 2),  # default: the cores
        (["builtin"] * 5, 3, 2, 3),  # --jobs
        (["builtin"] * 2, 8, 2, 2),  # never more than the tests
        (["builtin", "px4"], None, 4, 1),  # PX4's speed factor is chosen for one test's replicas
    ],
)
def test_how_many_tests_fly_at_once(sims: list[str], jobs: int | None, cores: int, width: int) -> None:
    tests = {Path(f"t{k}.yaml"): _test(f"t{k}", sim) for k, sim in enumerate(sims)}
    assert side_by_side_width(tests, jobs, cores) == width
