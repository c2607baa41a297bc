"""EKF2's altitude shift after touchdown: the range finder reads below its minimum on the ground,
the height follows the barometer/GNSS reference until the land detector says landed.

Calibrated on 16 PX4 v1.15 SIH flights flown here with their ground truth (``ekf2.py``)."""

import random

import pytest

from uavtest.sitl.ekf2 import GROUND_SHIFT_TIME, TERRAIN_TIMEOUT_S, Estimator

DT = 0.02


def _run(e: Estimator, seconds: float, height: float | None, landed: bool = False) -> list[float]:
    """Advance ``seconds``: at ``height`` (range fused) or on the ground (None: not fused)."""
    rates = []
    for _ in range(round(seconds / DT)):
        if height is None:
            e.range_lost()
        else:
            e.range_fused(height, landed)
        e.update(DT)
        rates.append(e.vz_shift)
    return rates


def _flown(shift: float) -> Estimator:
    e = Estimator(random.Random(1), random.Random(2), random.Random(3), random.Random(4))
    e.ground_shift = shift
    _run(e, 2.0, 0.0, landed=True)  # before the flight: the on-ground reading is fused
    _run(e, 1.0, None)  # the takeoff ramp: on the ground, no longer landed
    _run(e, 10.0, 5.0)  # flying at 5 m
    return e


def test_no_shift_before_a_flight():
    e = _flown(-1.3)
    assert e.z_shift == 0.0 and e.vz_shift == 0.0


def test_the_estimate_climbs_by_the_shift_after_touchdown_and_stays_there():
    e = _flown(-1.3)
    ez_before = e.ez
    rates = _run(e, GROUND_SHIFT_TIME + 1.0, None)
    assert e.z_shift == pytest.approx(-1.3, abs=1e-3)
    # a half sine: PX4 SIH's estimate climbed at up to 0.3-0.5 m/s while the vehicle sat still
    assert min(rates) == pytest.approx(-1.3 * 3.14159 / (2 * GROUND_SHIFT_TIME), abs=0.01)
    assert rates[-1] == 0.0
    assert e.ez - ez_before == pytest.approx(-1.3, abs=0.3)  # plus the small leaky error
    assert e.z_deriv_error == pytest.approx(e._cvz)  # the shift is over


def test_the_terrain_estimate_freezes_and_times_out_5_s_after_the_last_fusion():
    e = _flown(-1.3)
    assert e.terrain_valid and e.hagl(5.0) == 5.0
    _run(e, 3.0, None)
    assert e.terrain_valid
    assert e.hagl(0.1) > 0.1 + 0.7  # the estimate climbed, the terrain did not
    _run(e, TERRAIN_TIMEOUT_S - 3.0 + DT, None)
    assert not e.terrain_valid
    _run(e, DT, 0.0, landed=True)  # landed: EKF2 fuses its on-ground reading again
    assert e.terrain_valid


def test_a_bounce_does_not_restart_the_shift_and_landing_stops_it():
    e = _flown(-1.0)
    _run(e, 1.0, None)
    _run(e, 0.1, 0.05)  # bounced off the ground for a moment
    _run(e, GROUND_SHIFT_TIME, None)
    assert e.z_shift == pytest.approx(-1.0, abs=0.05)
    e2 = _flown(-1.0)
    _run(e2, 1.0, None)
    shifted = e2.z_shift
    _run(e2, 3.0, 0.0, landed=True)  # landed after 1 s: the shift stops where it is
    assert e2.z_shift == shifted and e2.vz_shift == 0.0


def test_each_flight_lands_with_its_own_shift():
    shifts = [Estimator(random.Random(0), rng_ground=random.Random(s)).ground_shift for s in range(400)]
    mean = sum(shifts) / len(shifts)
    sd = (sum((s - mean) ** 2 for s in shifts) / len(shifts)) ** 0.5
    assert mean == pytest.approx(-0.28, abs=0.1) and sd == pytest.approx(0.69, abs=0.08)
