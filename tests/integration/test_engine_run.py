"""``uavtest run`` end to end: real ``uavtest sitl`` and ``uavtest runner`` processes over UDP."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.engine_cli import uavtest_run
from uavtest.analysis.average import AverageTrajectory

pytestmark = pytest.mark.integration


def run_dir(out: Path, test_name: str) -> Path:
    """The one run folder ``<out>/local/<test>/<run-id>`` a run created."""
    runs = sorted((out / "local" / test_name).iterdir())
    assert len(runs) == 1, runs
    return runs[0]


def test_parallel_replicas_write_the_store_layout(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/obstacle-pass.yaml", tmp_path, "--replicas", "4", "--jobs", "4")
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None
    assert (out.summary["passed"], out.summary["failed"], out.summary["errors"]) == (4, 0, 0)
    assert [r["seed"] for r in out.summary["results"]] == [7, 8, 9, 10]
    run = run_dir(tmp_path, "obstacle-pass")
    assert out.summary["run_id"] == run.name
    for i in range(4):
        replica = run / f"replica-{i}"
        for name in ("flight.ulg", "trajectory.csv", "result.json", "runner.stderr.log", "sim.stderr.log"):
            assert (replica / name).is_file(), replica / name
        assert json.loads((replica / "result.json").read_text())["verdict"] == "pass"
    aggregate = run / "aggregate"
    assert json.loads((aggregate / "summary.json").read_text()) == out.summary
    average = AverageTrajectory.from_csv((aggregate / "average.csv").read_text())
    assert len(average.t) > 100 and abs(average.mean[-1, 0] - 40.0) < 2.0  # ends at the last waypoint
    assert (aggregate / "trajectories.png").read_bytes().startswith(b"\x89PNG")


def test_table_and_summary_are_printed(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/hover.yaml", tmp_path, "--replicas", "1", json_out=False)
    assert out.code == 0, out.stderr[-3000:]
    for heading in ("replica", "seed", "verdict", "3-D", "2-D", "points", "flight", "reason"):
        assert heading in out.stdout
    assert "1 passed · 0 failed · 0 error · flakiness 0.00 · flaky no" in out.stdout
    run = run_dir(tmp_path, "hover")
    assert str(run / "aggregate" / "summary.json") in out.stdout
    assert str(run / "aggregate" / "trajectories.png") in out.stdout


def test_competition_mission_runs_directly_with_a_notice(shared_data: Path, tmp_path: Path) -> None:
    test = shared_data / "competition/snippets/case_studies/mission2.yaml"
    out = uavtest_run(test, tmp_path, "--replicas", "2")
    assert "asks for the 'ros' simulator" in out.stderr
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["passed"] == 2
    # its mission-params.csv sets SDLOG_PROFILE, a PX4 parameter the built-in vehicle ignores
    assert "no effect in the built-in simulator: SDLOG_PROFILE" in " ".join(out.stderr.split())
    assert out.summary["unmodelled_params"] == ["SDLOG_PROFILE"]
    assert all(r["unmodelled_params"] == ["SDLOG_PROFILE"] for r in out.summary["results"])


def test_bad_input_exits_2_before_flying(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/hover.yaml", tmp_path, "--replica", "5", json_out=False)
    assert out.code == 2
    assert "--replica" in out.stderr and "0..2" in out.stderr
    missing = uavtest_run(tmp_path / "absent.yaml", tmp_path, json_out=False)
    assert missing.code == 2 and "absent.yaml" in missing.stderr
    assert not (tmp_path / "local").exists()


def test_replay_of_a_replica_is_exact(repo_root: Path, tmp_path: Path) -> None:
    test = repo_root / "examples/near-miss-wind.yaml"
    full = uavtest_run(test, tmp_path / "full", "--replicas", "4")
    one = uavtest_run(test, tmp_path / "one", "--replica", "3")
    two = uavtest_run(test, tmp_path / "two", "--replica", "3")
    for out in (full, one, two):
        assert out.summary is not None, out.stderr[-3000:]
    assert [r["index"] for r in one.summary["results"]] == [3]  # type: ignore[index]
    assert one.by_index[3]["seed"] == full.by_index[3]["seed"] == 1003

    def trajectory(out_dir: Path) -> str:
        return (run_dir(out_dir, "near-miss-wind") / "replica-3" / "trajectory.csv").read_text()

    first = trajectory(tmp_path / "one")
    assert len(first.splitlines()) > 100
    assert first == trajectory(tmp_path / "two")
    assert first == trajectory(tmp_path / "full")
    assert one.by_index[3]["verdict"] == full.by_index[3]["verdict"]


def test_a_dead_simulator_is_a_bench_error_not_a_failure(
    repo_root: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A vehicle that never answers (here: 'PX4' that exits at once) is exit 3, with retries."""
    test = tmp_path / "px4.yaml"
    text = (repo_root / "examples/hover.yaml").read_text()
    test.write_text(text.replace("  vehicle:\n", "  vehicle:\n    simulator: px4\n"))
    monkeypatch.setenv("UAVTEST_PX4_BIN", "/bin/false")
    out = uavtest_run(test, tmp_path / "runs", "--replicas", "1")
    assert out.code == 3, out.stderr[-3000:]
    assert out.summary is not None
    result = out.summary["results"][0]
    assert result["verdict"] == "error" and result["attempts"] == 3
    assert "simulator exited with code 1" in result["reason"]
