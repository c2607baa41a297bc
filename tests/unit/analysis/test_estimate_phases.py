"""How EKF2's errors depend on the flight's phase (``analysis.estimate_phases``): synthetic flights
whose errors are known, measured the way ``bench/bench_fidelity.py`` measures PX4's and the built-in
vehicle's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uavtest.analysis.estimate_phases import (
    RATE,
    VelocityAttitude,
    body_errors_by_speed,
    climb_wander,
    heading_turn_response,
    heading_turn_series,
    leg_start_means,
    leg_start_response,
    position_errors_by_phase,
    tilt_push_response,
    tilt_push_series,
)
from uavtest.errors import BadInput

G = 9.80665


def _series(t, est, truth, q_est, q_true) -> VelocityAttitude:
    """A synthetic flight's series, all on one clock."""
    return VelocityAttitude(t, est, t, truth, t, q_est, t, q_true)


def _flight(errors_rest: tuple[float, float], errors_cruise: tuple[float, float]):
    """20 s hovering facing north, then 20 s cruising east at 5 m/s facing east (after 5 s of
    acceleration), the estimate off the truth by square waves of the given fore-aft / sideways
    amplitudes (rms = amplitude)."""
    t = np.arange(0.0, 45.0, 0.01)
    speed = np.clip((t - 20.0) / 5.0, 0.0, 1.0) * 5.0
    truth = np.column_stack([np.zeros_like(t), speed])
    heading = np.where(t < 20.0, 0.0, math.pi / 2)
    sign = np.where(np.floor(t * 2) % 2 == 0, 1.0, -1.0)
    fore_amp = np.where(t < 20.0, errors_rest[0], errors_cruise[0])
    side_amp = np.where(t < 20.0, errors_rest[1], errors_cruise[1])
    fore, side = fore_amp * sign, side_amp * -sign
    c, s = np.cos(heading), np.sin(heading)
    est = np.column_stack([truth[:, 0] + c * fore - s * side, truth[:, 1] + s * fore + c * side, heading])
    return t, est, truth


def test_the_errors_are_told_apart_at_rest_and_at_cruise_in_the_body_frame():
    t, est, truth = _flight((0.15, 0.22), (0.17, 0.30))  # PX4 SIH's (module docstring)
    e = body_errors_by_speed(t, est, t, truth, (1.0, 44.0))
    assert (e.rest_fore, e.rest_side) == (pytest.approx(0.15, abs=0.01), pytest.approx(0.22, abs=0.01))
    assert (e.cruise_fore, e.cruise_side) == (pytest.approx(0.17, abs=0.01), pytest.approx(0.30, abs=0.01))


def test_a_flight_that_never_cruises_has_no_cruise_figure():
    t, est, truth = _flight((0.15, 0.22), (0.17, 0.30))
    e = body_errors_by_speed(t, est, t, truth, (1.0, 19.0))  # the hover only
    assert e.rest_side == pytest.approx(0.22, abs=0.01)
    assert math.isnan(e.cruise_fore) and math.isnan(e.cruise_side)
    with pytest.raises(BadInput, match="shorter than a second"):
        body_errors_by_speed(t, est, t, truth, (3.0, 3.5))


def test_the_position_error_is_told_apart_across_a_leg_and_at_rest():
    """A hover 0.30 m off (north-east), then a leg east at 5 m/s: 0.25 m off across it (north) and
    0.5 m ahead along it (the GPS lead, which the across-track figure leaves out)."""
    t = np.arange(0.0, 45.0, 0.01)
    speed = np.clip((t - 20.0) / 5.0, 0.0, 1.0) * 5.0
    east = np.cumsum(speed) * 0.01
    truth = np.column_stack([np.zeros_like(t), east, np.zeros_like(t), speed])
    off = np.where(t < 20.5, 0.30 / math.sqrt(2), 0.0)  # at rest: below 0.5 m/s
    est = np.column_stack([off + np.where(t >= 20.5, 0.25, 0.0), east + off + np.where(t >= 20.5, 0.5, 0.0)])
    e = position_errors_by_phase(t, est, t, truth, (1.0, 44.0))
    assert e.rest == pytest.approx(0.30, abs=0.01)
    assert e.across == pytest.approx(0.25, abs=0.01)
    hover = position_errors_by_phase(t, est, t, truth, (1.0, 19.0))
    assert math.isnan(hover.across) and hover.rest == pytest.approx(0.30, abs=0.01)
    with pytest.raises(BadInput, match="position errors by phase"):
        position_errors_by_phase(t, est, t, truth, (3.0, 3.5))


