"""EKF2's heading error as PX4 v1.15 SIH shows it, and what it does to the flight.

PX4 SIH flights of the competition missions, flown here by ``uavtest run`` with
``simulator: px4`` (their ULogs carry ``vehicle_attitude_groundtruth``; 24 on 2026-11-27): EKF2's
heading is off the truth by -2.3 degrees in the climb (4.6 between flights) after its in-flight
alignment, settles during the first leg (half-way 4.0 s after the vehicle first exceeds 1.5 m/s)
at +2.7 (5.2 between flights), and varies 2.2 degrees within a flight. PX4's attitude controller
tilts the *estimated* body, so the real thrust leans the other way by that much: at a cruise's
drag-holding 4 m/s^2 that is 0.2-0.4 m/s^2 across the track, which pushes PX4 off its track
mid-leg.
"""

from __future__ import annotations

import dataclasses
import io
import math
import random
import statistics

import numpy as np
from pyulog import ULog

from uavtest.analysis.ulog import read_ulog
from uavtest.px4.modes import AutoSubMode, MainMode
from uavtest.sitl.ekf2 import Estimator
from uavtest.sitl.geo import Projection
from uavtest.sitl.inprocess import _command, fly_mission
from uavtest.sitl.mav import MavCmd, MavFrame
from uavtest.sitl.mission import NavItem
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Home

from .conftest import competition


def test_the_heading_error_has_px4_sihs_offset_and_spread() -> None:
    """Two sets of 24 PX4 v1.15 SIH flights of the competition's missions against their ground
    truth (2026-11-27, stop 29 / stop 31), timed from the moment the vehicle first moves faster than
    1.5 m/s: the heading error is -1.8 / -2.9 degrees in the climb (4.9 / 6.5 between flights),
    +1.9 / +1.3 at 4 s, +5.3 / +5.5 at 6-12 s (3.5 / 4.3 between flights; correlated with the
    climb's by -0.5 / +0.2), +2.7 / +3.8 at 24-40 s (3.5 / 3.4), +0.5 / +2.1 at 44-56 s. A flight
    keeps its shift: 6-12 s and 24-40 s in are correlated by 0.69 / 0.72. (Until stop 32 the
    built-in estimator gave 2.7 between flights at 6-12 s, +1.7 at 24-40 s and 0.60 here.)"""
    climbs, early, late, later, at4 = [], [], [], [], []
    for seed in range(60):
        e = Estimator(random.Random(seed), random.Random(seed + 1000), random.Random(seed + 2000))
        samples = []
        for k in range(50 * 70):  # 10 s of climb, then a 60 s leg at 4 m/s, at 50 Hz
            moving = k >= 50 * 10
            e.update(0.02, 4.0 if moving else 0.0, 0.0)
            samples.append(math.degrees(e.eh))

        def mean(a: float, b: float, samples: list[float] = samples) -> float:  # seconds after moving
            return statistics.fmean(samples[int(50 * (10 + a)) : int(50 * (10 + b))])

        climbs.append(statistics.fmean(samples[: 50 * 10]))
        at4.append(mean(3.5, 4.5))
        early.append(mean(6, 12))
        late.append(mean(24, 40))
        later.append(mean(44, 56))
    assert -3.5 < statistics.fmean(climbs) < -1.0
    assert 3.0 < statistics.pstdev(climbs) < 6.0
    assert 0.5 < statistics.fmean(at4) < 3.0  # PX4 +1.9: the settling starts about 3 s in
    assert 4.0 < statistics.fmean(early) < 6.5
    assert 3.0 < statistics.pstdev(early) < 4.5
    assert 2.0 < statistics.fmean(late) < 4.0
    assert 2.5 < statistics.pstdev(late) < 4.5
    assert -1.0 < statistics.fmean(later) < 2.5
    assert -0.6 < statistics.correlation(climbs, early) < 0.3
    assert statistics.correlation(early, late) > 0.68  # PX4 0.69 / 0.72


