"""`uavtest run --engine kubernetes`: exit codes, progress, the JSON summary, the options it
honours and the artifact download, from a UavTest's status (pure parts, and the CLI's refusals
that happen before any cluster is touched)."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from rich.console import Console

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, RunSummary, Verdict
from uavtest.controller.cluster_download import (
    S3_VARIABLES,
    check_download_settings,
    download_run,
    missing_s3_settings,
    store_root,
)
from uavtest.controller.cluster_run import (
    apply_overrides,
    exit_code_for,
    progress_text,
    results_table,
    still_running_message,
    summary_from_status,
    with_download,
)
from uavtest.controller.reconcile import parse_test
from uavtest.controller.status import status_from
from uavtest.controller.views import job_view, pod_view, run_view
from uavtest.errors import BadInput, ExitCode, UavTestError
from uavtest.run_options import Engine, ignored_options, ignored_warning
from uavtest.spec.loaders import load_test
from uavtest.store.local import LocalStore

from .controller_bodies import job_body, pod_body, uavtest_body


def final(*verdicts: Verdict) -> dict[str, object]:
    results = [
        ReplicaResult(
            index=i,
            seed=i,
            verdict=v,
            metrics=None if v == Verdict.ERROR else FlightMetrics(min_obstacle_distance=2),
        )
        for i, v in enumerate(verdicts)
    ]
    summary = summarize(results, test="hover", namespace="team-a", run_id="5f0c3a9e")
    test = run_view(uavtest_body(replicas=len(verdicts)))
    return status_from(test, None, [], store_url="s3://b", summary=summary).dump()


@pytest.mark.parametrize(
    ("verdicts", "code"),
    [
        ((Verdict.PASS, Verdict.PASS), ExitCode.PASS),
        ((Verdict.PASS, Verdict.FAIL), ExitCode.FAIL),
        ((Verdict.FAIL, Verdict.ERROR), ExitCode.FAIL),
        ((Verdict.PASS, Verdict.ERROR), ExitCode.INFRASTRUCTURE),
        ((Verdict.ERROR, Verdict.ERROR), ExitCode.INFRASTRUCTURE),
    ],
)
def test_exit_codes_match_the_local_engine(verdicts: tuple[Verdict, ...], code: ExitCode) -> None:
    assert exit_code_for(final(*verdicts)) == code


def test_a_spec_the_cluster_cannot_run_exits_as_bad_input() -> None:
    status = {
        "phase": "Error",
        "conditions": [{"type": "Complete", "status": "True", "reason": "InvalidSpec", "message": "x"}],
    }
    assert exit_code_for(status) == ExitCode.BAD_INPUT


def test_progress_line_counts_replicas() -> None:
    test = run_view(uavtest_body(replicas=4))
    pods = [pod_view(pod_body(0, "Running")), pod_view(pod_body(1, "Succeeded", exit_code=0))]
    st = status_from(
        test, job_view(job_body(completed="1", active=1)), [p for p in pods if p], store_url="s3://b"
    ).dump()
    assert progress_text(st) == "Running · 1 passed · 0 failed · 0 error · 1 running · 2 pending"


def test_a_body_that_does_not_fit_the_model_names_the_field() -> None:
    with pytest.raises(BadInput, match=r"spec\.testSpec\.replicas"):
        parse_test(uavtest_body(replicas=0))


REPO = Path(__file__).resolve().parents[3]
HOVER = REPO / "examples" / "hover.yaml"


def test_the_json_summary_has_the_local_engines_shape_and_numbers() -> None:
    status = final(Verdict.PASS, Verdict.FAIL, Verdict.ERROR)
    summary = summary_from_status("hover-x7k2p", "team-a", status)
    assert isinstance(summary, RunSummary)
    assert (summary.test, summary.namespace, summary.run_id) == ("hover-x7k2p", "team-a", "5f0c3a9e")
    assert (summary.replicas, summary.passed, summary.failed, summary.errors) == (3, 1, 1, 1)
    assert summary.verdict == Verdict.FAIL and summary.flakiness == 0.5 and summary.flaky
    assert [(r.index, r.seed, r.verdict) for r in summary.results] == [
        (0, 0, Verdict.PASS),
        (1, 1, Verdict.FAIL),
        (2, 2, Verdict.ERROR),
    ]
    assert summary.min_obstacle_distance is not None and summary.min_obstacle_distance.count == 2
    # the same keys as the local engine's --json
    local = summarize([], test="t", namespace="local", run_id="r")
    assert set(summary.model_dump()) == set(local.model_dump())


def test_the_json_verdict_follows_the_counters_when_results_are_omitted() -> None:
    status = final(Verdict.PASS, Verdict.PASS)
    status.update({"replicas": 60, "passed": 58, "errors": 2, "resultsOmitted": 10})
    summary = summary_from_status("hover-x7k2p", "team-a", status)
    assert (summary.replicas, summary.passed, summary.errors) == (60, 58, 2)
    assert summary.verdict == Verdict.PASS and summary.min_obstacle_distance is None


def test_the_status_carries_the_competition_outcomes_to_the_table_and_the_json() -> None:
    def scored(i: int, d3: float, d2: float, points: int) -> ReplicaResult:
        metrics = FlightMetrics(
            min_obstacle_distance=d3, min_obstacle_distance_2d=d2, competition_points=points
        )
        return ReplicaResult(index=i, seed=i, verdict=Verdict.FAIL, reason="soft fail: ...", metrics=metrics)

    summary = summarize(
        [scored(0, 0.9, 0.78, 2), scored(1, 1.3, 1.21, 1)], test="gap", namespace="a", run_id="r"
    )
    test = run_view(uavtest_body(replicas=2))
    status = status_from(test, None, [], store_url="s3://b", summary=summary).dump()
    assert status["results"][0]["minDistance2D"] == 0.78 and status["results"][0]["points"] == 2
    console = Console(width=160, record=True, color_system=None)
    console.print(results_table("gap", status))
    row = next(line for line in console.export_text().splitlines() if "0.78 m" in line)
    assert "0.90 m" in row and " 2 " in row
    back = summary_from_status("gap", "a", status)
    assert back.competition_points is not None
    assert (back.competition_points.total, back.competition_points.soft_fails) == (3, 2)


def test_replicas_and_seed_override_the_spec_and_name_the_option_when_wrong() -> None:
    test = load_test(HOVER)
    spec = apply_overrides(test, replicas=2, seed=7).spec
    assert (spec.replicas, spec.seed, spec.replica_seed(1)) == (2, 7, 8)
    assert apply_overrides(test, replicas=None, seed=None) is test
    with pytest.raises(BadInput, match=r"--replicas.*got 0.*1\.\.1000"):
        apply_overrides(test, replicas=0, seed=None)
    with pytest.raises(BadInput, match=r"--seed.*got -1"):
        apply_overrides(test, replicas=None, seed=-1)


@pytest.mark.parametrize(
    ("run", "download", "code"),
    [
        (ExitCode.PASS, None, ExitCode.PASS),
        (ExitCode.PASS, "store unreachable", ExitCode.INFRASTRUCTURE),
        (ExitCode.FAIL, "store unreachable", ExitCode.FAIL),  # the test's news wins
        (ExitCode.INFRASTRUCTURE, "store unreachable", ExitCode.INFRASTRUCTURE),
    ],
)
def test_a_failed_download_never_passes_silently(run: ExitCode, download: str | None, code: ExitCode) -> None:
    assert with_download(int(run), download) == code


def test_options_an_engine_does_not_use_are_named() -> None:
    given = {"--jobs": 4, "--replica": None, "--namespace": "ci", "--timeout": 60.0, "--out": Path("o")}
    assert ignored_options(Engine.KUBERNETES, given) == ["--jobs"]
    assert ignored_options(Engine.LOCAL, given) == ["--namespace", "--timeout"]
    assert ignored_options(Engine.KUBERNETES, given, wait=False) == ["--jobs", "--timeout", "--out"]
    text = ignored_warning(Engine.KUBERNETES, ["--jobs"])
    assert text is not None and "--jobs" in text and "spec.parallelism" in text
    assert ignored_warning(Engine.KUBERNETES, []) is None


def test_the_timeout_message_says_the_test_runs_on_and_how_to_follow_it() -> None:
    text = still_running_message("hover-x7k2p", "ci", {"phase": "Running", "running": 2}, 30)
    assert "30 s" in text and "still running" in text
    assert "kubectl get uavtestrun/hover-x7k2p -n ci -w" in text


def test_the_store_is_the_run_uri_without_the_run_prefix() -> None:
    uri = "s3://uavtest/runs/team-a/hover-x7k2p/5f0c3a9e/"
    assert store_root(uri, "team-a", "hover-x7k2p", "5f0c3a9e") == "s3://uavtest/runs"
    assert store_root(uri.rstrip("/"), "team-a", "hover-x7k2p", "5f0c3a9e") == "s3://uavtest/runs"
    with pytest.raises(UavTestError, match="cannot tell which store"):
        store_root("s3://uavtest/other/", "team-a", "hover-x7k2p", "5f0c3a9e")


def test_missing_s3_settings_are_named_before_anything_is_created() -> None:
    assert missing_s3_settings({}) == list(S3_VARIABLES)
    env = {
        "UAVTEST_S3_ENDPOINT": "127.0.0.1:9000",
        "UAVTEST_S3_ACCESS_KEY": "a",
        "UAVTEST_S3_SECRET_KEY": " ",
    }
    assert missing_s3_settings(env) == ["UAVTEST_S3_SECRET_KEY"]
    with pytest.raises(BadInput, match="UAVTEST_S3_SECRET_KEY is not set") as e:
        check_download_settings(env)
    assert e.value.exit_code == ExitCode.BAD_INPUT


def test_download_copies_every_artifact_of_the_run_in_the_store_layout(tmp_path: Path) -> None:
    remote = LocalStore(tmp_path / "remote")
    prefix = "team-a/hover-x7k2p/5f0c3a9e/"
    for key in ("replica-0/flight.ulg", "replica-0/result.json", "aggregate/summary.json"):
        remote.put(prefix + key, key.encode())
    remote.put("team-a/hover-x7k2p/other-run/replica-0/result.json", b"not this run")
    files = download_run(remote, prefix, tmp_path / "out")
    assert sorted(p.relative_to(tmp_path / "out").as_posix() for p in files) == sorted(
        prefix + k for k in ("replica-0/flight.ulg", "replica-0/result.json", "aggregate/summary.json")
    )
    assert (tmp_path / "out" / prefix / "replica-0" / "flight.ulg").read_bytes() == b"replica-0/flight.ulg"
    with pytest.raises(UavTestError, match="no artifacts"):
        download_run(remote, "team-a/hover-x7k2p/missing/", tmp_path / "out")


def _cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    base = {k: v for k, v in os.environ.items() if not k.startswith("UAVTEST_S3_") and k != "KUBECONFIG"}
    return subprocess.run(
        [sys.executable, "-m", "uavtest.cli", "run", *args],
        env={**base, "KUBECONFIG": "/nonexistent/kubeconfig", "COLUMNS": "300", **(env or {})},
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_an_unknown_engine_is_a_usage_error_listing_the_choices() -> None:
    done = _cli(str(HOVER), "--engine", "foo")
    assert done.returncode == 2
    assert "'foo' is not one of 'local', 'kubernetes'" in " ".join(done.stderr.split())


def test_out_without_s3_settings_exits_2_before_the_cluster_and_warns_of_ignored_options() -> None:
    done = _cli(str(HOVER), "--engine", "kubernetes", "--out", "dl", "--jobs", "3")
    assert done.returncode == 2, done.stderr
    text = " ".join(done.stderr.split())
    assert "ignored with --engine kubernetes: --jobs" in text
    assert "--out" in text and all(v in text for v in S3_VARIABLES)
    assert "no cluster" not in text  # refused before the (missing) cluster was asked anything


def test_a_run_without_timeout_watches_a_minute_at_a_time() -> None:
    from uavtest.controller.cluster_run import watch_seconds

    assert watch_seconds(math.inf) == 60
    assert watch_seconds(0.2) == 1
    assert watch_seconds(12.5) == 13


def test_junit_links_are_the_replicas_s3_uris_from_the_status() -> None:
    from uavtest.controller.cluster_run import replica_links

    status = {"runId": "r1", "artifacts": {"store": "s3://uavtest/pre/ns/t-x7k2f/r1/"}}
    links = replica_links(status, "t-x7k2f", "ns", [0, 2])
    assert links[2] == {
        "flight.ulg": "s3://uavtest/pre/ns/t-x7k2f/r1/replica-2/flight.ulg",
        "result.json": "s3://uavtest/pre/ns/t-x7k2f/r1/replica-2/result.json",
    }
    assert replica_links({"runId": "r1"}, "t", "ns", [0]) == {}
