"""MPC_YAW_MODE picks a mission's heading as PX4 v1.15's FlightTaskAuto does
(``_set_heading_from_mode``, ``_generateHeadingAlongTraj``, ``_limitYawRate``): 0 faces the
waypoint, 1 home, 2 away from home, 3 along the trajectory, 4 faces the waypoint and holds the
trajectory until the heading is there. Until stop 41 the built-in vehicle flew modes 1-4 holding its
takeoff heading."""

from __future__ import annotations

import dataclasses
import io
import math

import numpy as np
import pytest
from pyulog import ULog

from uavtest.sitl.geo import Projection
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mav import MavCmd, MavFrame
from uavtest.sitl.mission import NavItem
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.models import Home

HOME = Home()
CORNER = (30.0, 0.0)
END = (30.0, 30.0)


def _square() -> list[NavItem]:
    """Takeoff to 10 m, 30 m North, then 30 m East, land there: no holds, the corner turned."""
    proj = Projection(HOME.lat, HOME.lon)
    rel = MavFrame.GLOBAL_RELATIVE_ALT_INT

    def at(seq: int, cmd: int, north: float, east: float, alt: float) -> NavItem:
        lat, lon = proj.reproject(north, east)
        return NavItem(seq, cmd, rel, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)

    return [
        at(0, MavCmd.NAV_TAKEOFF, 0.0, 0.0, 10.0),
        at(1, MavCmd.NAV_WAYPOINT, *CORNER, 10.0),
        at(2, MavCmd.NAV_WAYPOINT, *END, 10.0),
        at(3, MavCmd.NAV_LAND, *END, 0.0),
    ]


def _fly(mode: int, seed: int = 1) -> ULog:
    params = {"MIS_TAKEOFF_ALT": 5.0, "MPC_XY_CRUISE": 8.0, "MPC_YAW_MODE": mode}
    sink = MemorySink()
    fly_mission(dataclasses.replace(SimConfig(home=HOME, params=params, seed=seed)), _square(), sink=sink)
    return ULog(io.BytesIO(sink.logs[0]))


def _headings_mid_leg(
    ulog: ULog,
    start: tuple[float, float],
    end: tuple[float, float],
    window: tuple[float, float] = (10.0, 20.0),
) -> np.ndarray:
    """The estimated heading (deg) where the estimate is ``window`` m down the leg from start to end."""
    lp = ulog.get_dataset("vehicle_local_position").data
    att = ulog.get_dataset("vehicle_attitude").data
    ux, uy = end[0] - start[0], end[1] - start[1]
    n = math.hypot(ux, uy)
    along = ((lp["x"] - start[0]) * ux + (lp["y"] - start[1]) * uy) / n
    across = (-(lp["x"] - start[0]) * uy + (lp["y"] - start[1]) * ux) / n
    t = lp["timestamp"][(along > window[0]) & (along < window[1]) & (np.abs(across) < 3.0)]
    w, x, y, z = (att[f"q[{i}]"] for i in range(4))
    yaw = np.degrees(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))
    return np.interp(t, att["timestamp"], np.unwrap(yaw, period=360.0))


def _off(headings: np.ndarray, expected: float) -> float:
    """The median heading's angle from ``expected`` (deg)."""
    return abs((float(np.median(headings)) - expected + 180.0) % 360.0 - 180.0)


@pytest.mark.parametrize(
    ("mode", "first_leg", "second_leg"),
    [
        (0, 0.0, 90.0),  # towards the waypoint
        (1, 180.0, math.degrees(math.atan2(-15.0, -30.0))),  # towards home, mid-leg at (30, 15)
        (2, 0.0, math.degrees(math.atan2(15.0, 30.0))),  # away from home
        (3, 0.0, 90.0),  # along the trajectory
    ],
)
def test_the_heading_on_a_leg_follows_mpc_yaw_mode(mode: int, first_leg: float, second_leg: float) -> None:
    ulog = _fly(mode)
    # the vehicle lifts off facing east and turns at MPC_YAWRAUTO_MAX once it is farther than the
    # acceptance radius from the waypoint (or home) it faces: the end of the first leg
    assert _off(_headings_mid_leg(ulog, (0.0, 0.0), CORNER, (20.0, 27.0)), first_leg) < 8.0
    assert _off(_headings_mid_leg(ulog, CORNER, END), second_leg) < 8.0


def _slowest_trajectory_near(ulog: ULog, point: tuple[float, float], within: float = 3.0) -> float:
    sp = ulog.get_dataset("trajectory_setpoint").data
    near = np.hypot(sp["position[0]"] - point[0], sp["position[1]"] - point[1]) < within
    return float(np.hypot(sp["velocity[0]"], sp["velocity[1]"])[near].min())


def test_mode_4_stops_at_the_corner_until_it_faces_the_next_leg() -> None:
    # mode 0 turns the corner at computeMaxSpeedInWaypoint's speed (about 1.7 m/s, the heading
    # following on the way out); mode 4 holds the trajectory (a zero velocity setpoint) until the
    # heading setpoint is within MIS_YAW_ERR of the next waypoint's bearing
    assert _slowest_trajectory_near(_fly(0), CORNER) > 1.0
    held = _fly(4)
    assert _slowest_trajectory_near(held, CORNER) < 0.3
    assert _off(_headings_mid_leg(held, CORNER, END), 90.0) < 8.0


def test_mode_3_points_along_the_trajectory_through_the_corner() -> None:
    ulog = _fly(3)
    sp = ulog.get_dataset("trajectory_setpoint").data
    att = ulog.get_dataset("vehicle_attitude").data
    speed = np.hypot(sp["velocity[0]"], sp["velocity[1]"])
    along = np.degrees(np.arctan2(sp["velocity[1]"], sp["velocity[0]"]))
    w, x, y, z = (att[f"q[{i}]"] for i in range(4))
    yaw_sp = np.degrees(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))
    heading = np.interp(sp["timestamp"], att["timestamp"], np.unwrap(yaw_sp, period=360.0))
    off = np.abs((heading - along + 180.0) % 360.0 - 180.0)
    far = np.hypot(sp["position[0]"] - END[0], sp["position[1]"] - END[1]) > 5.0
    # the first leg, once the heading has turned from the east it lifted off with, and the second
    for leg in (sp["position[0]"] < 25.0, sp["position[0]"] > 29.0):
        moving = (speed > 3.0) & far & leg
        assert moving.sum() > 10 and np.median(off[moving]) < 5.0
