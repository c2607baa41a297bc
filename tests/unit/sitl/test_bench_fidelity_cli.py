"""``bench/bench_fidelity.py --px4-logs``: a PX4 user's own SIH flights of a plan join the shared ones."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
from rich.console import Console

from uavtest.analysis.fidelity import flight_figures, pairs_between, share_noise
from uavtest.analysis.ulog import read_ulog, trajectory_from_ulog
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.recorder import MemorySink

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


def test_your_px4_flights_are_held_to_the_shared_logs_range_beside_the_built_in(
    shared_data: Path, tmp_path: Path
):
    own = tmp_path / "replica-0"
    own.mkdir()
    (own / "flight.ulg").symlink_to(shared_data / "px4-sih" / "competition-mission1-run2.ulg")
    args = ("--seeds", "2", "--plans", "mission1", "--px4-logs", f"mission1={tmp_path}")
    run = _bench(*args, data=shared_data)
    assert "against the 4 shared PX4 logs alone, your 1 PX4 flights" in run.stdout, run.stdout + run.stderr
    runs = ("run1", "run2", "run3", "sf1")
    logs = [shared_data / "px4-sih" / f"competition-mission1-{r}.ulg" for r in runs]
    shared = [flight_figures(trajectory_from_ulog(read_ulog(log))) for log in logs]
    # run2 against the four shared logs, itself among them (a DTW of 0)
    expected = np.mean([p.dtw for p in pairs_between([shared[1]], shared)])
    rows = [line for line in run.stdout.splitlines() if "DTW" in line and "side)" in line]
    assert len(rows) == 1, run.stdout
    assert rows[0].split("│")[3].strip().startswith(f"{expected:.2f} ("), rows[0]


def test_a_px4_logs_argument_names_the_plan_and_a_folder_with_logs(shared_data: Path, tmp_path: Path):
    run = _bench("--px4-logs", f"mission9={tmp_path}", data=shared_data)
    assert run.returncode != 0
    assert "expected PLAN=DIR with PLAN one of mission1, mission2, square" in run.stderr
    run = _bench("--px4-logs", f"mission2={tmp_path}", data=shared_data)
    assert run.returncode != 0
    assert f"no *.ulg under {tmp_path}" in run.stderr


def _rows(stdout: str, figure: str) -> list[str]:
    return [line.split("│")[2:5] for line in stdout.splitlines() if line.startswith(f"│ {figure}")]


def test_your_own_test_file_is_flown_and_held_to_your_px4_flights_of_it(shared_data: Path, tmp_path: Path):
    cases = shared_data / "competition" / "snippets" / "case_studies"
    test = tmp_path / "my-mission.yaml"
    test.write_text(
        "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: my-mission}\nspec:\n"
        "  vehicle: {avoidance: none, paramsFile: " + str(cases / "mission-params.csv") + "}\n"
        "  world: {home: {lat: 47.397742, lon: 8.545594, alt: 488}}\n"
        "  mission: {planFile: " + str(cases / "mission1.plan") + "}\n"
        "  commands: [{at: 1, action: mode, mode: mission}]\n"
    )
    runs = tmp_path / "px4-runs"
    for r in ("run1", "run2", "run3", "sf1"):
        replica = runs / f"replica-{r}"
        replica.mkdir(parents=True)
        (replica / "flight.ulg").symlink_to(shared_data / "px4-sih" / f"competition-mission1-{r}.ulg")
    own = _bench("--seeds", "2", "--test", f"{test}={runs}", data=shared_data)
    assert "my-mission.yaml: 4 PX4 logs" in own.stdout, own.stdout + own.stderr
    assert "my-mission: built-in (2 seeds) vs PX4 v1.15 SIH (4 runs)" in own.stdout
    # the same plan, params and home as the bench's own mission1: the same flights, the same figures
    builtin = _bench("--seeds", "2", "--plans", "mission1", data=shared_data)
    for figure in ("DTW", "flight time", "altitude error"):
        assert _rows(own.stdout, figure) == _rows(builtin.stdout, figure) != [], figure


def test_a_test_argument_names_a_test_file_and_a_folder_with_logs(shared_data: Path, tmp_path: Path):
    run = _bench("--test", f"{tmp_path / 'nothere.yaml'}={tmp_path}", data=shared_data)
    assert run.returncode != 0
    assert "no test file" in run.stderr
    test = tmp_path / "t.yaml"
    test.write_text("x: 1\n")
    run = _bench("--test", str(test), data=shared_data)
    assert run.returncode != 0
    assert "expected FILE.yaml=DIR" in run.stderr
    run = _bench("--test", f"{test}={tmp_path / 'empty'}", data=shared_data)
    assert run.returncode != 0
    assert "no *.ulg under" in run.stderr


def test_a_flight_that_stops_making_progress_ends_as_uavtest_run_ends_it_and_is_counted_not_measured(
    shared_data: Path, tmp_path: Path, bench_fidelity
):
    """With a 0.1 m acceptance radius most takeoffs turn back (PX4 v1.15 SIH: 11 of 14) and some
    never recover: the runner calls them blocked after a minute without progress, so the bench's
    built-in flights end there too (not at its 600 s limit), and only finished flights are measured."""
    experiments = shared_data / "surrealist" / "experiments"
    test = tmp_path / "auto1.yaml"
    test.write_text(
        "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: auto1}\nspec:\n"
        f"  vehicle: {{avoidance: none, paramsFile: {experiments / 'auto1-params.csv'},\n"
        "    params: {NAV_RCL_ACT: 3}}\n"  # the file's 0 is PX4 v1.12's: v1.15 allows 1-6
        "  world: {home: {lat: 47.397742, lon: 8.545594, alt: 488}}\n"
        f"  mission: {{planFile: {experiments / 'auto1.plan'}}}\n"
        "  commands: [{at: 1, action: mode, mode: mission}]\n"
    )
    plan = bench_fidelity.from_test(test)
    config, items = plan(0)  # its takeoff turns back and never gets within 0.1 m again
    sink = MemorySink()
    flight = fly_mission(config, items, sink=sink, stop=bench_fidelity._blocked(config, items))
    assert flight.reached == [] and flight.samples[-1][0] < 90.0
    # seed 0 (stalled) and seed 3 (finished in ~120 s), as the bench's first and second flights
    flights, _ = bench_fidelity.builtin_flights(lambda i: plan((0, 3)[i]), 2)
    assert flights.completed == [False, True]
    assert len(flights.figures) == 1  # the stalled one is only counted


def test_a_px4_range_drawn_from_shared_noise_is_said_to_be_one(shared_data: Path, bench_fidelity) -> None:
    """The shared mission2 logs are one noise realization (PX4 SIH's srand(1234): their EKF2
    velocity errors correlate 0.84-1.0 at equal time since start); built-in seeds are not. The
    bench says so beside a figure outside that range, so a user reads the range for what it is."""
    logs = sorted((shared_data / "px4-sih").glob("competition-mission2-*.ulg"))
    px4 = bench_fidelity.Flights([], [])
    for log in logs:
        bench_fidelity._measure(read_ulog(log), px4)
    assert share_noise(px4.boot_x, px4.boot_y)
    ours, _ = bench_fidelity.builtin_flights(bench_fidelity.competition(2), 4)
    assert not share_noise(ours.boot_x, ours.boot_y)
    run = _bench("--seeds", "3", "--plans", "mission2", data=shared_data)
    assert run.returncode == 1, run.stdout + run.stderr  # mission2's path shape: outside (0.60 vs 0.53)
    assert "note: these 4 PX4 flights share their noise" in " ".join(run.stdout.split())


def test_each_built_in_mean_comes_with_its_standard_error_over_the_seeds(shared_data: Path) -> None:
    """A researcher reading "inside PX4's range" must see how sure it is: each built-in-vs-PX4
    mean carries its standard error over the seeds, and a verdict within two of them of PX4's
    bound says so ("within noise")."""
    run = _bench("--seeds", "3", "--plans", "mission1", data=shared_data)
    cells = [row[1].strip() for row in _rows(run.stdout, "DTW per point")]
    assert len(cells) == 1, run.stdout + run.stderr
    assert re.fullmatch(r"\d+\.\d\d ± \d+\.\d\d \(\d+\.\d\d–\d+\.\d\d\)", cells[0]), cells[0]
    caption = " ".join(run.stdout.split())
    assert "mean ± one standard error over the seeds" in caption
    assert "within 2 standard errors of PX4's bound" in caption


def test_the_lift_off_is_read_from_every_flight_with_attitude_ground_truth(bench_fidelity) -> None:
    """The lift-off row (``analysis.liftoff``) is how the built-in's takeoff was held to 96 PX4
    flights at stop 45: every flight logging SIH's attitude ground truth yields its three figures,
    and the table prints them beside PX4's."""
    ours, _ = bench_fidelity.builtin_flights(bench_fidelity.competition(1), 2)
    assert len(ours.liftoffs) == 2
    for f in ours.liftoffs:
        assert 0.0 < f.tilt_error < 6.0, f  # PX4: 0.59-2.86 degrees, p10-p90
        assert f.tilt_peak > 1.0, f  # the kick: PX4 3.8-17.2 degrees
        assert 0.0 <= f.setpoint_offset < 1.5, f
    table, _ = bench_fidelity.table("mission1", ours, ours)
    console = Console(record=True, width=200)
    console.print(table)
    text = " ".join(console.export_text().split())
    assert "lift-off: EKF2's tilt error before the release" in text
    assert "(2 flights)" in text
