"""Averaging flights of different lengths on normalized progress."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from uavtest.analysis.average import AVERAGE_CSV_COLUMNS, AverageTrajectory, average_trajectories
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import read_ulog, trajectory_from_ulog
from uavtest.errors import BadInput


def path_at_pace(duration: float, offset: float = 0.0, rate: float = 20.0) -> Trajectory:
    """The same path (North 0→40 m, East offset, 10 m up) flown in ``duration`` seconds."""
    t = 100.0 + np.arange(0.0, duration + 1e-9, 1.0 / rate)
    s = (t - t[0]) / duration
    return Trajectory(t, 40.0 * s, np.full_like(s, offset), -10.0 * np.ones_like(s))


def test_flights_at_different_paces_average_to_the_path() -> None:
    avg = average_trajectories([path_at_pace(30), path_at_pace(45), path_at_pace(60)], points=101)
    np.testing.assert_allclose(avg.mean[:, 0], 40.0 * avg.progress, atol=1e-6)
    np.testing.assert_allclose(avg.std, 0.0, atol=1e-6)
    assert avg.t[-1] == pytest.approx(45.0)  # mean flight time
    assert avg.count == 3


def test_spread_band_is_std_and_min_max_across_flights() -> None:
    avg = average_trajectories([path_at_pace(30, -2.0), path_at_pace(40, 0.0), path_at_pace(50, 2.0)])
    np.testing.assert_allclose(avg.mean[:, 1], 0.0, atol=1e-9)
    np.testing.assert_allclose(avg.std[:, 1], np.std([-2.0, 0.0, 2.0]))
    np.testing.assert_allclose(avg.min[:, 1], -2.0)
    np.testing.assert_allclose(avg.max[:, 1], 2.0)


def test_empty_flights_are_left_out_and_none_left_is_bad_input() -> None:
    empty = Trajectory([], [], [], [])
    assert average_trajectories([empty, path_at_pace(10)]).count == 1
    with pytest.raises(BadInput, match="no flight to average"):
        average_trajectories([empty])


def test_csv_has_the_documented_columns_and_round_trips() -> None:
    avg = average_trajectories([path_at_pace(30, -1.0), path_at_pace(40, 1.0)], points=11)
    text = avg.to_csv()
    assert text.splitlines()[0].split(",") == list(AVERAGE_CSV_COLUMNS)
    assert len(text.splitlines()) == 12
    back = AverageTrajectory.from_csv(text)
    np.testing.assert_allclose(back.mean, avg.mean, atol=1e-4)
    np.testing.assert_allclose(back.max, avg.max, atol=1e-4)


def test_px4_runs_average_lands_at_the_mean_landing_point(shared_data: Path) -> None:
    runs = [
        trajectory_from_ulog(read_ulog(shared_data / "px4-sih" / f"competition-mission2-run{i}.ulg"))
        for i in (1, 2, 3)
    ]
    avg = average_trajectories(runs)
    landing = np.mean([[r.x[-1], r.y[-1], r.z[-1]] for r in runs], axis=0)
    np.testing.assert_allclose(avg.mean[-1], landing, atol=1e-6)
    assert avg.t[-1] == pytest.approx(np.mean([72.2, 60.5, 71.7]), abs=0.2)
