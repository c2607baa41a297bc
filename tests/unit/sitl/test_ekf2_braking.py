"""EKF2's velocity misses part of the braking, as PX4 v1.15 SIH's does against its ground truth.

The oracle is the shared ``square-mission.ulg`` (PX4 v1.15.3 SIH, ground truth logged): braking
into its two waypoints from 8 m/s, EKF2's velocity is 0.26 m/s short of the truth along the leg
over the 3 s after each acceptance. The built-in vehicle flies the same mission (``bench_fidelity``
rebuilds it from the data README) and its estimate must be as short. Without the coupling it was
0.04 m/s short: the velocity loop then stopped the vehicle where PX4's carries on past the
waypoint and off the next leg.
"""

from __future__ import annotations

import io
import math
import os
import random
import statistics
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.fidelity import braking_velocity_errors
from uavtest.analysis.ulog import read_ulog, setpoint_changes
from uavtest.sitl import ekf2
from uavtest.sitl.ekf2 import Estimator
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.recorder import MemorySink

REPO = Path(__file__).resolve().parents[3]
SHARED = Path(os.environ.get("UAVTEST_SHARED_DATA", REPO.parent / "shared" / "data"))
SQUARE = SHARED / "px4-sih" / "square-mission.ulg"


def _braking(ulog: ULog) -> list[tuple[float, float]]:
    lp = ulog.get_dataset("vehicle_local_position").data
    gt = ulog.get_dataset("vehicle_local_position_groundtruth").data
    estimate = np.column_stack([lp[k] for k in ("x", "y", "vx", "vy")])
    truth = np.column_stack([gt["vx"], gt["vy"]])
    return braking_velocity_errors(
        lp["timestamp"] / 1e6, estimate, gt["timestamp"] / 1e6, truth, setpoint_changes(ulog)
    )


@pytest.mark.skipif(not SQUARE.exists(), reason=f"shared PX4 SIH log not found: {SQUARE}")
def test_the_velocity_estimate_falls_short_braking_into_a_waypoint_as_px4s_does(bench_square) -> None:
    px4 = _braking(read_ulog(SQUARE))
    assert len(px4) == 2
    px4_along = statistics.mean(a for a, _ in px4)
    assert -0.35 < px4_along < -0.15  # the oracle as the shared log has it: -0.26 m/s

    ours: list[tuple[float, float]] = []
    for seed in range(6):
        config, items = bench_square(seed)
        sink = MemorySink()
        fly_mission(config, items, sink=sink)
        ours += _braking(ULog(io.BytesIO(sink.logs[0])))
    assert len(ours) == 12
    along = statistics.mean(a for a, _ in ours)
    assert abs(along - px4_along) < 0.1, (along, px4_along)


def _brake(e: Estimator, seconds: float, decel: float, v0: float, dt: float = 0.02) -> float:
    """Fly ``e`` through a braking north at ``decel`` from ``v0``; the true velocity at the end."""
    v = v0
    for _ in range(round(seconds / dt)):
        v = max(0.0, v - decel * dt)
        e.update(dt, v, 0.0, 0.0)
    return v


def _pair(offset_deg: float) -> tuple[Estimator, Estimator]:
    pair = []
    for coupled in (True, False):
        e = Estimator(random.Random(7), random.Random(8), random.Random(9), random.Random(10))
        e.hold_heading_offset(math.radians(offset_deg))
        e.acc_coupled = coupled
        pair.append(e)
    return pair[0], pair[1]


def test_braking_leaves_the_velocity_short_and_gps_fusion_takes_it_back() -> None:
    coupled, plain = _pair(0.0)
    for e in (coupled, plain):
        _brake(e, 30.0, 0.0, 4.0)  # cruise: no acceleration, nothing missed (the jump to 4 m/s
        # at the start is long taken back)
    assert coupled.evx == pytest.approx(plain.evx, abs=1e-6)
    for e in (coupled, plain):
        _brake(e, 4.0, 0.85, 4.0)  # PX4's braking into a competition waypoint
    short = coupled.evx - plain.evx
    tau = ekf2.ACC_COUPLING_TAU
    expected = -ekf2.ACC_COUPLING * min(0.85, ekf2.ACC_COUPLING_MAX) * tau * (1 - math.exp(-4.0 / tau))
    assert -0.22 < expected < -0.12  # PX4 SIH braking into a competition waypoint: -0.13 to -0.21
    assert short == pytest.approx(expected, rel=0.05)
    assert coupled.ex == pytest.approx(plain.ex, abs=1e-9)  # the position does not follow it
    for e in (coupled, plain):
        _brake(e, 6.0, 0.0, 0.0)  # stopped: GPS fusion takes the miss back
    assert abs(coupled.evx - plain.evx) < 0.1 * abs(short)


def test_a_heading_error_turns_the_braking_sideways() -> None:
    coupled, plain = _pair(5.0)  # EKF2's heading 5 degrees right of the truth, braking north
    for e in (coupled, plain):
        _brake(e, 3.0, 0.85, 4.0)
    sideways = coupled.evy - plain.evy
    # EKF2 rotates the measured braking by its heading: the estimate misses a drift to the east
    assert sideways < -0.5 * math.radians(5.0) * 0.85 * 1.0
    left, _ = _pair(-5.0)
    _brake(left, 3.0, 0.85, 4.0)
    assert left.evy - plain.evy > 0.0


def test_the_local_planners_system_is_calibrated_without_it() -> None:
    e = Estimator(random.Random(1))
    e.gazebo_system()
    assert not e.acc_coupled


def _accelerate(e: Estimator, seconds: float, acc: float, v0: float, dt: float = 0.02) -> float:
    """Fly ``e`` north accelerating at ``acc`` from ``v0`` for ``seconds``; the true velocity then."""
    v = v0
    for _ in range(round(seconds / dt)):
        v += acc * dt
        e.update(dt, v, 0.0, 0.0)
    return v


def test_out_of_a_corner_the_miss_is_no_larger_than_brakings_and_soon_gone() -> None:
    """PX4 v1.15 SIH accelerating out of a waypoint at 2-3 m/s^2 (40 legs, 24 flights with their
    ground truth): EKF2's velocity error along the leg peaks at +0.19 m/s 2 s in, and is 0.03 by
    3.5 s, 1 s after the acceleration ends. Before stop 40 the built-in's reached 0.26 and held
    0.11 at 4 s, and its estimate drifted off the new leg as the acceleration ended."""
    coupled, plain = _pair(0.0)
    for e in (coupled, plain):
        _brake(e, 10.0, 0.0, 0.0)  # at rest on the waypoint
    v = 0.0
    for e in (coupled, plain):
        v = _accelerate(e, 2.0, 2.5, 0.0)  # MPC_ACC_HOR-like acceleration out of the corner
    peak = coupled.evx - plain.evx
    assert 0.1 < peak < 0.22, peak
    for e in (coupled, plain):
        _accelerate(e, 1.0, 0.0, v)  # at cruise speed: the acceleration is over
    assert abs(coupled.evx - plain.evx) < 0.06, coupled.evx - plain.evx
