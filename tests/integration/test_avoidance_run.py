"""``uavtest run`` with PX4-Avoidance's local planner: real sitl and runner processes."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.engine_cli import uavtest_run

pytestmark = pytest.mark.integration


def test_obstacle_avoidance_example_flies_around_the_box(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/obstacle-avoidance.yaml", tmp_path)
    assert out.code == 0, out.stderr[-3000:]
    assert out.summary is not None and out.summary["passed"] == 3
    for r in out.summary["results"]:
        assert r["metrics"]["collision"] is False and r["metrics"]["mission_completed"] is True
        assert r["metrics"]["min_obstacle_distance"] > 1.0


def test_the_same_box_without_avoidance_is_a_collision(repo_root: Path, tmp_path: Path) -> None:
    text = (repo_root / "examples/obstacle-avoidance.yaml").read_text()
    plain = text.replace("avoidance: local-planner", "avoidance: none")
    assert plain != text
    test = tmp_path / "no-avoidance.yaml"
    test.write_text(plain)
    out = uavtest_run(test, tmp_path / "runs", "--replicas", "1")
    assert out.code == 1, out.stderr[-3000:]
    assert out.summary is not None
    (r,) = out.summary["results"]
    assert r["metrics"]["collision"] is True and "collision" in r["reason"]


def test_a_wall_ends_as_blocked_before_the_timeout(repo_root: Path, tmp_path: Path) -> None:
    out = uavtest_run(repo_root / "examples/avoidance-wall.yaml", tmp_path)
    assert out.code == 1, out.stderr[-3000:]
    assert out.summary is not None and out.summary["failed"] == 2
    for r in out.summary["results"]:
        assert r["reason"].startswith("blocked: no progress toward mission item 2"), r["reason"]
        assert r["metrics"]["collision"] is False
        assert r["sim_time"] < 400 - 60  # ended by the runner, well before the test's timeout


def test_a_competition_file_says_it_flies_with_the_local_planner(shared_data: Path, tmp_path: Path) -> None:
    test = shared_data / "competition/snippets/case_studies/mission1.yaml"
    out = uavtest_run(test, tmp_path, "--replicas", "1")
    assert out.code == 0, out.stderr[-3000:]
    assert "PX4-Avoidance's local planner" in out.stderr
    assert out.summary is not None and out.summary["passed"] == 1
