"""Sanity bounds of the fidelity figures (``bench/bench_fidelity.py`` measures them with 25 seeds).

The built-in simulator flies the competition's mission1 and mission2 like PX4 v1.15 SIH flies
them (../shared/data/px4-sih): measured from lift-off on normalised time, each built-in-vs-PX4
figure stays within a loose multiple of PX4's own run-to-run maximum, the flight time within a
few seconds of PX4's range, the logged position as smooth as EKF2's output, and replicas differ.
A vehicle that misses a waypoint, cruises at the wrong altitude, hovers for half a minute or
logs a white-noise position fails these; the bench holds the tight target.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.fidelity import (
    FIGURES,
    flight_figures,
    pairs_between,
    pairs_within,
    spread,
    takeoff_turned_back,
)
from uavtest.analysis.ulog import read_ulog, trajectory_from_ulog
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.recorder import MemorySink

from .conftest import competition

#: with 6 seeds the means swung by about 0.1 m between seed sets (mission2's altitude error 0.96
#: on seeds 0-5, 0.81 over 100 seeds at stop 37): a coin toss against the bounds, not a check
SEEDS = 12
FIGURE_FACTOR = 2.5  # built-in vs PX4 (mean) <= this x PX4 vs PX4 (max)
FLIGHT_TIME_MARGIN = 6.0  # s outside PX4's flight-time range
JITTER_FACTOR = 2.0  # x PX4's velocity jitter (white noise on the position would give ~3x)


@pytest.mark.parametrize("n", [1, 2])
def test_builtin_flies_the_competition_missions_within_loose_bounds_of_px4(shared_data: Path, n: int):
    px4 = [
        flight_figures(
            trajectory_from_ulog(read_ulog(shared_data / "px4-sih" / f"competition-mission{n}-{r}.ulg"))
        )
        for r in ("run1", "run2", "run3", "sf1")
    ]
    ours = []
    for seed in range(SEEDS):
        config, items = competition(shared_data, n, seed=seed)
        sink = MemorySink()
        fly_mission(config, items, sink=sink)
        ours.append(flight_figures(trajectory_from_ulog(ULog(io.BytesIO(sink.logs[0])))))
    px4_pairs, cross = pairs_within(px4), pairs_between(ours, px4)
    for attr, label, _ in FIGURES:
        theirs = spread([getattr(p, attr) for p in px4_pairs])
        mine = spread([getattr(p, attr) for p in cross])
        assert mine.mean <= FIGURE_FACTOR * theirs.high, f"mission{n} {label}: {mine} vs PX4 {theirs}"
    ft_px4 = spread([f.flight_time for f in px4])
    ft_ours = spread([f.flight_time for f in ours])
    assert ft_px4.low - FLIGHT_TIME_MARGIN <= ft_ours.mean <= ft_px4.high + FLIGHT_TIME_MARGIN, (
        ft_ours,
        ft_px4,
    )
    assert ft_ours.high - ft_ours.low > 0.5, "replicas with different seeds fly the same time"
    assert spread([f.jitter for f in ours]).high <= JITTER_FACTOR * spread([f.jitter for f in px4]).high


def test_some_takeoffs_stall_and_recover_as_px4_sihs_do(shared_data: Path) -> None:
    """4 of 32 PX4 v1.15 SIH flights of the competition's missions (2 of 8 of mission3, flown here)
    climbed, went back down to the ground and climbed again: FlightTaskAuto's track states on the
    takeoff's centimetre-short track (``test_a_takeoff_drifting_behind_its_tracks_start_goes_back_
    down_to_it``). The built-in vehicle's takeoffs drift as far (0.2-0.7 m) and some stall too,
    fewer than PX4's since its takeoff climbs as PX4's does (TakeoffHandling's ramp: 2 of 60 here);
    every stalled one still flies its mission."""
    stalls = 0
    for seed in range(60):
        config, items = competition(shared_data, 1, seed=seed)
        flight = fly_mission(config, items)
        assert flight.vehicle is not None and not flight.vehicle.crashed
        t, _, _, z = np.array(flight.samples).T
        if takeoff_turned_back(t, -z, flight.reached[0][1]):
            stalls += 1
            assert [i for i, _ in flight.reached] == list(range(len(items))), f"seed {seed}: {flight.reached}"
            assert flight.landed_s is not None, f"seed {seed} did not land"
    assert 1 <= stalls <= 12, stalls