def test_the_climb_wander_is_the_mean_distance_from_the_liftoff_point():
    t = np.arange(0.0, 20.0, 0.05)
    # lifted off at 2 s at (1, 1), then circling it 0.3 m off from 4 s on
    ang = 0.5 * t
    r = np.where(t < 4.0, 0.0, 0.3)
    x, y = 1.0 + r * np.cos(ang), 1.0 + r * np.sin(ang)
    assert climb_wander(t, x, y, liftoff=2.0, until=15.0) == pytest.approx(0.3, abs=1e-6)
    # the takeoff item reached 5.5 s after lift-off: no climb to measure after the slide
    with pytest.raises(BadInput, match="climb wander"):
        climb_wander(t, x, y, liftoff=2.0, until=7.5)


def _tilted(push_seen: float, seconds: float = 30.0, speed: float = 0.0):
    """A hover whose estimated body z axis is off the truth by a slow tilt error towards north,
    and whose velocity error is ``push_seen`` x the push that hides (a leaky 1 s integral of
    -g x the error): 1 misses it all, 0 sees it."""
    t = np.arange(0.0, seconds, 1.0 / RATE)
    tilt = math.radians(1.0) * np.sin(2 * math.pi * t / 7.0)  # about the east axis: z leans north
    half = tilt / 2
    q_est = np.column_stack([np.cos(half), np.zeros_like(t), np.sin(half), np.zeros_like(t)])
    q_true = np.column_stack([np.ones_like(t), np.zeros((len(t), 3))])
    offset_north = np.sin(tilt)  # body z's north component (quaternion about y: x-z plane)
    a = math.exp(-1.0 / RATE)
    push = np.zeros_like(t)
    for i in range(1, len(t)):
        push[i] = a * push[i - 1] - G * offset_north[i] / RATE
    truth = np.column_stack([np.full_like(t, speed), np.zeros_like(t)])
    est = truth + np.column_stack([push_seen * push, np.zeros_like(t)])
    return t, est, truth, q_est, q_true


@pytest.mark.parametrize("missed", [1.0, 0.3])
def test_the_push_a_tilt_error_hides_is_measured_as_the_share_ekf2_misses(missed: float):
    t, est, truth, q_est, q_true = _tilted(missed)
    series = tilt_push_series(
        VelocityAttitude(t, est, t, truth, t, q_est, t, q_true), (0.0, 29.0)
    )  # both from rest
    r = tilt_push_response([series])
    assert r.slope == pytest.approx(missed, abs=0.02)
    assert r.correlation > 0.5  # the east axis carries no push and no error


def test_an_error_that_ignores_the_tilt_has_no_response():
    t, est, truth, q_est, q_true = _tilted(0.0)
    rng = np.random.default_rng(1)
    est = est + np.column_stack([rng.normal(0, 0.2, len(t)), rng.normal(0, 0.2, len(t))])
    r = tilt_push_response([tilt_push_series(_series(t, est, truth, q_est, q_true), (2.0, 29.0))])
    assert abs(r.slope) < 0.1 and abs(r.correlation) < 0.1


def test_a_flight_never_slow_has_no_tilt_push_to_measure():
    t, est, truth, q_est, q_true = _tilted(1.0, speed=5.0)
    with pytest.raises(BadInput, match="slower than 1 m/s"):
        tilt_push_series(_series(t, est, truth, q_est, q_true), (2.0, 29.0))
    with pytest.raises(BadInput, match="no flight"):
        tilt_push_response([])


def _turned(k: float, seconds: float = 40.0):
    """Steady flight east at 5 m/s with a slowly swinging heading error (estimate minus truth,
    up to 6 degrees) and a sideways velocity error of ``k`` x the heading error x the speed, plus
    independent noise."""
    t = np.arange(0.0, seconds, 1.0 / RATE)
    eh = math.radians(6.0) * np.sin(2 * math.pi * t / 13.0)
    yaw_true = np.full_like(t, math.pi / 2)
    q_true = np.column_stack([np.cos(yaw_true / 2), np.zeros((len(t), 2)), np.sin(yaw_true / 2)])
    yaw_est = yaw_true + eh
    q_est = np.column_stack([np.cos(yaw_est / 2), np.zeros((len(t), 2)), np.sin(yaw_est / 2)])
    truth = np.column_stack([np.zeros_like(t), np.full_like(t, 5.0)])
    # flying east, sideways (90 degrees clockwise from above) is south: -x
    side = k * eh * 5.0 + np.random.default_rng(2).normal(0.0, 0.05, len(t))
    est = truth + np.column_stack([-side, np.zeros_like(t)])
    return t, est, truth, q_est, q_true


