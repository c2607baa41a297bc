"""The attitude response fit: a delay and a first-order lag from thrust setpoint to tilt."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uavtest.analysis.attitude_response import (
    _lag,
    body_z_from_quaternion,
    body_z_from_thrust,
    fit,
)
from uavtest.errors import BadInput
from uavtest.sitl.uorb import quaternion


def _smooth_noise(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [np.convolve(rng.normal(size=n), np.ones(50) / 50, mode="same") * 0.3 for _ in range(2)]
    )


@pytest.mark.parametrize(("delay", "tau"), [(0.0, 0.12), (0.07, 0.08), (0.10, 0.06)])
def test_fit_recovers_a_known_delay_and_lag_from_a_10_hz_setpoint(delay: float, tau: float) -> None:
    t = np.arange(0.0, 60.0, 0.01)
    want = _smooth_noise(len(t), seed=1)
    got = _lag(want, tau, 0.01)
    k = round(delay / 0.01)
    if k:
        got = np.vstack([np.repeat(got[:1], k, axis=0), got[:-k]])
    r = fit(t[::10], want[::10], t, got, (1.0, 59.0))  # the setpoint logged at 10 Hz, as PX4 logs it
    assert (r.delay, r.tau) == pytest.approx((delay, tau), abs=0.011)
    assert r.rms < 0.01


def test_a_window_too_short_to_tell_is_bad_input() -> None:
    t = np.arange(0.0, 3.0, 0.01)
    z = np.zeros((len(t), 2))
    with pytest.raises(BadInput, match="too short"):
        fit(t, z, t, z, (0.0, 3.0))


def test_thrust_and_attitude_agree_on_which_way_the_body_leans() -> None:
    """Thrust north-east and up (PX4's NED thrust setpoint: z negative) and a body pitched nose
    down and rolled right, facing north: both lean the body z axis south-west."""
    desired = body_z_from_thrust(np.array([[0.1, 0.1, -0.5], [0.0, 0.0, -0.5]]))
    assert desired[0, 0] < 0 and desired[0, 1] < 0
    assert desired[1] == pytest.approx((0.0, 0.0))
    roll, pitch = math.atan2(0.1, 0.5), -math.atan2(0.1, 0.5)
    actual = body_z_from_quaternion(np.array([quaternion(roll, pitch, 0.0)]))
    assert actual[0] == pytest.approx(desired[0], abs=0.02)
