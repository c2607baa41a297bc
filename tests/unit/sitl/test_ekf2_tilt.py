"""EKF2's tilt error (``ekf2.TILT_*``): PX4 v1.15 SIH's estimated roll and pitch are off the ground
truth, 0.66 degrees before arming and 1.58 before the lift-off's release (median, 96 PX4 flights
flown here, stop 45; ``analysis.liftoff``), and the attitude controller levels the estimate, so the
true body leans the other way."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from uavtest.sitl import ekf2
from uavtest.sitl.ekf2 import TILT_SIGMA_AIR, Estimator
from uavtest.sitl.simulator_sih import GRAVITY, Body


def _magnitudes(armed: bool, airborne: bool, seconds: float) -> np.ndarray:
    out = []
    for seed in range(200):
        e = Estimator(random.Random(seed), rng_tilt=random.Random(f"{seed}:tilt"))
        for _ in range(int(seconds * 50)):
            e.update_tilt(0.02, armed, airborne)
        out.append(math.degrees(math.hypot(e.tx, e.ty)))
    return np.array(out)


def test_the_error_grows_while_the_vehicle_stands_armed_as_px4s_does() -> None:
    disarmed = np.median(_magnitudes(False, False, 10.0))
    armed = np.median(_magnitudes(True, False, 4.5))  # arming to lift-off, as in PX4's flights
    assert 0.4 < disarmed < 0.9  # PX4 0.66
    # PX4 1.58 (p10 0.59, p90 2.86) before the release; the built-in was 2.1 before stop 45
    assert 1.3 < armed < 1.9
    air = np.median(_magnitudes(True, True, 30.0))
    assert 0.7 < air < 1.7  # PX4 1.2-1.6 in flight


def test_the_local_planners_system_has_none() -> None:
    """The Gazebo system's flights were calibrated without it: no error, no push."""
    e = Estimator(random.Random(1), rng_tilt=random.Random(2))
    e.gazebo_system()
    for _ in range(500):
        e.update_tilt(0.02, True, True)
        e.update(0.02)
    assert e.tx == e.ty == 0.0 and e._tvx == e._tvy == 0.0


def test_the_ground_holds_the_body_level_and_the_air_leans_it_against_the_estimate() -> None:
    body = Body(windup=True)
    body.motors = True
    body.lean_x = math.radians(2.0)  # EKF2 believes the body tilted 2 degrees towards North
    body.step(0.004, 0.0, 0.0, GRAVITY, 0.0, 0.0, 0.0, 0.0)
    assert body.on_ground and body.tilt() == (0.0, 0.0)  # the truth: level, whatever EKF2 says
    while body.on_ground:
        body.step(0.004, 0.0, 0.0, GRAVITY - 12.0, 0.0, 0.0, 0.0, 0.0)
    for _ in range(500):  # 2 s in the air, the kick spent
        body.step(0.004, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    # the controller asks for no tilt, so the true body pitches its nose up by the error (South)
    assert math.degrees(body.tilt()[1]) > 1.5
    # and drifts South, against the estimate's error, towards g x 2 degrees / SIH's drag (0.34 m/s)
    assert -0.4 < body.vx < -0.2


def test_the_air_process_keeps_pxs_spread() -> None:
    xs = []
    e = Estimator(random.Random(3), rng_tilt=random.Random(4))
    for _ in range(50 * 600):
        e.update_tilt(0.02, True, True)
        xs.append(e.tx)
    assert 0.8 * TILT_SIGMA_AIR < float(np.std(xs)) < 1.2 * TILT_SIGMA_AIR


def _hover_position_error(monkeypatch: pytest.MonkeyPatch, share: float) -> float:
    """The horizontal position error's mean magnitude (m) of estimators hovering for a minute."""
    monkeypatch.setattr(ekf2, "TILT_POSITION_SHARE", share)
    mags = []
    for seed in range(40):
        e = Estimator(random.Random(seed), rng_tilt=random.Random(f"{seed}:tilt"))
        for i in range(50 * 60):
            e.update_tilt(0.02, True, True)
            e.update(0.02)
            if i >= 500:
                mags.append(math.hypot(e.ex, e.ey))
    return float(np.mean(mags))


def test_the_position_follows_part_of_the_push_as_px4s_does(monkeypatch: pytest.MonkeyPatch) -> None:
    """PX4 v1.15 SIH's position error at rest in the air: 0.30-0.34 m (mean magnitude, 24 flights of
    the competition missions against their ground truth); the push in the velocity alone left the
    built-in's at 0.18."""
    share = ekf2.TILT_POSITION_SHARE
    assert 0.22 < _hover_position_error(monkeypatch, share) < 0.4
    assert _hover_position_error(monkeypatch, 0.0) < 0.2


def test_part_of_the_takeoffs_slide_stays_in_the_position(monkeypatch: pytest.MonkeyPatch) -> None:
    """The push of the tilt error carried off the ground is kept out of the position in part: PX4's
    estimate sees part of the takeoff's slide (its takeoffs turn back to the track's start)."""

    def drift(kept_out: float) -> float:
        monkeypatch.setattr(ekf2, "TILT_LIFTOFF_KEPT_OUT", kept_out)
        out = []
        for seed in range(40):
            e = Estimator(random.Random(seed), rng_tilt=random.Random(f"{seed}:tilt"))
            for _ in range(int(4.5 * 50)):  # armed on the ground: the error grows
                e.update_tilt(0.02, True, False)
                e.update(0.02)
            ex0, ey0 = e.ex, e.ey
            for _ in range(3 * 50):  # the first 3 s in the air
                e.update_tilt(0.02, True, True)
                e.update(0.02)
            out.append(math.hypot(e.ex - ex0, e.ey - ey0))
        return float(np.median(out))

    share = ekf2.TILT_LIFTOFF_KEPT_OUT
    assert 0.0 < share < 1.0
    assert drift(1.0) < drift(share) < drift(0.0)
