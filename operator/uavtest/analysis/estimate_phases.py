"""How EKF2's errors depend on what the vehicle is doing: at rest or at cruise, in the climb, and
with its own tilt error. Pure functions over logged arrays (``vehicle_local_position``, its ground
truth, ``vehicle_attitude`` and its ground truth); ``bench/bench_fidelity.py`` prints them for PX4
v1.15 SIH's flights and the built-in vehicle's side by side.

- ``body_errors_by_speed``: the estimated velocity's error against the truth, in the body frame
  (the estimated heading), rms fore-aft and sideways, at rest in the air and at a steady cruise.
  24 PX4 SIH flights of the competition missions (stops 35-36): 0.15 / 0.22 m/s at rest, 0.17 /
  0.30 at a cruise above 4.2 m/s. The error grows with the speed, mostly sideways.
- ``climb_wander``: how far the estimate strays horizontally from where it lifted off while it
  climbs, from 5 s after lift-off (the takeoff's slide is over) until the takeoff item is
  reached. The controller holds the estimate on the takeoff point, so this is the part of EKF2's
  velocity error its position does not follow. A first leg that starts more than the acceptance
  radius off its track goes "offtrack" (FlightTaskAuto) and brakes early. 24 PX4 SIH flights,
  8-10 s after lift-off: 0.20 m median, 0.37 p90; the built-in vehicle 0.23-0.29, 0.53 (stop 38).
- ``position_errors_by_phase``: the estimated position's error against the truth, mean magnitude,
  across the track on a leg (true speed above ``LEG_SPEED``: the along-track part is mostly
  the GPS lead) and at rest in the air. PX4's position follows part of its tilt push: 24 PX4 SIH
  flights, 0.24-0.29 m across, 0.30-0.34 at rest; the built-in vehicle 0.14-0.15 and 0.18
  before stop 39, 0.20-0.21 and 0.26-0.27 since.
- ``tilt_push_response``: at low speed, the velocity error against the leaky integral (1 s) of
  g x the tilt error (the estimated body z axis's horizontal offset from the true one): its
  least-squares slope and correlation. The attitude controller levels the estimated body, so the
  true thrust leans by the tilt error and EKF2 misses that push until GPS fusion takes it back.
  24 PX4 SIH flights: slope 0.86, correlation 0.62; the built-in vehicle 0.30, 0.24 (stop 38).
- ``heading_turn_series`` / ``heading_turn_response``: in steady flight (faster than
  ``TURN_SPEED``, not accelerating), the velocity error sideways (across the true velocity)
  against EKF2's heading error times the true speed. In 64 PX4 v1.15 SIH flights of mission2's
  plan under seven parameter sets and of mission1 and mission3 (stop 41) the slope is -0.26 to
  -0.51 (correlation -0.23 to -0.46; -0.15 / -0.14 with a 3 m/s cruise): where EKF2's heading is
  off, its velocity is off sideways the other way, more so the faster the vehicle flies. The
  built-in vehicle draws the two independently (+0.06 to +0.16, -0.10 at 8 m/s).
- ``leg_start_response``: per leg of at least ``LEG_RESPONSE_MIN`` metres, the velocity error
  across the leg (estimate minus truth, positive 90 degrees clockwise of the leg seen from above)
  ``LEG_RESPONSE_AT`` seconds after the navigator set its target, signed by EKF2's heading error
  ``LEG_RESPONSE_SIGN_AT`` seconds in; ``leg_start_means`` averages the legs. In 84 PX4 v1.15
  SIH flights of twelve sets (the competition missions, mission2's plan at ``MPC_XY_CRUISE`` 6 and
  8, flown with three start times so that SIH's seeded noise differs; stop 43) the error is +0.08
  to +0.16 m/s 1 s in (EKF2 misses part of the acceleration the heading error turns), crosses zero
  2.5-3.5 s in and is -0.04 to -0.29 from 4 to 8 s: EKF2, once the acceleration makes its yaw
  observable, turns the miss into accelerometer bias and overshoots; its estimate, pushed back
  toward the track, is on it again 5-6 s in and the true vehicle crosses to the other side. The
  built-in vehicle's stays positive through 5 s (+0.07 to +0.16 at 3 s, +0.01 to +0.13 at 5 s).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.signal import lfilter

from uavtest.analysis.attitude_response import body_z_from_quaternion
from uavtest.analysis.fidelity import body_frame_series, errors_on
from uavtest.errors import BadInput

__all__ = [
    "CLIMB_AFTER",
    "CRUISE_SPEED",
    "LEG_RESPONSE_AT",
    "LEG_RESPONSE_MIN",
    "LEG_RESPONSE_SIGN_AT",
    "LEG_SPEED",
    "REST_SPEED",
    "SLOW_SPEED",
    "PositionErrors",
    "Regression",
    "SpeedErrors",
    "TiltPush",
    "VelocityAttitude",
    "body_errors_by_speed",
    "climb_wander",
    "heading_turn_response",
    "heading_turn_series",
    "leg_start_means",
    "leg_start_response",
    "position_errors_by_phase",
    "tilt_offset",
    "tilt_push_response",
    "tilt_push_series",
]

GRAVITY = 9.80665  # m/s^2
REST_SPEED = 0.5  # m/s: below this the vehicle is at rest (hovering, climbing, descending)
CRUISE_SPEED = 4.2  # m/s: above this, and not accelerating, it cruises
LEG_SPEED = 3.5  # m/s: above this it flies a leg (``position_errors_by_phase``)
STEADY_ACC = 0.5  # m/s^2: the true horizontal acceleration (0.5 s mean) below which it is steady
SLOW_SPEED = 1.0  # m/s: ``tilt_push_response`` looks below this speed
CLIMB_AFTER = 5.0  # s after lift-off: the takeoff's slide is over, the climb goes on
PUSH_TAU = 1.0  # s: the leaky integral of g x the tilt error (``ekf2.TILT_VEL_TAU``)
TURN_SPEED = 2.0  # m/s: ``heading_turn_series`` looks above this true speed
LEG_RESPONSE_MIN = 40.0  # m: ``leg_start_response`` looks at legs at least this long
LEG_RESPONSE_AT = (1.0, 3.0, 5.0, 7.0)  # s after the leg's target was set
LEG_RESPONSE_SIGN_AT = 3.0  # s: the heading error that signs a leg's response
RATE = 20.0  # Hz: every series is resampled onto this grid


@dataclass(frozen=True, slots=True)
class SpeedErrors:
    """One flight's velocity error (m/s rms, body frame) at rest and at cruise; NaN where it has
    fewer than ``min_samples`` samples (``body_errors_by_speed``)."""

    rest_fore: float
    rest_side: float
    cruise_fore: float
    cruise_side: float


@dataclass(frozen=True, slots=True)
class PositionErrors:
    """One flight's position error (m, mean magnitude) across the track on a leg and at rest in the
    air; NaN where it has fewer than ``min_samples`` samples (``position_errors_by_phase``)."""

    across: float
    rest: float


@dataclass(frozen=True, slots=True)
class Regression:
    """A least-squares response, flights pooled: the slope of y on x, their correlation, and the
    number of samples."""

    slope: float
    correlation: float
    samples: int


#: the velocity error's response to g x the tilt error, leaky-integrated (``tilt_push_response``)
TiltPush = Regression


class VelocityAttitude(NamedTuple):
    """One flight's horizontal velocities and attitudes, estimate and ground truth, each with its
    own timestamps (s): ``velocity`` / ``truth_velocity`` (N, 2) / (M, 2), NED; ``q`` / ``q_truth``
    attitudes (w, x, y, z). What ``tilt_push_series`` and ``heading_turn_series`` read."""

    t: np.ndarray
    velocity: np.ndarray
    t_truth: np.ndarray
    truth_velocity: np.ndarray
    t_att: np.ndarray
    q: np.ndarray
    t_att_truth: np.ndarray
    q_truth: np.ndarray


def _grid(window: tuple[float, float], what: str) -> np.ndarray:
    start, end = window
    if not end - start > 1.0:
        raise BadInput(f"{what}: the window {start:.1f}-{end:.1f} s is shorter than a second")
    return np.arange(start, end, 1.0 / RATE)


def _rms(x: np.ndarray, min_samples: int) -> float:
    return float(np.sqrt(np.mean(x * x))) if len(x) >= min_samples else float("nan")


def body_errors_by_speed(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    window: tuple[float, float],
    min_samples: int = 40,
) -> SpeedErrors:
    """``estimate``: (N, 3) vx, vy (NED), heading (rad) as ``vehicle_local_position`` logs them;
    ``truth``: (M, 2) true vx, vy; ``window``: the seconds to look at (in the air). At rest: the
    true horizontal speed below ``REST_SPEED``; at cruise: above ``CRUISE_SPEED`` while the true
    acceleration (0.5 s mean) stays below ``STEADY_ACC``."""
    g = _grid(window, "body errors by speed")
    vx, vy = np.interp(g, t_truth, truth[:, 0]), np.interp(g, t_truth, truth[:, 1])
    fore, side = body_frame_series(g, t, estimate, t_truth, truth)
    k = max(1, round(0.5 * RATE))
    ax = np.convolve(np.gradient(vx, g), np.ones(k) / k, "same")
    ay = np.convolve(np.gradient(vy, g), np.ones(k) / k, "same")
    speed = np.hypot(vx, vy)
    rest = speed < REST_SPEED
    cruise = (speed > CRUISE_SPEED) & (np.hypot(ax, ay) < STEADY_ACC)
    return SpeedErrors(
        rest_fore=_rms(fore[rest], min_samples),
        rest_side=_rms(side[rest], min_samples),
        cruise_fore=_rms(fore[cruise], min_samples),
        cruise_side=_rms(side[cruise], min_samples),
    )


def _mean_abs(x: np.ndarray, min_samples: int) -> float:
    return float(np.mean(np.abs(x))) if len(x) >= min_samples else float("nan")


def position_errors_by_phase(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    window: tuple[float, float],
    min_samples: int = 40,
) -> PositionErrors:
    """``estimate``: (N, 2) x, y (NED) as ``vehicle_local_position`` logs them; ``truth``: (M, 4)
    true x, y, vx, vy; ``window``: the seconds to look at (in the air). Across the track: the
    error's component across the true velocity where the true speed is above ``LEG_SPEED``; at
    rest: its magnitude where the true speed is below ``REST_SPEED``."""
    g = _grid(window, "position errors by phase")
    ex, ey = errors_on(g, t, estimate, t_truth, truth, 2).T
    vx, vy = np.interp(g, t_truth, truth[:, 2]), np.interp(g, t_truth, truth[:, 3])
    speed = np.hypot(vx, vy)
    leg = speed > LEG_SPEED
    across = (ey[leg] * vx[leg] - ex[leg] * vy[leg]) / speed[leg]
    rest = speed < REST_SPEED
    return PositionErrors(
        across=_mean_abs(across, min_samples),
        rest=_mean_abs(np.hypot(ex[rest], ey[rest]), min_samples),
    )


def climb_wander(
    t: np.ndarray, x: np.ndarray, y: np.ndarray, liftoff: float, until: float, after: float = CLIMB_AFTER
) -> float:
    """The estimate's mean horizontal distance (m) from where it was at ``liftoff`` (s), from
    ``after`` seconds after it until ``until`` (s: the takeoff item reached). A climb shorter than
    that plus a second raises ``BadInput``."""
    g = _grid((liftoff + after, min(until, float(t[-1]))), "climb wander")
    x0, y0 = np.interp(liftoff, t, x), np.interp(liftoff, t, y)
    return float(np.mean(np.hypot(np.interp(g, t, x) - x0, np.interp(g, t, y) - y0)))


def _truth_and_error(flight: VelocityAttitude, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The true horizontal velocity on grid ``g`` and the estimate's error against it, (N, 2) each."""
    vt = np.column_stack([np.interp(g, flight.t_truth, flight.truth_velocity[:, i]) for i in range(2)])
    return vt, errors_on(g, flight.t, flight.velocity, flight.t_truth, flight.truth_velocity, 2)


