"""PX4 SIH's body is fixed by its parameters and its auto yaw sweeps at MPC_YAWRAUTO_MAX: replicas
differ by noise (EKF2, wind, timing), not by a different airframe. The local planner's system
(Gazebo, not lockstep), calibrated on the competition's flights, keeps its spread."""

import io

import numpy as np
from pyulog import ULog

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


def test_a_mission_corner_is_turned_at_mpc_yawrauto_max(shared_data):
    """PX4 v1.15 SIH turns mission2's corner with its yaw setpoint moving at exactly 45 degrees/s
    (MPC_YAWRAUTO_MAX, ``FlightTaskAuto::_limitYawRate``) and its heading following it. Before
    this, the built-in vehicle yawed at 27-45 degrees/s, by seed."""
    for seed in range(4):
        config, items = competition(shared_data, 2, seed)
        sink = MemorySink()
        fly_mission(config, items, sink=sink)
        lp = ULog(io.BytesIO(sink.logs[0])).get_dataset("vehicle_local_position").data
        t = lp["timestamp"] / 1e6
        grid = np.arange(t[0], t[-1], 0.1)
        heading = np.degrees(np.interp(grid, t, np.unwrap(lp["heading"])))
        rate = np.convolve(np.gradient(heading, grid), np.ones(5) / 5, mode="same")
        assert 40.0 < np.abs(rate).max() < 50.0, seed
