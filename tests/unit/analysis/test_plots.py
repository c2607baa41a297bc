"""Plots render real flights to PNG."""

from __future__ import annotations

from pathlib import Path

import pytest
from pyulog import ULog

from uavtest.analysis.average import average_trajectories
from uavtest.analysis.plots import plot_flight, plot_run, write_png
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import trajectory_from_ulog
from uavtest.errors import BadInput
from uavtest.spec.models import Obstacle

PNG = b"\x89PNG\r\n\x1a\n"


def test_run_plot_with_average_reference_and_obstacles(square_log: ULog, tmp_path: Path) -> None:
    tr = trajectory_from_ulog(square_log)
    shifted = Trajectory(tr.t, tr.x + 1, tr.y, tr.z)
    box = Obstacle.model_validate({"size": {"l": 4, "w": 2, "h": 8}, "position": {"x": 15, "y": 10, "r": 30}})
    png = plot_run([tr, shifted], average=average_trajectories([tr, shifted]), reference=tr, obstacles=[box])
    assert png[:8] == PNG
    assert write_png(tmp_path / "run.png", png).read_bytes() == png


def test_a_flight_that_never_took_off_still_plots() -> None:
    assert plot_flight(Trajectory([], [], [], []))[:8] == PNG


def test_writing_into_a_missing_folder_is_bad_input(tmp_path: Path) -> None:
    with pytest.raises(BadInput, match="folder does not exist"):
        write_png(tmp_path / "no" / "such" / "dir.png", PNG)
