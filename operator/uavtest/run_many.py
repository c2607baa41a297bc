"""``uavtest run`` with several tests: which files, one exit code, one table, one report.

``uavtest run tests/`` runs every ``*.yaml`` / ``*.yml`` file directly in the folder (sorted by
name, not recursive); ``uavtest run a.yaml b.yaml`` runs the files named, in that order.

One exit code for all, the most definite finding first:

- ``2`` bad input: every file is read and checked before anything flies; a wrong file is named
  and nothing flies (a suite is fixed as a whole, not half-run);
- ``1`` some test failed — also when another test had bench errors: a real failure is never
  hidden behind an infrastructure hiccup (a CI that tolerates or retries exit 3 must still see
  it);
- ``3`` bench errors (a test could not vouch for its result) and no failure;
- ``0`` every test passed.

A test the cluster rejects or the operator finds invalid after others flew still counts as ``2``
below a failure (``1``).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console
from rich.table import Table

from uavtest.analysis.junit import error_suite, junit_document, run_suite
from uavtest.analysis.models import RunSummary, Verdict
from uavtest.errors import BadInput, ExitCode, InfrastructureError, MissingFile

__all__ = [
    "TEST_SUFFIXES",
    "TestOutcome",
    "check_junit_path",
    "combined_exit",
    "exit_meaning",
    "expand_tests",
    "json_report",
    "junit_report",
    "suite_table",
    "write_junit",
]

TEST_SUFFIXES = (".yaml", ".yml")
#: most definite first: a failure outranks bad input, which outranks bench errors
_PRECEDENCE = (ExitCode.FAIL, ExitCode.BAD_INPUT, ExitCode.INFRASTRUCTURE, ExitCode.PASS)


def combined_exit(codes: Iterable[int]) -> ExitCode:
    """One exit code for several tests: 1 > 2 > 3 > 0 (see the module doc); 0 for none."""
    seen = {ExitCode(c) for c in codes}
    return next((c for c in _PRECEDENCE if c in seen), ExitCode.PASS)


def expand_tests(paths: Sequence[Path]) -> list[Path]:
    """The test files ``paths`` name: files as given, folders as their ``*.yaml``/``*.yml`` files."""
    if not paths:
        raise BadInput("name at least one test file or folder", field="TEST")
    files: list[Path] = []
    for path in paths:
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.is_file() and p.suffix in TEST_SUFFIXES)
            if not found:
                raise BadInput(
                    "the folder holds no test files", file=str(path), allowed="*.yaml or *.yml files in it"
                )
            files += found
        elif path.exists():
            files.append(path)
        else:
            raise MissingFile(str(path))
    return list(dict.fromkeys(files))


@dataclass(frozen=True)
class TestOutcome:
    """What one test of several came to: its summary (None when it did not run to one)."""

    __test__ = False  # not a pytest class

    source: Path
    test: str
    code: int
    summary: RunSummary | None = None
    message: str = ""
    namespace: str = ""
    #: replica index → {flight.ulg / result.json: file path or s3:// URI}
    links: Mapping[int, Mapping[str, str]] = field(default_factory=dict)

    def summary_or_error(self) -> RunSummary:
        """The run's summary; for a test that did not run to one, an ``error`` summary with no
        replicas whose warnings say why (so ``--json`` lists every test in one shape)."""
        if self.summary is not None:
            return self.summary
        return RunSummary(
            test=self.test,
            namespace=self.namespace,
            run_id="",
            replicas=0,
            passed=0,
            failed=0,
            errors=0,
            flaky=False,
            verdict=Verdict.ERROR,
            warnings=[self.message],
        )


def junit_report(outcomes: Sequence[TestOutcome]) -> bytes:
    """One JUnit document, one suite per test (a test without a summary: one ``<error>`` case)."""
    return junit_document(
        run_suite(o.summary, o.links)
        if o.summary is not None
        else error_suite(o.test, o.message, source=str(o.source))
        for o in outcomes
    )


def json_report(outcomes: Sequence[TestOutcome]) -> str:
    """``--json``: one test → its ``RunSummary`` object (as always); several → a list of them,
    in the order the tests were given."""
    docs = [o.summary_or_error().model_dump(mode="json") for o in outcomes]
    return json.dumps(docs[0] if len(docs) == 1 else docs, indent=2)


def suite_table(outcomes: Sequence[TestOutcome]) -> Table:
    """One row per test: file, test, verdict, passed / failed / errors, flakiness, exit."""
    table = Table(title=f"{len(outcomes)} tests", title_justify="left")
    for name, justify in (
        ("file", "left"),
        ("test", "left"),
        ("verdict", "left"),
        ("passed", "right"),
        ("failed", "right"),
        ("errors", "right"),
        ("flakiness", "right"),
        ("exit", "right"),
    ):
        table.add_column(name, justify=justify, overflow="fold")  # type: ignore[arg-type]
    style = {"pass": "green", "fail": "red", "error": "yellow"}
    for o in outcomes:
        s = o.summary
        if s is None:
            row = [str(o.source), o.test, f"[yellow]error[/] {o.message}", "-", "-", "-", "-"]
            table.add_row(*row, str(o.code))
            continue
        flakiness = "n/a" if s.flakiness is None else f"{s.flakiness:.2f}"
        verdict = f"[{style[s.verdict.value]}]{s.verdict.value}[/]"
        row = [str(o.source), s.test, verdict, str(s.passed), str(s.failed), str(s.errors)]
        table.add_row(*row, flakiness, str(o.code))
    return table


def exit_meaning(code: ExitCode) -> str:
    """The exit code in words, for the line under the table."""
    return {
        ExitCode.PASS: "every test passed",
        ExitCode.FAIL: "a test failed",
        ExitCode.BAD_INPUT: "bad input",
        ExitCode.INFRASTRUCTURE: "bench errors, no failure",
    }[code]


def check_junit_path(path: Path) -> None:
    """Refuse a ``--junit`` path that cannot be written before anything flies (exit 2)."""
    if path.is_dir():
        raise BadInput(
            "is a folder", field="--junit", value=str(path), allowed="a file path, e.g. report.xml"
        )
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise BadInput(f"its folder cannot be made: {e}", field="--junit", value=str(path)) from None


def write_junit(path: Path, xml: bytes, console: Console) -> None:
    """Write ``--junit``'s file (the one I/O here); InfrastructureError when it cannot be written."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(xml)
    except OSError as e:
        raise InfrastructureError(f"--junit: cannot write {path}: {e}") from None
    console.print(f"junit: {path}", highlight=False)
