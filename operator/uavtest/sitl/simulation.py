"""The PX4 ``src/modules/simulation`` pieces the built-in vehicle runs beside its physics.

One object on the vehicle (``Vehicle.sim``) so that the vehicle keeps few instance attributes
(CPython 3.11 specialises ``self.x`` loads in the hot loop only while an instance has at most 30):
``battery`` (battery_simulator), ``gps`` (the GPS and its failure injection), ``failure_injector``
(blocked motors and their tumble), ``failure_detector`` (commander/failure_detector),
``range_sensor`` (the simulated obstacle-distance sensor, None without one) and ``faulty``: a
failure was injected, so the per-tick failure paths run from then on; ``planner``: PX4-Avoidance's
local planner with its depth camera when the test flies with it (else None); ``hover_thrust``:
PX4's hover thrust estimator (mc_hover_thrust_estimator) with SIH's physics (else None).
"""

from __future__ import annotations

import random

from uavtest.sitl.battery_simulator import BatterySimulator
from uavtest.sitl.commander.failure_detector import FailureDetector, FailureInjector
from uavtest.sitl.local_planner import LocalPlanner
from uavtest.sitl.mc_hover_thrust_estimator import HoverThrustEstimator
from uavtest.sitl.params import ParamStore
from uavtest.sitl.sensor_gps_sim import GpsSimulator
from uavtest.sitl.sensor_obstacle_distance_sim import ObstacleDistanceSim
from uavtest.spec.models import RangeSensor

__all__ = ["Simulation"]


class Simulation:
    __slots__ = (
        "battery",
        "failure_detector",
        "failure_injector",
        "faulty",
        "gps",
        "hover_thrust",
        "planner",
        "range_sensor",
    )

    def __init__(self, params: ParamStore, seed: int, range_sensor: RangeSensor | None = None) -> None:
        self.gps = GpsSimulator(random.Random(f"{seed}:gps"))
        self.battery = BatterySimulator(params)
        self.failure_injector = FailureInjector()
        self.failure_detector = FailureDetector()
        self.faulty = False
        self.range_sensor = ObstacleDistanceSim(range_sensor) if range_sensor is not None else None
        self.planner: LocalPlanner | None = None
        #: PX4's hover thrust estimator, when the vehicle flies SIH's physics (else None: the
        #: local planner's system was calibrated without it)
        self.hover_thrust: HoverThrustEstimator | None = None
