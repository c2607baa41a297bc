"""Helpers for the simulator's unit tests: competition missions flown in-process."""

from __future__ import annotations

from pathlib import Path

import pytest

from uavtest.sitl.mission import NavItem, from_spec
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.loaders import load_test
from uavtest.spec.mission import mission_items


def competition(shared_data: Path, n: int, seed: int = 0) -> tuple[SimConfig, list[NavItem]]:
    test = load_test(shared_data / "competition" / "snippets" / "case_studies" / f"mission{n}.yaml")
    return SimConfig.from_spec(test.spec, seed), from_spec(mission_items(test.spec))


@pytest.fixture
def mission2(shared_data: Path) -> tuple[SimConfig, list[NavItem]]:
    return competition(shared_data, 2)
