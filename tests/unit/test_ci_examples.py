"""examples/ci: valid YAML whose uavtest commands the real CLI accepts, reports where CI reads them."""

from __future__ import annotations

import fnmatch
from pathlib import Path
from typing import Any

import pytest
import typer

from harness.ci_examples import load, option, uavtest_commands
from uavtest.cli import app

CI = Path(__file__).resolve().parents[2] / "examples" / "ci"


def _load(name: str) -> dict[str, Any]:
    return load(CI / name)


def _parse(argv: list[str]) -> Any:
    """What the real CLI makes of ``argv`` (its click context: options and values checked, nothing
    run); a usage error when the CLI does not know an option."""
    commands = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    assert argv[1] in commands, argv
    return commands[argv[1]].make_context(argv[1], argv[2:])


@pytest.mark.parametrize("name", ["github-actions.yml", "github-actions-cluster.yml", "gitlab-ci.yml"])
def test_every_uavtest_command_is_one_the_cli_accepts_and_writes_junit(name: str, repo_root: Path) -> None:
    commands = uavtest_commands(_load(name))
    assert commands, f"{name} runs no uavtest command"
    for argv in commands:
        ctx = _parse(argv)
        assert ctx.params["junit"] is not None, argv
        for test in ctx.params["tests"]:
            assert (repo_root / test).exists(), test  # the example names files that exist


def test_github_publishes_the_report_the_command_writes_even_when_a_test_failed() -> None:
    for name in ("github-actions.yml", "github-actions-cluster.yml"):
        doc = _load(name)
        steps = [s for job in doc["jobs"].values() for s in job["steps"]]
        (argv,) = uavtest_commands(doc)
        (reporter,) = [s for s in steps if str(s.get("uses", "")).startswith("dorny/test-reporter")]
        assert reporter["if"] == "always()" and reporter["with"]["reporter"] == "java-junit"
        assert fnmatch.fnmatch(option(argv, "--junit"), reporter["with"]["path"])
    cluster = uavtest_commands(_load("github-actions-cluster.yml"))[0]
    assert option(cluster, "--engine") == "kubernetes"


def test_gitlab_reads_the_junit_report_of_each_job() -> None:
    doc = _load("gitlab-ci.yml")
    engines = []
    for job in ("uav-tests", "uav-tests-cluster"):
        (argv,) = uavtest_commands({job: doc[job]})
        assert doc[job]["artifacts"]["reports"]["junit"] == option(argv, "--junit")
        assert doc[job]["artifacts"]["when"] == "always"
        engines.append(option(argv, "--engine") if "--engine" in argv else "local")
    assert engines == ["local", "kubernetes"]


def test_an_option_the_cli_does_not_know_is_caught() -> None:
    with pytest.raises(Exception, match="No such option"):
        _parse(["uavtest", "run", "examples/hover.yaml", "--junit-xml", "r.xml"])
