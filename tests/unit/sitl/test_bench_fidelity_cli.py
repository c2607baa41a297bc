"""``bench/bench_fidelity.py --px4-logs``: a PX4 user's own SIH flights of a plan join the shared ones."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[3] / "bench" / "bench_fidelity.py"


def _bench(*args: str, data: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(BENCH), *args],
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, "UAVTEST_SHARED_DATA": str(data), "COLUMNS": "200"},
    )


def test_more_px4_flights_of_a_plan_are_measured_with_the_shared_ones(shared_data: Path, tmp_path: Path):
    own = tmp_path / "my-px4-runs" / "replica-0"
    own.mkdir(parents=True)
    # a flight of the user's own PX4 build (here: one of the shared logs, linked, not copied)
    (own / "flight.ulg").symlink_to(shared_data / "px4-sih" / "competition-mission1-run2.ulg")
    args = ("--seeds", "2", "--plans", "mission1", "--px4-logs", f"mission1={tmp_path}")
    run = _bench(*args, data=shared_data)
    assert "mission1: 4 shared PX4 logs and 1 from --px4-logs" in run.stdout, run.stdout + run.stderr
    assert "vs PX4 v1.15 SIH (5 runs)" in run.stdout
    # the duplicate of run2 makes one PX4 pair identical: PX4's own range now starts at 0.00
    assert "(0.00–" in run.stdout


def test_a_px4_logs_argument_names_the_plan_and_a_folder_with_logs(shared_data: Path, tmp_path: Path):
    run = _bench("--px4-logs", f"mission9={tmp_path}", data=shared_data)
    assert run.returncode != 0
    assert "expected PLAN=DIR with PLAN one of mission1, mission2, square" in run.stderr
    run = _bench("--px4-logs", f"mission2={tmp_path}", data=shared_data)
    assert run.returncode != 0
    assert f"no *.ulg under {tmp_path}" in run.stderr
