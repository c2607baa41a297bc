"""``vehicle_local_position``'s ``ax, ay, az`` are the kinematic acceleration, as PX4 logs them.

EKF2 publishes its velocity's derivative there (``EKF2.cpp``: ``lpos.ax = vel_deriv(0)``) and SIH
its body's (``sih.cpp``: ``local_position.ax = _v_I_dot(0)``, thrust, drag and gravity together):
in a steady cruise both read about zero, whatever the tilt against the drag. A user who
differentiates the velocity, or reads these fields, must get the same acceleration from our log
as from PX4's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.ulog import read_ulog

from .conftest import competition_log


def _acceleration_against_velocity(ulog: ULog, name: str) -> tuple[float, float, float]:
    """For the flying part of ``name``: the rms of the horizontal ``ax, ay``, the rms of their
    difference from the velocity's derivative (both over 1 s, so the estimate's noise does not
    count) and that derivative's rms."""
    d = ulog.get_dataset(name).data
    t = d["timestamp"] * 1e-6
    grid = np.arange(t[0], t[-1], 0.1)
    flying = np.interp(grid, t, d["z"]) < -2.0
    window = np.ones(10) / 10  # 1 s

    def smooth(v: np.ndarray) -> np.ndarray:
        return np.convolve(np.interp(grid, t, v), window, mode="same")

    logged = np.hypot(smooth(d["ax"]), smooth(d["ay"]))[flying]
    dvx = np.gradient(smooth(d["vx"]), grid)
    dvy = np.gradient(smooth(d["vy"]), grid)
    derivative = np.hypot(dvx, dvy)[flying]
    off = np.hypot(smooth(d["ax"]) - dvx, smooth(d["ay"]) - dvy)[flying]
    rms = lambda v: float(np.sqrt(np.mean(v * v)))  # noqa: E731
    return rms(logged), rms(off), rms(derivative)


@pytest.mark.parametrize("name", ["vehicle_local_position", "vehicle_local_position_groundtruth"])
def test_the_logged_acceleration_is_the_velocitys_derivative_as_in_px4s_log(shared_data: Path, name: str):
    # the shared log that carries SIH's ground truth too
    px4 = read_ulog(shared_data / "px4-sih" / "square-mission.ulg")
    theirs = _acceleration_against_velocity(px4, name)
    ours = _acceleration_against_velocity(competition_log(shared_data, 2), name)
    # the oracle: PX4's fields follow its velocity's derivative
    assert theirs[1] < 0.35 * theirs[2], theirs
    # ours too (the thrust's acceleration alone, drag left out, is off by about g tan(tilt) in
    # cruise: 4 m/s^2)
    assert ours[1] < 0.35 * ours[2], ours
    assert ours[0] < 1.5 * theirs[0], (ours, theirs)
