"""JUnit XML of runs, read back the way CI systems read it (junitparser, an independent reader)."""

from __future__ import annotations

from pathlib import Path

import junitparser
import pytest

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.junit import error_suite, junit_document, run_suite, seeds_text
from uavtest.analysis.models import AssertionResult, ReplicaResult, RunSummary, Verdict


def _result(i: int, verdict: Verdict, reason: str = "", **kw: object) -> ReplicaResult:
    return ReplicaResult(index=i, seed=40 + i, verdict=verdict, reason=reason, wall_time=1.5, **kw)  # type: ignore[arg-type]


SHORT = "min distance 1.10 m < 1.5 m (short by 0.40 m)"


def _summary() -> RunSummary:
    results = [
        _result(0, Verdict.PASS),
        _result(
            1,
            Verdict.FAIL,
            "min distance 1.10 m < 1.5 m (short by 0.40 m)",
            assertions=[
                AssertionResult(name="noCollision", passed=True),
                AssertionResult(
                    name="minObstacleDistance",
                    passed=False,
                    message="min distance 1.10 m < 1.5 m (short by 0.40 m)",
                ),
                AssertionResult(name="maxFlightTime", passed=False, message="flight time 70.0 s > 60.0 s"),
            ],
        ),
        _result(2, Verdict.ERROR, "simulator exited with code 1", attempts=3),
        _result(3, Verdict.PASS),
    ]
    return summarize(results, test="near-miss", namespace="team-a", run_id="20260101-000000-abcd")


def _read(xml: bytes, tmp_path: Path) -> junitparser.JUnitXml:
    path = tmp_path / "report.xml"
    path.write_bytes(xml)
    doc = junitparser.JUnitXml.fromfile(str(path))
    assert isinstance(doc, junitparser.JUnitXml)
    return doc


def test_a_ci_reads_one_case_per_replica_with_its_verdict(tmp_path: Path) -> None:
    links = {1: {"flight.ulg": "s3://uavtest/team-a/near-miss/r/replica-1/flight.ulg"}}
    doc = _read(junit_document([run_suite(_summary(), links)]), tmp_path)
    (suite,) = list(doc)
    assert (doc.tests, doc.failures, doc.errors) == (4, 1, 1)
    assert (suite.name, suite.tests, suite.failures, suite.errors, suite.skipped) == ("near-miss", 4, 1, 1, 0)
    cases = {c.name: c for c in suite}
    assert sorted(cases) == ["replica-0", "replica-1", "replica-2", "replica-3"]
    assert all(c.classname == "near-miss" for c in cases.values())
    assert cases["replica-0"].is_passed and cases["replica-3"].is_passed
    (failure,) = cases["replica-1"].result
    assert isinstance(failure, junitparser.Failure)
    assert failure.message == "min distance 1.10 m < 1.5 m (short by 0.40 m)"
    assert failure.type == "minObstacleDistance"
    assert "- flight time 70.0 s > 60.0 s" in (failure.text or "")
    (error,) = cases["replica-2"].result
    assert isinstance(error, junitparser.Error) and error.message == "simulator exited with code 1"
    out = cases["replica-1"].system_out or ""
    assert "seed: 41" in out and "flight.ulg: s3://uavtest/team-a/near-miss/r/replica-1/flight.ulg" in out
    assert "attempts: 3" in (cases["replica-2"].system_out or "")
    assert cases["replica-0"].time == pytest.approx(1.5)


def test_the_suite_carries_flakiness_seeds_and_run_id(tmp_path: Path) -> None:
    (suite,) = list(_read(junit_document([run_suite(_summary())]), tmp_path))
    props = {p.name: p.value for p in suite.properties()}
    assert props["uavtest.run-id"] == "20260101-000000-abcd"
    assert props["uavtest.flakiness"] == "0.3333"  # 1 failed of 3 valid
    assert props["uavtest.flaky"] == "true"
    assert props["uavtest.seeds"] == "40..43"
    assert props["uavtest.verdict"] == "fail"
    assert props["uavtest.namespace"] == "team-a"
    assert "uavtest.results-omitted" not in props