def test_the_local_planners_system_keeps_one_heading_offset() -> None:
    """Gazebo's EKF2 (the local planner's system) keeps the offset it was calibrated with."""
    e = Estimator(random.Random(3), random.Random(1003), random.Random(2003))
    e.hold_heading_offset()
    held = e.eh_offset
    for _ in range(50 * 20):
        e.update(0.02, 4.0, 0.0)
    assert e.eh_offset == held


def _cross_track(offset_deg: float) -> float:
    """Mean east offset (m) over a 50 m leg North flown with EKF2's heading off by a fixed amount."""
    home = Home()
    proj = Projection(home.lat, home.lon)
    rel = MavFrame.GLOBAL_RELATIVE_ALT_INT

    def at(seq: int, cmd: int, north: float, alt: float) -> NavItem:
        lat, lon = proj.reproject(north, 0.0)
        return NavItem(seq, cmd, rel, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)

    v = Vehicle(dataclasses.replace(SimConfig(home=home, seed=4), links=()), None)
    v.load_mission(
        [
            at(0, MavCmd.NAV_TAKEOFF, 0.0, 10.0),
            at(1, MavCmd.NAV_WAYPOINT, 50.0, 10.0),
            at(2, MavCmd.NAV_LAND, 50.0, 0.0),
        ]
    )
    v.est.hold_heading_offset(math.radians(offset_deg))
    v.est._ch = 0.0  # the fixed part alone
    v.fly_until(lambda v: v.ready, 10_000_000)
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 1.0) == 0
    _command(v, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.MISSION))
    east = []
    for _ in range(3000):
        v.advance(v.time_us + 20_000)
        v.est._ch = 0.0
        if 5.0 < v.body.x < 45.0:
            east.append(v.body.y)
    return statistics.fmean(east)


def test_the_thrust_leans_against_the_heading_error() -> None:
    # the estimate's heading 6 degrees clockwise of the truth: the thrust leans counterclockwise
    # (flying North: West, negative East) until the velocity loop's integrator takes it back
    left, none, right = _cross_track(6.0), _cross_track(0.0), _cross_track(-6.0)
    assert left < none < right, (left, none, right)
    assert right - left > 0.15  # about 0.2 m between +-6 degrees, the same seed otherwise


def _heading_jitter(ulog) -> float:
    """Std of the logged heading's 0.1 s steps against their 1 s trend, in the air while the
    heading turns slower than 5 degrees/s (degrees)."""
    lp = ulog.get_dataset("vehicle_local_position").data
    land = ulog.get_dataset("vehicle_land_detected").data
    t = lp["timestamp"] / 1e6
    grid = np.arange(t[0] + 1.0, t[-1] - 1.0, 0.1)
    heading = np.degrees(np.interp(grid, t, np.unwrap(lp["heading"])))
    air = np.interp(grid, land["timestamp"] / 1e6, land["landed"].astype(float)) < 0.5
    steps = np.diff(heading)
    trend = np.convolve(steps, np.ones(10) / 10, mode="same")
    keep = air[1:] & (np.abs(trend) < 0.5)
    return float(np.std((steps - trend)[keep]))


def test_the_logged_heading_is_as_smooth_as_px4_sihs(shared_data) -> None:
    """EKF2's heading, like its position, does not jitter: PX4 SIH's logged heading moves by
    0.17 degrees (16 flights flown here) to 0.22 (the shared logs) per 0.1 s against its 1 s trend.
    The built-in heading error was a plain Gauss-Markov process (0.45); it is now low-passed."""
    px4 = _heading_jitter(read_ulog(shared_data / "px4-sih" / "competition-mission2-run2.ulg"))
    assert 0.1 < px4 < 0.35  # the oracle
    for seed in range(3):
        config, items = competition(shared_data, 2, seed)
        sink = MemorySink()
        fly_mission(config, items, sink=sink)
        ours = _heading_jitter(ULog(io.BytesIO(sink.logs[0])))
        assert 0.1 < ours < 0.3, (seed, ours, px4)
