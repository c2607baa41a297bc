"""Trajectory: the trajectory.csv artifact and its checks."""

from __future__ import annotations

import numpy as np
import pytest

from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import BadInput


def test_csv_round_trip_keeps_the_samples() -> None:
    tr = Trajectory(
        [1.0, 1.5, 2.0], [0.0, 1.25, 2.5], [0.0, -1.0, -2.0], [-1.0, -5.5, -10.0], [0.1, 0.2, -3.1]
    )
    text = tr.to_csv()
    assert text.splitlines()[0] == "t,x,y,z,heading"
    back = Trajectory.from_csv(text)
    for name in ("t", "x", "y", "z", "heading"):
        np.testing.assert_allclose(getattr(back, name), getattr(tr, name), atol=1e-4)
    assert back.altitude.max() == pytest.approx(10.0)


def test_empty_trajectory_round_trips() -> None:
    empty = Trajectory([], [], [], [])
    assert Trajectory.from_csv(empty.to_csv()).empty


def test_wrong_csv_names_the_source_and_header() -> None:
    with pytest.raises(BadInput, match=r"replica-0/trajectory.csv.*header"):
        Trajectory.from_csv("time,a,b\n1,2,3\n", source="replica-0/trajectory.csv")


def test_arrays_must_match_and_time_must_not_go_back() -> None:
    with pytest.raises(BadInput, match="length"):
        Trajectory([0, 1], [0], [0, 1], [0, 1])
    with pytest.raises(BadInput, match="decrease"):
        Trajectory([0, 2, 1], [0, 0, 0], [0, 0, 0], [0, 0, 0])


def test_resample_interpolates_on_a_uniform_grid() -> None:
    tr = Trajectory([0.0, 1.0, 3.0], [0.0, 10.0, 30.0], [0, 0, 0], [0, -2, -2], [3.0, -3.0, -3.0])
    r = tr.resample(2.0)
    np.testing.assert_allclose(r.t, [0, 0.5, 1, 1.5, 2, 2.5, 3])
    np.testing.assert_allclose(r.x, [0, 5, 10, 15, 20, 25, 30])
    # heading crosses ±pi the short way: 3.0 → -3.0 (through pi), never through 0
    assert np.all(np.abs(r.heading) > 2.9)
