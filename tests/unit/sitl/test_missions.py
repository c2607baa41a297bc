"""The competition's mission1 and mission2, flown in-process, against PX4 v1.15 SIH's flight times."""

from pathlib import Path

import pytest

from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.vehicle import SimConfig

from .conftest import competition

# PX4 v1.15 SIH, competition parameters (../shared/data/px4-sih, all four runs each, and 8 more
# per plan flown here through uavtest on 2026-11-28, README "Benchmarks"): takeoff to landing
PX4_RANGE = {1: (38.0, 50.4), 2: (56.4, 72.2)}
#: a sanity bound, not the fidelity target (bench/bench_fidelity.py measures that): PX4's range
#: widened by 15 %. PX4's four logs per plan are two noise realizations (SIH seeds its sensor
#: noise at every boot); PX4 creeps onto a waypoint for 5-9 s in some flights and lands 8-9 s
#: late after EKF2's altitude shift in others. The built-in vehicle does each too, and in 1 of 40
#: seeds both in one flight: mission1 seeds 0-39 take 38-52 s, mission2 55-78 s
MARGIN = 0.15
WINDOWS = {n: (low * (1 - MARGIN), high * (1 + MARGIN)) for n, (low, high) in PX4_RANGE.items()}


@pytest.mark.parametrize("n", [1, 2])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_competition_mission_times_like_px4(shared_data: Path, n: int, seed: int):
    config, items = competition(shared_data, n, seed)
    flight = fly_mission(config, items)
    low, high = WINDOWS[n]
    assert flight.flight_time is not None, "the vehicle did not take off and land"
    assert low <= flight.flight_time <= high, f"mission{n} seed {seed}: {flight.flight_time:.1f} s"
    assert [seq for seq, _ in flight.reached] == list(range(len(items)))
    assert flight.disarmed


@pytest.mark.parametrize("n", [1, 2])
def test_takeoff_to_the_items_altitude_and_every_waypoint_reached(shared_data: Path, n: int):
    config, items = competition(shared_data, n)
    flight = fly_mission(config, items)
    vehicle = flight.vehicle
    assert vehicle is not None
    highest = -min(z for _, _, _, z in flight.samples)
    # takeoff item at 10 m (MIS_TAKEOFF_ALT is 1 m); the true altitude strays with EKF2's altitude
    # drift: the 16 PX4 SIH flights of missions 1 and 2 flown here truly topped out at 10.2-11.8 m
    assert 9.5 <= highest <= 11.8
    for item in items[1:]:
        x, y = vehicle.proj.project(item.lat, item.lon)
        closest = min((sx - x) ** 2 + (sy - y) ** 2 for _, sx, sy, _ in flight.samples) ** 0.5
        assert closest < 1.0, f"item {item.seq} missed by {closest:.2f} m"


def test_same_seed_same_trajectory(mission2):
    config, items = mission2
    a = fly_mission(config, items, sample_us=20_000)
    b = fly_mission(config, items, sample_us=20_000)
    assert a.samples == b.samples
    assert a.reached == b.reached


def test_different_seeds_differ(mission2):
    config, items = mission2
    a = fly_mission(config, items)
    other = SimConfig(
        home=config.home, obstacles=config.obstacles, wind=config.wind, params=config.params, seed=7
    )
    b = fly_mission(other, items)
    assert a.samples != b.samples
    assert a.flight_time != b.flight_time
