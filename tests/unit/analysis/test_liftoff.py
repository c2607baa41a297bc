"""The lift-off's figures (``analysis.liftoff``): what PX4 v1.15 SIH's takeoffs are measured by, and
the built-in vehicle's against them (bench_fidelity's "lift-off" row)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uavtest.analysis.estimate_phases import VelocityAttitude
from uavtest.analysis.liftoff import RELEASE_RISE, Takeoff, liftoff_figures
from uavtest.errors import BadInput

ARMED_AT = 2.0
RELEASE = 6.0  # s: the truth starts rising


def _tilted(t: np.ndarray, north_deg: np.ndarray) -> np.ndarray:
    """Quaternions (w, x, y, z) pitched so that the body z axis leans ``north_deg`` north."""
    half = np.radians(north_deg) / 2
    return np.column_stack([np.cos(half), np.zeros_like(t), np.sin(half), np.zeros_like(t)])


def _flight(
    lean_deg: float = 2.0,
    kick_deg: float = 9.0,
    estimate_at_risen: tuple[float, float] = (0.3, 0.4),
    rise_rate: float = 0.5,
    setpoint: tuple[float, float] = (0.0, 0.0),
    lean_in_air: bool = True,
) -> tuple[VelocityAttitude, Takeoff]:
    """On the ground from 0 s, armed at 2 s, let go at 6 s and rising ``rise_rate`` m/s; EKF2's
    body leans ``lean_deg`` north of the (level) truth; the truth's tilt peaks at ``kick_deg`` 0.25 s
    after the release; the estimate slides linearly to ``estimate_at_risen`` by the time the truth
    is 0.3 m up; the setpoint is set at arming. ``lean_in_air`` False: EKF2 has the truth's tilt
    once let go."""
    t = np.arange(0.0, 12.0, 0.01)
    rise = np.clip((t - RELEASE) * rise_rate, 0.0, None)
    z_truth = -rise  # NED
    kick = kick_deg * np.exp(-(((t - RELEASE - 0.25) / 0.1) ** 2)) * (t > RELEASE)
    risen_at = RELEASE + 0.3 / rise_rate
    share = np.clip((t - RELEASE) / (risen_at - RELEASE), 0.0, None)
    xy = np.column_stack([estimate_at_risen[0] * share, estimate_at_risen[1] * share])
    sp = np.full((len(t), 2), np.nan)
    sp[t >= ARMED_AT] = setpoint
    # once the truth has risen RELEASE_RISE (what the analysis calls the release)
    lean = np.where(lean_in_air | (t <= RELEASE + RELEASE_RISE / rise_rate), lean_deg, 0.0)
    still = np.zeros((len(t), 2))  # the velocities: not read at lift-off
    flight = VelocityAttitude(t, still, t, still, t, _tilted(t, lean + kick), t, _tilted(t, kick))
    return flight, Takeoff(ARMED_AT, z_truth, xy, t, sp)


def test_the_lift_off_reads_the_tilt_error_the_kick_and_where_the_estimate_rose() -> None:
    f = liftoff_figures(*_flight())
    assert f.tilt_error == pytest.approx(2.0, abs=0.01)
    assert f.tilt_peak == pytest.approx(9.0, abs=0.1)
    assert f.setpoint_offset == pytest.approx(0.5, abs=0.01)


def test_the_tilt_error_is_taken_before_the_release_not_in_the_kick() -> None:
    # EKF2 has the truth's tilt once the body is let go: the error is the one it stood with
    f = liftoff_figures(*_flight(lean_deg=1.0, kick_deg=15.0, lean_in_air=False))
    assert f.tilt_error == pytest.approx(1.0, abs=0.01)
    assert f.tilt_peak == pytest.approx(15.0, abs=0.2)


def test_the_offset_is_from_the_setpoint_in_force_not_the_origin() -> None:
    f = liftoff_figures(*_flight(estimate_at_risen=(0.3, 0.4), setpoint=(0.3, 0.0)))
    assert f.setpoint_offset == pytest.approx(0.4, abs=0.01)


def test_a_level_release_has_no_peak_and_no_error() -> None:
    f = liftoff_figures(*_flight(lean_deg=0.0, kick_deg=0.0, estimate_at_risen=(0.0, 0.0)))
    assert f == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)


def test_a_vehicle_that_never_rose_is_bad_input_not_a_zero() -> None:
    flight, takeoff = _flight()
    grounded = takeoff._replace(z_truth=np.zeros_like(takeoff.z_truth))
    with pytest.raises(BadInput, match="never rose"):
        liftoff_figures(flight, grounded)


def test_a_flight_with_no_setpoint_before_it_rose_is_bad_input() -> None:
    flight, takeoff = _flight()
    with pytest.raises(BadInput, match="no horizontal setpoint"):
        liftoff_figures(flight, takeoff._replace(sp_xy=np.full_like(takeoff.sp_xy, math.nan)))
