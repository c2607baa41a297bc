"""How a multicopter leaves the ground in PX4 v1.15 SIH: EKF2's tilt error, the kick, the setpoint.

SIH holds a grounded body still and level (``sih.cpp``); EKF2's roll and pitch drift off the truth
while the vehicle stands armed, the attitude controller levels the *estimated* body, and the rate
integrators wind up against the ground until the thrust lifts the body, which is let go with that
torque stored and overshoots (``simulator_sih.KICK_GAIN``, ``ekf2.TILT_*``). Where the estimate is
when the vehicle has risen decides how far the climb wanders from the takeoff setpoint (Mission's
climb goes straight up from where the mission started). Pure functions over logged arrays
(``vehicle_attitude`` and its ground truth, ``vehicle_local_position`` and its ground truth,
``trajectory_setpoint``: ``estimate_phases.VelocityAttitude`` and a ``Takeoff``);
``bench/bench_fidelity.py`` prints them for PX4's flights and the built-in vehicle's side by side.

96 PX4 v1.15 SIH flights of the competition missions' plans flown here (mission2's also at 6 and
8 m/s; 2026-11-29, their ground truth): EKF2's tilt error before the release 1.58 degrees (median;
p10 0.59, p90 2.86), the true tilt's peak after it 8.2 (3.8-17.2), the estimate 0.20 m (p90 0.43)
from the takeoff setpoint once the truth is 0.3 m up.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from uavtest.analysis.attitude_response import body_z_from_quaternion
from uavtest.analysis.estimate_phases import VelocityAttitude, tilt_offset
from uavtest.errors import BadInput

__all__ = [
    "PEAK_AFTER",
    "PEAK_BEFORE",
    "RELEASE_RISE",
    "RISEN",
    "TILT_MEAN_S",
    "Liftoff",
    "Takeoff",
    "liftoff_figures",
]

RELEASE_RISE = 0.02  # m: the truth this far above where it stood when armed: let go
RISEN = 0.3  # m: the truth this far above it: risen (where the setpoint offset is taken)
TILT_MEAN_S = 0.5  # s: EKF2's tilt error is the mean over this long, ending at the release
PEAK_BEFORE = 0.3  # s: the true tilt's peak is sought from this long before the release
PEAK_AFTER = 1.0  # s: to this long after it


class Takeoff(NamedTuple):
    """What a takeoff adds to a flight's ``VelocityAttitude``: ``armed_at`` (s), when it armed;
    ``z_truth``: the true altitude (NED down) at the flight's ``t_truth``; ``xy``: the estimated
    horizontal position (N, 2) at its ``t``; ``t_sp`` / ``sp_xy``: the trajectory setpoint's
    horizontal position (N, 2; NaN where it sets none) and its timestamps (s)."""

    armed_at: float
    z_truth: np.ndarray
    xy: np.ndarray
    t_sp: np.ndarray
    sp_xy: np.ndarray


class Liftoff(NamedTuple):
    """``tilt_error``: EKF2's tilt error (degrees, the estimated body z axis's horizontal offset
    from the true one, its mean over ``TILT_MEAN_S`` up to the release); ``tilt_peak``: the true
    body's largest tilt (degrees) from ``PEAK_BEFORE`` before to ``PEAK_AFTER`` after the release;
    ``setpoint_offset``: the estimate's horizontal distance (m) from the setpoint in force when the
    truth is ``RISEN`` up."""

    tilt_error: float
    tilt_peak: float
    setpoint_offset: float


def _crossing(t: np.ndarray, rise: np.ndarray, after: float, height: float, what: str) -> float:
    """The first time after ``after`` that ``rise`` (m above the ground) reaches ``height``."""
    i = np.flatnonzero((t > after) & (rise >= height))
    if not len(i):
        raise BadInput(f"lift-off: the truth never rose {height:g} m after arming ({what})")
    return float(t[i[0]])


def liftoff_figures(flight: VelocityAttitude, takeoff: Takeoff) -> Liftoff:
    """The lift-off's three figures (``Liftoff``). A flight whose truth never rose ``RISEN`` after
    arming, or that set no horizontal setpoint by then, raises ``BadInput``."""
    t_truth, z_truth = flight.t_truth, takeoff.z_truth
    rise = np.interp(takeoff.armed_at, t_truth, z_truth) - z_truth
    released = _crossing(t_truth, rise, takeoff.armed_at, RELEASE_RISE, "release")
    risen = _crossing(t_truth, rise, takeoff.armed_at, RISEN, "risen")
    lean = tilt_offset(flight, np.linspace(released - TILT_MEAN_S, released, 26))
    tilt_error = float(np.degrees(np.hypot(*lean.mean(axis=0))))
    t_att = flight.t_att_truth
    window = (t_att >= released - PEAK_BEFORE) & (t_att <= released + PEAK_AFTER)
    if not window.any():
        raise BadInput("lift-off: no true attitude logged around the release")
    horizontal = np.hypot(*body_z_from_quaternion(flight.q_truth[window]).T)
    tilt_peak = float(np.degrees(np.arcsin(np.clip(horizontal.max(), 0.0, 1.0))))
    set_ = np.flatnonzero(np.isfinite(takeoff.sp_xy).all(axis=1) & (takeoff.t_sp <= risen))
    if not len(set_):
        raise BadInput("lift-off: no horizontal setpoint before the vehicle rose")
    here = np.array([np.interp(risen, flight.t, takeoff.xy[:, i]) for i in range(2)])
    return Liftoff(tilt_error, tilt_peak, float(np.hypot(*(here - takeoff.sp_xy[set_[-1]]))))
