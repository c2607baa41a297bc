"""PX4 SIH's body is fixed by its parameters and its auto yaw sweeps at MPC_YAWRAUTO_MAX through
PX4's yaw loops: replicas differ by noise (EKF2, wind, timing), not by a different airframe. The
local planner's system (Gazebo, not lockstep), calibrated on the competition's flights, keeps its spread."""

import io

import numpy as np
from pyulog import ULog

from uavtest.analysis.ulog import read_ulog
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.simulator_sih import DRAG_LINEAR, TAU_TILT
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Avoidance

from .conftest import competition


def test_sih_replicas_fly_one_airframe():
    for seed in range(6):
        v = Vehicle(SimConfig(seed=seed))
        assert v.body.kl == DRAG_LINEAR
        assert v.body.tau_tilt == TAU_TILT
        assert v.ctrl.yaw_rate_scale == 1.0


def test_the_local_planners_system_still_varies():
    bodies = [Vehicle(SimConfig(seed=seed, avoidance=Avoidance.LOCAL_PLANNER)) for seed in range(6)]
    assert len({v.body.kl for v in bodies}) == 6
    assert len({v.ctrl.yaw_rate_scale for v in bodies}) == 6


def _first_turn(ulog: ULog) -> tuple[float, float, float]:
    """The turn onto mission2's first leg (from the takeoff item reached, 4 s): the yaw
    setpoint's fastest sweep, the heading's peak rate (deg/s) and how far the heading goes past
    the setpoint it settles on (deg)."""
    result = ulog.get_dataset("mission_result").data
    start = result["timestamp"][np.flatnonzero(result["seq_reached"] >= 0)[0]] / 1e6
    lp = ulog.get_dataset("vehicle_local_position").data
    sp = ulog.get_dataset("trajectory_setpoint").data
    grid = np.arange(start, start + 4.0, 0.02)
    heading = np.degrees(np.interp(grid, lp["timestamp"] / 1e6, np.unwrap(lp["heading"])))
    valid = np.isfinite(sp["yaw"])
    setpoint = np.degrees(np.interp(grid, sp["timestamp"][valid] / 1e6, np.unwrap(sp["yaw"][valid])))
    rate = np.convolve(np.gradient(heading, grid), np.ones(5) / 5, mode="same")
    direction = np.sign(setpoint[-1] - heading[0])
    # the setpoint the sweep ends on: its extreme (a vehicle off the track from the takeoff item,
    # PX4's previous waypoint, may turn its setpoint back towards the track before the 4 s end)
    final = float((setpoint * direction).max() * direction)
    return (
        float(np.abs(np.gradient(setpoint, grid)).max()),
        float(np.abs(rate).max()),
        float(((heading - final) * direction).max()),
    )


def test_a_turn_is_flown_through_px4s_yaw_loops(shared_data):
    """PX4 v1.15 SIH moves its yaw setpoint at exactly MPC_YAWRAUTO_MAX (45 degrees/s,
    ``FlightTaskAuto::_limitYawRate``, no acceleration limit) and feeds its rate forward; the
    attitude controller adds MC_YAW_P x the error, and the yaw rate, through the rate loop and
    SIH's yaw torque, lags, catches up at 62-79 degrees/s and carries the heading 9-17 degrees
    past the setpoint (the shared logs and the PX4 flights flown here). The built-in vehicle used to
    yaw at at most 45 degrees/s and stop on the setpoint (1-3 degrees past it)."""
    px4_peak = _first_turn(read_ulog(shared_data / "px4-sih" / "competition-mission2-run1.ulg"))[1]
    assert 60.0 < px4_peak < 80.0  # the oracle
    turns = []
    for seed in range(8):
        config, items = competition(shared_data, 2, seed)
        sink = MemorySink()
        fly_mission(config, items, sink=sink)
        sweep, peak, past = _first_turn(ULog(io.BytesIO(sink.logs[0])))
        assert 44.0 < sweep < 46.0, (seed, sweep)
        turns.append((peak, past))
    # judged on the median of eight seeds: a takeoff that turned back (EKF2's tilt error, as in
    # some of PX4's flights) comes to the leg off its track and turns less sharply
    peak, past = (float(np.median(c)) for c in zip(*turns, strict=True))
    assert 60.0 < peak < 85.0, turns
    assert 8.0 < past < 25.0, turns
