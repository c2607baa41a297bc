"""Sanity against real PX4: our flights of the competition plans follow PX4 v1.15 SIH's paths.

../shared/data/px4-sih holds PX4 SIH flights of the same plans with the same parameters.
PX4 against itself differs by 0.1-0.56 m per DTW step; a path that misses a waypoint or takes
off to the wrong altitude differs by metres.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.similarity import dtw
from uavtest.analysis.ulog import read_ulog, trajectory_from_ulog
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.recorder import MemorySink

from .conftest import competition

DTW_PER_STEP_LIMIT = 1.5  # metres: about 3x PX4's own run-to-run spread


@pytest.mark.parametrize("n", [1, 2])
def test_paths_and_altitudes_match_px4_sih(shared_data: Path, n: int):
    config, items = competition(shared_data, n, seed=0)
    sink = MemorySink()
    fly_mission(config, items, sink=sink)
    ours = trajectory_from_ulog(ULog(io.BytesIO(sink.logs[0])))
    for run in (1, 2, 3):
        px4 = trajectory_from_ulog(
            read_ulog(shared_data / "px4-sih" / f"competition-mission{n}-run{run}.ulg")
        )
        d = dtw(ours, px4)
        assert d.per_step < DTW_PER_STEP_LIMIT, f"mission{n} vs PX4 run{run}: DTW {d.per_step:.2f} m/step"
        # takes off to the same altitude (the plans fly at 10 m above home) within half a metre
        assert abs(ours.altitude.max() - px4.altitude.max()) < 0.5
        # ends where PX4 ends: the land point
        end_ours = np.array([ours.x[-1], ours.y[-1]])
        end_px4 = np.array([px4.x[-1], px4.y[-1]])
        assert np.linalg.norm(end_ours - end_px4) < 2.0