def test_several_runs_are_one_document_with_totals(tmp_path: Path) -> None:
    passing = summarize([_result(0, Verdict.PASS)], test="hover", namespace="local", run_id="r1")
    broken = error_suite("obstacle", "gave up waiting after 5 s", source="tests/obstacle.yaml")
    doc = _read(junit_document([run_suite(passing), run_suite(_summary()), broken]), tmp_path)
    assert [s.name for s in doc] == ["hover", "near-miss", "obstacle"]
    assert (doc.tests, doc.failures, doc.errors) == (6, 1, 2)
    (case,) = list(list(doc)[2])
    assert case.name == "run" and isinstance(case.result[0], junitparser.Error)
    assert case.result[0].message == "gave up waiting after 5 s"


def test_a_run_without_valid_replicas_says_flakiness_is_unknown(tmp_path: Path) -> None:
    summary = summarize([_result(0, Verdict.ERROR, "no heartbeat")], test="t", namespace="local", run_id="r")
    (suite,) = list(_read(junit_document([run_suite(summary)]), tmp_path))
    props = {p.name: p.value for p in suite.properties()}
    assert props["uavtest.flakiness"] == "n/a" and props["uavtest.flaky"] == "false"


def test_results_a_cluster_status_left_out_are_counted_as_omitted(tmp_path: Path) -> None:
    summary = _summary().model_copy(update={"replicas": 20})
    (suite,) = list(_read(junit_document([run_suite(summary)]), tmp_path))
    props = {p.name: p.value for p in suite.properties()}
    assert props["uavtest.results-omitted"] == "16" and suite.tests == 4


def test_characters_xml_cannot_hold_do_not_break_the_report(tmp_path: Path) -> None:
    crash = _result(0, Verdict.ERROR, "simulator said \x00\x1b[31mboom\x07 <&>")
    summary = summarize([crash], test="t", namespace="local", run_id="r")
    (suite,) = list(_read(junit_document([run_suite(summary)]), tmp_path))
    (case,) = list(suite)
    assert case.result[0].message == "simulator said \ufffd\ufffd[31mboom\ufffd <&>"


@pytest.mark.parametrize(
    ("seeds", "text"), [([], "-"), ([7], "7"), ([9, 7, 8], "7..9"), ([1, 5], "1,5"), ([3, 3], "3,3")]
)
def test_seeds_are_a_range_when_consecutive(seeds: list[int], text: str) -> None:
    assert seeds_text(seeds) == text


def test_a_run_with_obstacles_carries_the_competition_score(tmp_path: Path) -> None:
    from uavtest.analysis.models import FlightMetrics

    def scored(i: int, d3: float, d2: float, points: int, collision: bool = False) -> ReplicaResult:
        metrics = FlightMetrics(
            min_obstacle_distance=d3,
            min_obstacle_distance_2d=d2,
            competition_points=points,
            collision=collision,
        )
        verdict = Verdict.PASS if d3 >= 1.5 else Verdict.FAIL
        return _result(i, verdict, "" if verdict is Verdict.PASS else "soft fail: ...", metrics=metrics)

    results = [scored(0, 0.0, 0.0, 5, collision=True), scored(1, 0.9, 0.78, 2), scored(2, 2.0, 1.9, 0)]
    summary = summarize(results, test="narrow-gap", namespace="local", run_id="r")
    (suite,) = list(_read(junit_document([run_suite(summary)]), tmp_path))
    props = {p.name: p.value for p in suite.properties()}
    assert props["uavtest.competition.points"] == "7"
    assert props["uavtest.competition.points-mean"] == "2.333"
    assert (props["uavtest.competition.hard-fails"], props["uavtest.competition.soft-fails"]) == ("1", "1")
    out = {c.name: c.system_out or "" for c in suite}
    assert "min obstacle distance: 0.900 m (3-D)" in out["replica-1"]
    assert "competition distance: 0.780 m (2-D)" in out["replica-1"]
    assert "competition points: 2" in out["replica-1"]
    # without obstacles there is no score
    (plain,) = list(_read(junit_document([run_suite(_summary())]), tmp_path))
    assert not any(p.name.startswith("uavtest.competition") for p in plain.properties())