@pytest.mark.parametrize("k", [-0.3, 0.2])
def test_a_velocity_error_that_follows_the_heading_error_is_measured(k: float):
    t, est, truth, q_est, q_true = _turned(k)
    r = heading_turn_response([heading_turn_series(_series(t, est, truth, q_est, q_true), (1.0, 39.0))])
    assert r.slope == pytest.approx(k, abs=0.03)
    assert math.copysign(1.0, r.correlation) == math.copysign(1.0, k) and abs(r.correlation) > 0.8


def test_independent_heading_and_velocity_errors_have_no_turn():
    t, est, truth, q_est, q_true = _turned(0.0)
    r = heading_turn_response([heading_turn_series(_series(t, est, truth, q_est, q_true), (1.0, 39.0))])
    assert abs(r.slope) < 0.03 and abs(r.correlation) < 0.15


def test_a_hover_has_no_heading_turn_to_measure():
    t, est, truth, q_est, q_true = _turned(-0.3)
    truth = truth * 0.2  # 1 m/s: below TURN_SPEED
    with pytest.raises(BadInput, match="steadily faster than 2 m/s"):
        heading_turn_series(_series(t, est, truth, q_est, q_true), (1.0, 39.0))
    with pytest.raises(BadInput, match="no flight"):
        heading_turn_response([])


def _legs(response, heading_deg: tuple[float, float]):
    """A log of 50 s: a 60 m leg north set at 0 s, a 60 m leg east at 20 s, a 15 m leg at 40 s and
    a 60 m leg south at 45 s (the log ends 5 s into it). On the first two the heading error is
    ``heading_deg`` (constant), and the velocity error across the leg ``response``(seconds since
    the leg's start) times the heading error's sign."""
    t = np.arange(0.0, 50.0, 1.0 / RATE)
    changes = np.array(
        [[-5.0, 0, 0, 0.5], [0.0, 60, 0, 0.5], [20.0, 60, 60, 0.5], [40.0, 60, 75, 0.5], [45.0, 0, 75, 0.5]]
    )
    first = t < 20.0
    eh = np.radians(np.where(first, heading_deg[0], heading_deg[1]))
    since = np.where(first, t, t - 20.0)
    side = np.array([response(s) for s in since]) * np.sign(eh)
    across = np.where(first[:, None], [[0.0, 1.0]], [[-1.0, 0.0]])  # 90 degrees clockwise of the leg
    truth = np.column_stack([np.where(first, 3.0, 0.0), np.where(first, 0.0, 3.0)])
    est = truth + side[:, None] * across
    q_true = np.column_stack([np.ones_like(t), np.zeros((len(t), 3))])
    q_est = np.column_stack([np.cos(eh / 2), np.zeros((len(t), 2)), np.sin(eh / 2)])
    return _series(t, est, truth, q_est, q_true), changes


def test_the_error_across_a_new_leg_is_signed_by_the_heading_error():
    # PX4's shape: the miss of the acceleration, then the bias that pulls the estimate back
    flight, changes = _legs(lambda s: 0.12 if s < 2.0 else -0.2, (4.0, -4.0))
    legs = leg_start_response(flight, changes)
    assert len(legs) == 2  # the 15 m leg and the leg the log ends within are left out
    for leg in legs:
        assert leg == pytest.approx([0.12, -0.2, -0.2, -0.2], abs=1e-6)
    assert leg_start_means(legs) == pytest.approx([0.12, -0.2, -0.2, -0.2], abs=1e-6)


def test_an_error_that_ignores_the_heading_error_averages_out():
    # the same error across both legs whatever the heading error's sign: no signed response
    flight, changes = _legs(lambda s: 0.1, (4.0, 4.0))
    t = flight.t
    eh = np.radians(np.where(t < 20.0, 4.0, -4.0))
    flight = flight._replace(q=np.column_stack([np.cos(eh / 2), np.zeros((len(t), 2)), np.sin(eh / 2)]))
    assert leg_start_means(leg_start_response(flight, changes)) == pytest.approx([0.0] * 4, abs=1e-6)
    assert np.isnan(leg_start_means([])).all()
