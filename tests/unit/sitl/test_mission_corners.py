"""A waypoint without a hold time is a corner, not a stop: PX4 v1.15's navigator hands the next
item to the setpoint triplet (Mission::setActiveMissionItems) and PositionSmoothing turns through
it at computeMaxSpeedInWaypoint's speed (MPC_XY_TRAJ_P x MPC_ACC_HOR, the acceptance radius)."""

from __future__ import annotations

import dataclasses
import io
import math
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.ulog import read_ulog
from uavtest.sitl.geo import Projection
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mav import MavCmd, MavFrame
from uavtest.sitl.mission import NavItem
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.models import Home

HOME = Home()
CORNER = (30.0, 0.0)


def _square(hold: float) -> list[NavItem]:
    """The SIH square: takeoff to 10 m, 30 m North (holding ``hold`` s), 30 m East, land there."""
    proj = Projection(HOME.lat, HOME.lon)
    rel = MavFrame.GLOBAL_RELATIVE_ALT_INT

    def at(seq: int, cmd: int, north: float, east: float, alt: float, p1: float = 0.0) -> NavItem:
        lat, lon = proj.reproject(north, east)
        return NavItem(seq, cmd, rel, param1=p1, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)

    return [
        at(0, MavCmd.NAV_TAKEOFF, 0.0, 0.0, 10.0),
        at(1, MavCmd.NAV_WAYPOINT, *CORNER, 10.0, hold),
        at(2, MavCmd.NAV_WAYPOINT, 30.0, 30.0, 10.0),
        at(3, MavCmd.NAV_LAND, 30.0, 30.0, 0.0),
    ]


def _slowest_setpoint_near_the_corner(ulog: ULog, corner: tuple[float, float], within: float = 4.0) -> float:
    sp = ulog.get_dataset("trajectory_setpoint").data
    near = np.hypot(sp["position[0]"] - corner[0], sp["position[1]"] - corner[1]) < within
    return float(np.hypot(sp["velocity[0]"], sp["velocity[1]"])[near].min())


def _fly(hold: float, seed: int = 1) -> ULog:
    config = SimConfig(home=HOME, params={"MIS_TAKEOFF_ALT": 5.0, "MPC_XY_CRUISE": 8.0}, seed=seed)
    sink = MemorySink()
    fly_mission(dataclasses.replace(config), _square(hold), sink=sink)
    return ULog(io.BytesIO(sink.logs[0]))


def test_a_corner_without_a_hold_is_turned_at_px4s_corner_speed() -> None:
    # at most sqrt(MPC_XY_TRAJ_P 0.5 * MPC_ACC_HOR 3 * NAV_ACC_RAD 2 * tan(45 deg)) = 1.73 m/s,
    # less as the turn's speed lock and the new leg's L1 point take over
    slowest = _slowest_setpoint_near_the_corner(_fly(hold=0.0), CORNER)
    assert 1.2 < slowest <= math.sqrt(3.0) + 0.05


def test_a_hold_time_stops_the_vehicle_at_the_waypoint() -> None:
    # PX4 brakes for a hold (brake_for_hold: the triplet's next is invalid): the trajectory
    # creeps onto the waypoint (computeMaxSpeedFromDistance falls with the distance)
    assert _slowest_setpoint_near_the_corner(_fly(hold=3.0), CORNER) < 0.3


def test_the_corner_speed_is_px4_sihs(shared_data: Path) -> None:
    px4 = read_ulog(shared_data / "px4-sih" / "square-mission.ulg")
    lp = px4.get_dataset("vehicle_local_position").data
    # the square's corner in PX4's frame: where the logged trajectory turns East
    sp = px4.get_dataset("trajectory_setpoint").data
    north = float(np.nanmax(sp["position[0]"]))
    theirs = _slowest_setpoint_near_the_corner(px4, (north, float(np.nanmedian(lp["y"]))), within=4.0)
    ours = [_slowest_setpoint_near_the_corner(_fly(0.0, seed), CORNER) for seed in range(3)]
    assert theirs == pytest.approx(1.34, abs=0.1)  # what the log holds
    assert all(abs(o - theirs) < 0.15 for o in ours), (theirs, ours)
