"""``uavtest run`` of several tests: real built-in simulator flights, one exit code, one JUnit file."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import junitparser
import pytest

from harness.ci_examples import load, option, uavtest_commands

pytestmark = pytest.mark.integration


def _suite(folder: Path, repo_root: Path) -> Path:
    """A folder with a passing test (hover) and one that always fails (hover, at most 5 s aloft)."""
    folder.mkdir()
    hover = (repo_root / "examples/hover.yaml").read_text()
    (folder / "a-hover.yaml").write_text(hover)
    slow = hover.replace("name: hover", "name: hover-too-slow").replace(
        "maxFlightTime: 60", "maxFlightTime: 5"
    )
    assert slow != hover
    (folder / "b-too-slow.yaml").write_text(slow)
    (folder / "notes.txt").write_text("not a test")
    return folder


def _run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "uavtest.cli", "run", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=900, check=False, cwd=cwd)


def test_a_folder_with_a_passing_and_a_failing_test_exits_1_and_reports_both(
    repo_root: Path, tmp_path: Path
) -> None:
    folder = _suite(tmp_path / "tests", repo_root)
    report = tmp_path / "reports" / "uavtest.xml"
    out = _run(
        str(folder), "--replicas", "2", "--out", str(tmp_path / "runs"), "--junit", str(report), "--json"
    )
    assert out.returncode == 1, out.stderr[-3000:]
    summaries = json.loads(out.stdout)
    assert [(s["test"], s["verdict"], s["passed"], s["failed"]) for s in summaries] == [
        ("hover", "pass", 2, 0),
        ("hover-too-slow", "fail", 0, 2),
    ]
    doc = junitparser.JUnitXml.fromfile(str(report))
    assert (doc.tests, doc.failures, doc.errors) == (4, 2, 0)
    hover, slow = list(doc)
    assert (hover.name, hover.tests, hover.failures) == ("hover", 2, 0)
    assert (slow.name, slow.tests, slow.failures) == ("hover-too-slow", 2, 2)
    case = next(iter(slow))
    assert "flight time" in case.result[0].message and "> 5.0 s" in case.result[0].message
    flight_log = next(ln for ln in (case.system_out or "").splitlines() if ln.startswith("flight.ulg: "))
    assert Path(flight_log.removeprefix("flight.ulg: ")).is_file()  # the link leads to the real log
    props = {p.name: p.value for p in slow.properties()}
    assert props["uavtest.run-id"] == summaries[1]["run_id"] and props["uavtest.flakiness"] == "1"
    for s in summaries:  # each run's aggregate holds the same suite
        stored = tmp_path / "runs" / "local" / s["test"] / s["run_id"] / "aggregate" / "junit.xml"
        (suite,) = list(junitparser.JUnitXml.fromfile(str(stored)))
        assert (suite.name, suite.tests) == (s["test"], 2)


def test_the_table_over_the_tests_and_the_exit_line(repo_root: Path, tmp_path: Path) -> None:
    folder = _suite(tmp_path / "tests", repo_root)
    out = _run(
        str(folder / "b-too-slow.yaml"),
        str(folder / "a-hover.yaml"),
        "--replicas",
        "1",
        "--out",
        str(tmp_path),
    )
    assert out.returncode == 1, out.stderr[-3000:]
    assert "2 tests" in out.stdout and "exit 1: a test failed" in out.stdout
    assert out.stderr.index("test 1/2") < out.stderr.index("test 2/2")


def test_a_wrong_file_among_good_ones_exits_2_and_nothing_flies(repo_root: Path, tmp_path: Path) -> None:
    folder = _suite(tmp_path / "tests", repo_root)
    (folder / "c-broken.yaml").write_text(
        "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: x}\nspec: {replicas: -1}\n"
    )
    report = tmp_path / "report.xml"
    out = _run(str(folder), "--out", str(tmp_path / "runs"), "--junit", str(report))
    assert out.returncode == 2, out.stderr[-3000:]
    assert "c-broken.yaml" in out.stderr and "1 of 3 test files are wrong" in " ".join(out.stderr.split())
    assert not (tmp_path / "runs").exists() and not report.exists()


def test_the_ci_examples_local_command_runs_as_written(repo_root: Path, tmp_path: Path) -> None:
    github = uavtest_commands(load(repo_root / "examples/ci/github-actions.yml"))[0]
    gitlab = uavtest_commands(load(repo_root / "examples/ci/gitlab-ci.yml"))[0]
    assert github == gitlab  # both CI examples fly the same suite
    args = github[2:]
    args[args.index("--out") + 1] = str(tmp_path / "runs")
    args[args.index("--junit") + 1] = str(tmp_path / option(github, "--junit"))
    out = _run(*args, cwd=repo_root)
    assert out.returncode == 0, out.stderr[-3000:]  # the example suite passes: a green build
    doc = junitparser.JUnitXml.fromfile(str(tmp_path / "reports" / "uavtest.xml"))
    assert [s.name for s in doc] == ["hover", "obstacle-pass"]
    assert (doc.tests, doc.failures, doc.errors) == (6, 0, 0)


def test_one_replica_tests_fly_side_by_side_and_report_in_their_order(
    repo_root: Path, tmp_path: Path
) -> None:
    """A generator's output: many tests, one replica each. With --jobs 2 two fly at once (the
    second starts before the first is done); results, table and JSON keep the files' order."""
    folder = tmp_path / "tests"
    folder.mkdir()
    hover = (repo_root / "examples/hover.yaml").read_text()
    for k in range(3):
        (folder / f"t{k}.yaml").write_text(hover.replace("name: hover", f"name: hover-{k}"))
    out = _run(str(folder), "--replicas", "1", "--jobs", "2", "--out", str(tmp_path / "runs"), "--json")
    assert out.returncode == 0, out.stderr[-3000:]
    assert "3 tests, 2 at a time" in out.stderr
    assert out.stderr.index("test 1/3:") < out.stderr.index("test 2/3:") < out.stderr.index("test 3/3:")
    assert out.stderr.index("test 2/3:") < out.stderr.index("test 1/3 done")  # side by side
    summaries = json.loads(out.stdout)
    assert [(s["test"], s["passed"]) for s in summaries] == [("hover-0", 1), ("hover-1", 1), ("hover-2", 1)]
    for s in summaries:  # every replica flew and stored its log, on its own ports
        replica = tmp_path / "runs" / "local" / s["test"] / s["run_id"] / "replica-0"
        assert (replica / "flight.ulg").stat().st_size > 0