def tilt_offset(flight: VelocityAttitude, g: np.ndarray) -> np.ndarray:
    """(N, 2): EKF2's tilt error at times ``g``, the estimated body z axis's horizontal components
    less the true one's (quaternions interpolated component-wise: their samples are milliseconds
    apart)."""
    est = np.column_stack([np.interp(g, flight.t_att, flight.q[:, i]) for i in range(4)])
    tru = np.column_stack([np.interp(g, flight.t_att_truth, flight.q_truth[:, i]) for i in range(4)])
    return body_z_from_quaternion(est) - body_z_from_quaternion(tru)


def tilt_push_series(flight: VelocityAttitude, window: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """One flight's (push, velocity error) samples, both axes, where the true speed is below
    ``SLOW_SPEED`` within ``window``, each about its mean. The push is -g x the body z axis's
    horizontal offset (estimate minus truth), leaky-integrated over ``PUSH_TAU``: a tilt error
    towards north hides a push towards south. A flight with no slow stretch of 2 s raises ``BadInput``."""
    g = _grid(window, "tilt push")
    offset = tilt_offset(flight, g)
    # push[i] = a push[i-1] - g offset[i] / RATE, push[0] = 0: at rest at the window's start
    a = np.exp(-1.0 / (RATE * PUSH_TAU))
    drive = offset.copy()
    drive[0] = 0.0
    push = lfilter([-GRAVITY / RATE], [1.0, -a], drive, axis=0)
    vt, err = _truth_and_error(flight, g)
    slow = np.hypot(vt[:, 0], vt[:, 1]) < SLOW_SPEED
    if slow.sum() < 2 * RATE:
        raise BadInput("tilt push: the vehicle was slower than 1 m/s for less than 2 s")
    p, e = push[slow], err[slow]
    return (p - p.mean(axis=0)).ravel(), (e - e.mean(axis=0)).ravel()


def _pooled(series: Sequence[tuple[np.ndarray, np.ndarray]], what: str, x_name: str) -> Regression:
    """y regressed on x, every flight's samples together, about their pooled means."""
    if not series:
        raise BadInput(f"{what}: no flight to measure")
    x = np.concatenate([s[0] for s in series])
    y = np.concatenate([s[1] for s in series])
    x, y = x - x.mean(), y - y.mean()
    xx, yy = float(np.dot(x, x)), float(np.dot(y, y))
    if xx <= 0.0 or yy <= 0.0:
        raise BadInput(f"{what}: the {x_name} or the velocity error never changed")
    xy = float(np.dot(x, y))
    return Regression(slope=xy / xx, correlation=xy / float(np.sqrt(xx * yy)), samples=len(x))


def tilt_push_response(series: Sequence[tuple[np.ndarray, np.ndarray]]) -> Regression:
    """The velocity error regressed on the push, flights pooled (``tilt_push_series``): a slope
    of 1 is a push EKF2 misses entirely, 0 one it sees (or balances) at once."""
    return _pooled(series, "tilt push", "tilt error")


def _yaw(q: np.ndarray) -> np.ndarray:
    """The heading (rad) of attitudes (w, x, y, z), unwrapped."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.unwrap(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


def heading_turn_series(
    flight: VelocityAttitude, window: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """One flight's (heading error x true speed, sideways velocity error) samples where it flies
    steadily within ``window``: faster than ``TURN_SPEED``, its true acceleration (0.5 s mean)
    below ``STEADY_ACC``. The heading error is the estimate's minus the truth's (rad); sideways is
    90 degrees clockwise from the true velocity seen from above (east of a vehicle flying north),
    the error the estimate's minus the truth's. A flight never steady for 2 s raises ``BadInput``."""
    g = _grid(window, "heading turn")
    vt, err = _truth_and_error(flight, g)
    speed = np.hypot(vt[:, 0], vt[:, 1])
    k = max(1, round(0.5 * RATE))
    acc = np.hypot(*(np.convolve(np.gradient(vt[:, i], g), np.ones(k) / k, "same") for i in range(2)))
    steady = (speed > TURN_SPEED) & (acc < STEADY_ACC)
    if steady.sum() < 2 * RATE:
        raise BadInput("heading turn: the vehicle flew steadily faster than 2 m/s for less than 2 s")
    err = err[steady]
    ux, uy = (vt[steady] / speed[steady, None]).T
    side = -err[:, 0] * uy + err[:, 1] * ux
    eh = np.interp(g, flight.t_att, _yaw(flight.q)) - np.interp(g, flight.t_att_truth, _yaw(flight.q_truth))
    eh = np.angle(np.exp(1j * eh))[steady]
    return eh * speed[steady], side


def heading_turn_response(series: Sequence[tuple[np.ndarray, np.ndarray]]) -> Regression:
    """The sideways velocity error regressed on heading error x speed, flights pooled
    (``heading_turn_series``): its slope (s: m/s of error per rad x m/s) and correlation."""
    return _pooled(series, "heading turn", "heading error")


def leg_start_response(flight: VelocityAttitude, changes: np.ndarray) -> list[np.ndarray]:
    """Per leg (module docstring), the velocity error across it at ``LEG_RESPONSE_AT`` seconds
    after its start, times the sign of the heading error ``LEG_RESPONSE_SIGN_AT`` seconds in.
    ``changes``: the setpoint triplet's changes (``ulog.setpoint_changes``: time, north, east,
    acceptance radius); a leg runs from one target to the next and starts when the next is set.
    Legs shorter than ``LEG_RESPONSE_MIN``, those the log (truth or attitude) ends within, and
    those whose heading error is exactly zero are left out."""
    out: list[np.ndarray] = []
    ends = min(flight.t[-1], flight.t_truth[-1], flight.t_att[-1], flight.t_att_truth[-1])
    yaw, yaw_truth = _yaw(flight.q), _yaw(flight.q_truth)  # once per flight, not per leg
    for k in range(1, len(changes)):
        _, px, py, _ = changes[k - 1]
        start, tx, ty, _ = changes[k]
        length = float(np.hypot(tx - px, ty - py))
        g = start + np.asarray(LEG_RESPONSE_AT)
        if length < LEG_RESPONSE_MIN or max(g[-1], start + LEG_RESPONSE_SIGN_AT) > ends:
            continue
        ux, uy = (tx - px) / length, (ty - py) / length
        _, err = _truth_and_error(flight, g)
        side = -err[:, 0] * uy + err[:, 1] * ux
        at = start + LEG_RESPONSE_SIGN_AT
        eh = np.interp(at, flight.t_att, yaw) - np.interp(at, flight.t_att_truth, yaw_truth)
        sign = float(np.sign(np.angle(np.exp(1j * eh))))
        if sign != 0.0:
            out.append(side * sign)
    return out


def leg_start_means(legs: Sequence[np.ndarray]) -> np.ndarray:
    """The mean over legs of ``leg_start_response`` (one value per ``LEG_RESPONSE_AT``); NaN
    without a leg."""
    if not legs:
        return np.full(len(LEG_RESPONSE_AT), np.nan)
    return np.mean(np.vstack(legs), axis=0)
