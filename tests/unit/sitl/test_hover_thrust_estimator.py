"""PX4's hover thrust estimator and what it does to a SIH flight: it learns SIH's vertical drag
during the takeoff climb as hover thrust (0.5 -> ~0.56 in PX4 v1.15 SIH, true 0.49), unlearns it
over the next tens of seconds, and meanwhile PositionControl's horizontal anti-windup bleeds the
velocity integrator, so the vehicle gathers speed on its first leg more slowly."""

import dataclasses
import io

import numpy as np
import pytest
from pyulog import ULog

from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mc_hover_thrust_estimator import HoverThrustEstimator
from uavtest.sitl.params import ParamStore
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.simulator_sih import HOVER_THRUST

from .conftest import competition

G = 9.80665


def _fly(hte: HoverThrustEstimator, seconds: float, vz_up: float, drag: float = 1.0) -> None:
    """Feed the estimator SIH's physics holding a climb rate: the thrust that does so against
    the drag, and the acceleration it measures (none: a steady climb)."""
    thrust = HOVER_THRUST * (G + drag * vz_up) / G
    for _ in range(int(seconds * 50)):
        hte.update(0.02, 0.0, thrust, -vz_up, 0.0, 5.0, False)


def test_it_learns_the_climbs_drag_and_unlearns_it_in_level_flight():
    hte = HoverThrustEstimator(ParamStore())
    assert hte.hover == 0.5 and not hte.valid
    _fly(hte, 7.0, 1.3)  # the takeoff climb
    climbed = hte.hover
    assert 0.53 < climbed < 0.58 and hte.valid
    _fly(hte, 15.0, 0.0)  # a level leg
    assert HOVER_THRUST < hte.hover < climbed - 0.02
    hte.reset()  # disarmed
    assert hte.hover == hte.used == 0.5 and not hte.valid


def test_it_waits_for_the_air_and_stops_when_landed():
    hte = HoverThrustEstimator(ParamStore())
    thrust = HOVER_THRUST * 1.2
    for _ in range(200):  # on the ground, or below 1 m after takeoff: not in the air yet
        assert not hte.update(0.02, 0.0, thrust, 0.0, 0.0, 0.5, False)
    assert hte.hover == 0.5
    hte.update(0.02, 0.0, thrust, 0.0, 0.0, 1.5, False)
    assert hte.hover != 0.5
    moved = hte.hover
    hte.update(0.02, 0.0, thrust, 0.0, 0.0, 0.0, True)
    assert hte.hover == moved


def _first_leg(shared_data, seed: int, use_hte: int) -> tuple[np.ndarray, float]:
    config, items = competition(shared_data, 1, seed)
    # PX4 SIH's flights start on the takeoff item (mission1's planned home is 0.45 m off it, and
    # PX4 v1.15 flies to the takeoff item's position after the climb, Mission::handleTakeoff)
    home = config.home.model_copy(update={"lat": items[0].lat, "lon": items[0].lon})
    config = dataclasses.replace(config, home=home, params={**config.params, "MPC_USE_HTE": use_hte})
    sink = MemorySink()
    fly_mission(config, items, sink=sink)
    log = ULog(io.BytesIO(sink.logs[0]))
    lp = log.get_dataset("vehicle_local_position").data
    result = log.get_dataset("mission_result").data
    start = result["timestamp"][np.flatnonzero(result["seq_current"] == 1)[0]]
    leg = lp["timestamp"] >= start
    moved = np.hypot(lp["x"][leg] - lp["x"][leg][0], lp["y"][leg] - lp["y"][leg][0])
    speed = np.hypot(lp["vx"][leg], lp["vy"][leg])
    hover = log.get_dataset("hover_thrust_estimate").data["hover_thrust"]
    return hover, float(speed[np.searchsorted(moved, 15.0)])


def test_a_competition_flight_logs_px4s_estimate_and_gathers_speed_as_px4_does(shared_data):
    """PX4 v1.15 SIH, mission1 (8 flights flown here): the estimate 0.56 after the climb, 0.50
    at the end of the leg, 0.47 after the descent; 3.76 / 4.09 m/s at 10 / 20 m into the leg
    (median), where without the estimate the built-in vehicle flew 3.96 / 4.28."""
    with_hte, without = [], []
    for seed in range(4):
        hover, v15 = _first_leg(shared_data, seed, 1)
        assert 0.52 < hover.max() < 0.59
        assert 0.45 < hover[-1] < 0.50
        with_hte.append(v15)
        without.append(_first_leg(shared_data, seed, 0)[1])
    # slower with the estimate in every flight that does not slow down mid-leg (offtrack: seed 2
    # here, to 3.4 m/s at 15 m with the estimate, 3.1 without; PX4's cruise 3.76-4.09); the
    # median, as one in four may
    cruising = [(w, wo) for w, wo in zip(with_hte, without, strict=True) if min(w, wo) > 3.5]
    assert len(cruising) >= 2 and all(w < wo for w, wo in cruising), (with_hte, without)
    assert np.median(with_hte) == pytest.approx(3.95, abs=0.2)
