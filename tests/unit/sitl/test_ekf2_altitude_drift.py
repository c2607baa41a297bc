"""EKF2's altitude drift (``ekf2.HGT_*``): in flight only, frozen from touchdown.

PX4 v1.15 SIH's estimated altitude strays 0.35-0.40 m from the truth within a flight (GNSS height
reference), but not while landed, where EKF2 fuses its on-ground range, and a drift the flight
left at touchdown stays put until EKF2's own shift after it (``ground_shift``, separate).
"""

from __future__ import annotations

import random

import numpy as np
import pytest

from uavtest.sitl.ekf2 import Estimator

DT = 0.02  # s: the control tick


def _twins() -> tuple[Estimator, Estimator]:
    """The same seed's estimator with and without the altitude drift."""

    def one() -> Estimator:
        return Estimator(*(random.Random(f"7:{name}") for name in ("xy", "z", "heading", "ground", "height")))

    drifting, still = one(), one()
    still.hgt_sigma = 0.0
    return drifting, still


def _run(pair: tuple[Estimator, Estimator], seconds: float, step) -> list[float]:
    """Advance both ``seconds``, calling ``step(estimator)`` first each tick: the drift (m) each tick."""
    out = []
    for _ in range(int(seconds / DT)):
        for e in pair:
            step(e)
            e.update(DT)
        out.append(pair[0].ez - pair[1].ez)
    return out


def test_no_drift_while_landed_and_frozen_from_touchdown() -> None:
    pair = _twins()
    on_ground = _run(pair, 60.0, lambda e: e.range_fused(0.0, landed=True))
    assert max(abs(d) for d in on_ground) == 0.0  # armed or not, landed: EKF2 fuses its range
    flying = _run(pair, 120.0, lambda e: e.range_fused(10.0, landed=False))
    assert 0.2 < float(np.std(flying)) < 0.8  # decimetres within a flight, as PX4 SIH's
    at_touchdown = flying[-1]
    after = _run(pair, 30.0, lambda e: e.range_lost())
    assert after == pytest.approx([at_touchdown] * len(after), abs=1e-9)  # frozen where the flight left it
    landed = _run(pair, 30.0, lambda e: e.range_fused(0.0, landed=True))
    assert landed == pytest.approx([at_touchdown] * len(landed), abs=1e-9)


def test_the_gazebo_system_has_none() -> None:
    """The local planner's system (PX4 in Gazebo) keeps the estimator it was calibrated with."""
    pair = _twins()
    pair[0].gazebo_system()
    pair[1].gazebo_system()
    flying = _run(pair, 60.0, lambda e: e.range_fused(10.0, landed=False))
    assert max(abs(d) for d in flying) == 0.0
