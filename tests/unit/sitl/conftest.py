"""Helpers for the simulator's unit tests: competition missions flown in-process."""

from __future__ import annotations

import dataclasses
import io
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest
from pyulog import ULog

from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mission import NavItem, from_spec
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.loaders import load_test
from uavtest.spec.mission import mission_items
from uavtest.spec.models import Avoidance


def competition(
    shared_data: Path, n: int, seed: int = 0, avoidance: Avoidance = Avoidance.NONE
) -> tuple[SimConfig, list[NavItem]]:
    """The competition's mission ``n``; its ``simulator: ros`` would fly it with the local planner,
    the PX4 SIH comparisons want PX4 alone (``avoidance`` none) unless asked otherwise."""
    test = load_test(shared_data / "competition" / "snippets" / "case_studies" / f"mission{n}.yaml")
    config = dataclasses.replace(SimConfig.from_spec(test.spec, seed), avoidance=avoidance)
    return config, from_spec(mission_items(test.spec))


def competition_log(shared_data: Path, n: int, seed: int = 0) -> ULog:
    """The ULog of the competition's mission ``n`` flown in-process with seed ``seed``, no avoidance."""
    config, items = competition(shared_data, n, seed)
    sink = MemorySink()
    fly_mission(config, items, sink=sink)
    return ULog(io.BytesIO(sink.logs[0]))


@pytest.fixture
def mission2(shared_data: Path) -> tuple[SimConfig, list[NavItem]]:
    return competition(shared_data, 2)


@pytest.fixture(scope="module")
def bench_fidelity() -> ModuleType:
    """``bench/bench_fidelity.py`` as a module."""
    bench = str(Path(__file__).resolve().parents[3] / "bench")
    sys.path.insert(0, bench)
    try:
        import bench_fidelity
    finally:
        sys.path.remove(bench)
    return bench_fidelity


@pytest.fixture(scope="module")
def bench_square(bench_fidelity: ModuleType) -> Callable[[int], tuple[SimConfig, list[NavItem]]]:
    """The bench's square plan (the data README's ``square-mission.ulg``: takeoff to 10 m, 30 m
    north, 30 m east, land there; MIS_TAKEOFF_ALT 5, MPC_XY_CRUISE 8) per seed."""
    return bench_fidelity.square
