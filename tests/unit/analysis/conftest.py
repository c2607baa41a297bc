"""Fixtures of the analysis tests: real PX4 logs parsed once per session."""

from __future__ import annotations

from pathlib import Path

import pytest
from pyulog import ULog

from uavtest.analysis.ulog import read_ulog


@pytest.fixture(scope="session")
def square_log(shared_data: Path) -> ULog:
    """PX4 v1.15.3 SIH: takeoff to 10 m, (30, 0), (30, 30), land; armed 134.2, airborne 136.0–176.2 s."""
    return read_ulog(shared_data / "px4-sih" / "square-mission.ulg")


@pytest.fixture(scope="session")
def aerialist_log(shared_data: Path) -> ULog:
    """Aerialist's mission1.ulg: a real Pixhawk flight on PX4 v1.12.3."""
    return read_ulog(shared_data / "aerialist" / "samples" / "flights" / "mission1.ulg")
