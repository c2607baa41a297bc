"""Several tests in one command: which files run, the one exit code, the JSON and JUnit shapes."""

from __future__ import annotations

import json
from pathlib import Path

import junitparser
import pytest

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.errors import BadInput, ExitCode, MissingFile
from uavtest.run_many import (
    TestOutcome,
    check_junit_path,
    combined_exit,
    expand_tests,
    json_report,
    junit_report,
    suite_table,
)

P, F, B, E = ExitCode.PASS, ExitCode.FAIL, ExitCode.BAD_INPUT, ExitCode.INFRASTRUCTURE


@pytest.mark.parametrize(
    ("codes", "code"),
    [
        ([], P),
        ([P, P], P),
        ([P, F], F),
        ([P, E], E),
        ([E, F, P], F),  # a real failure is never hidden behind a bench error
        ([B, E], B),
        ([B, F], F),
        ([P, B], B),
    ],
)
def test_one_exit_code_for_several_tests(codes: list[ExitCode], code: ExitCode) -> None:
    assert combined_exit(codes) is code


def test_a_folder_runs_its_yaml_files_in_name_order(tmp_path: Path) -> None:
    for name in ("b.yaml", "a.yml", "notes.txt", "c.yaml"):
        (tmp_path / name).write_text("x")
    (tmp_path / "nested").mkdir()
    (tmp_path / "nested" / "d.yaml").write_text("x")
    extra = tmp_path / "nested" / "d.yaml"
    assert expand_tests([tmp_path, extra, tmp_path / "a.yml"]) == [
        tmp_path / "a.yml",
        tmp_path / "b.yaml",
        tmp_path / "c.yaml",
        extra,
    ]


def test_a_missing_file_or_an_empty_folder_is_bad_input(tmp_path: Path) -> None:
    with pytest.raises(MissingFile, match=r"absent\.yaml"):
        expand_tests([tmp_path / "absent.yaml"])
    with pytest.raises(BadInput, match="holds no test files"):
        expand_tests([tmp_path])


def _outcome(name: str, verdicts: list[Verdict], source: str) -> TestOutcome:
    results = [ReplicaResult(index=i, seed=i, verdict=v) for i, v in enumerate(verdicts)]
    summary = summarize(results, test=name, namespace="local", run_id=f"run-{name}")
    code = {Verdict.PASS: P, Verdict.FAIL: F, Verdict.ERROR: E}[summary.verdict]
    return TestOutcome(Path(source), name, int(code), summary, namespace="local")


def test_json_is_the_summary_for_one_test_and_a_list_for_several() -> None:
    one = _outcome("hover", [Verdict.PASS], "hover.yaml")
    lost = TestOutcome(Path("b.yaml"), "b", int(E), message="lost the cluster", namespace="ci")
    assert json.loads(json_report([one]))["test"] == "hover"
    docs = json.loads(json_report([one, lost]))
    assert [d["test"] for d in docs] == ["hover", "b"]
    assert docs[1]["verdict"] == "error" and docs[1]["replicas"] == 0
    assert docs[1]["warnings"] == ["lost the cluster"] and docs[1]["namespace"] == "ci"


def test_the_junit_report_has_a_suite_per_test(tmp_path: Path) -> None:
    outcomes = [
        _outcome("hover", [Verdict.PASS, Verdict.PASS], "a.yaml"),
        _outcome("wall", [Verdict.FAIL, Verdict.PASS, Verdict.ERROR], "b.yaml"),
        TestOutcome(Path("c.yaml"), "c", int(E), message="gave up waiting"),
    ]
    path = tmp_path / "report.xml"
    path.write_bytes(junit_report(outcomes))
    doc = junitparser.JUnitXml.fromfile(str(path))
    assert [s.name for s in doc] == ["hover", "wall", "c"]
    assert (doc.tests, doc.failures, doc.errors) == (6, 1, 2)


def test_the_table_has_a_row_per_test() -> None:
    outcomes = [_outcome("hover", [Verdict.PASS], "a.yaml"), TestOutcome(Path("c.yaml"), "c", 3, message="x")]
    table = suite_table(outcomes)
    assert table.row_count == 2
    assert [c.header for c in table.columns][:3] == ["file", "test", "verdict"]


def test_a_junit_path_that_cannot_be_written_is_refused_before_flying(tmp_path: Path) -> None:
    with pytest.raises(BadInput, match="is a folder"):
        check_junit_path(tmp_path)
    (tmp_path / "file").write_text("x")
    with pytest.raises(BadInput, match="--junit"):
        check_junit_path(tmp_path / "file" / "report.xml")
    check_junit_path(tmp_path / "new" / "report.xml")
    assert (tmp_path / "new").is_dir()
