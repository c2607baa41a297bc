"""``uavtest run TEST... --engine kubernetes``: apply each test in a cluster, follow its run, exit.

A test keeps its identity (``metadata.name``): the rendered test is created, or the UavTest of
that name gets the new spec. Each apply starts one run (a ``UavTestRun`` the operator creates under
a name known in advance): a changed spec starts the run ``<test>-g<generation>``; an unchanged one
sets the ``uavtest.io/rerun`` annotation to a fresh value, which starts ``<test>-r<hash>``.
Progress comes from watching those runs' status, and the exit code is the local engine's: 0 every
replica passed, 1 some replica failed, 2 bad input (also a test the API server rejects), 3 bench
errors only, or the cluster could not be used.

``--replicas`` / ``--seed`` override the spec before it is created; ``--json`` prints the local
engine's ``RunSummary``; ``--out`` downloads the run's artifacts (``cluster_download``);
``--timeout`` gives up waiting (exit 3) and leaves the runs going; ``--junit`` writes the runs
as JUnit XML (from the store's ``summary.json`` when ``--out`` brought it home, else from the status,
with each replica's ``s3://`` artifact URIs). Several tests are all rendered and dry-run created
first (a wrong one: exit 2, nothing applied), then applied and their runs followed together; one exit code
(``uavtest.run_many``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, RunSummary, Verdict
from uavtest.controller import names
from uavtest.controller.cluster_download import check_download_settings, download_run, store_root
from uavtest.controller.status import is_final
from uavtest.errors import BadInput, ExitCode, InfrastructureError, UavTestError
from uavtest.spec.models import UavTest
from uavtest.store.layout import FLIGHT_LOG, RESULT, SUMMARY, aggregate_key, replica_key, run_prefix

__all__ = [
    "ClusterRunOptions",
    "apply_overrides",
    "exit_code_for",
    "progress_text",
    "replica_links",
    "results_table",
    "run_in_cluster",
    "still_running_message",
    "summary_from_status",
    "watch_seconds",
    "with_download",
]

MAX_REPLICAS = 1000  # spec.replicas' bound
MAX_SEED = 2**32 - 1  # spec.seed's bound

_WATCH_SECONDS = 60


def watch_seconds(left: float) -> int:
    """Seconds for one watch request: at most a minute, at least 1, ``left`` may be infinite."""
    return max(1, math.ceil(min(float(_WATCH_SECONDS), left)))


def exit_code_for(status: Mapping[str, Any]) -> ExitCode:
    """The exit code a final status means (same as the local engine's)."""
    complete = next(
        (c for c in status.get("conditions") or [] if c.get("type") == names.ConditionType.COMPLETE), {}
    )
    if complete.get("reason") == names.Reason.INVALID_SPEC:
        return ExitCode.BAD_INPUT
    phase = status.get("phase")
    if phase == names.Phase.SUCCEEDED:
        return ExitCode.PASS
    if phase == names.Phase.FAILED:
        return ExitCode.FAIL
    return ExitCode.INFRASTRUCTURE


def progress_text(status: Mapping[str, Any]) -> str:
    """One line of phase and counts: ``Running · 2 passed · 0 failed · 0 error · 3 running · 5 pending``."""
    counts = " · ".join(
        f"{int(status.get(k) or 0)} {label}"
        for k, label in (
            ("passed", "passed"),
            ("failed", "failed"),
            ("errors", "error"),
            ("running", "running"),
            ("pending", "pending"),
        )
    )
    return f"{status.get('phase') or 'Pending'} · {counts}"


def results_table(name: str, status: Mapping[str, Any]) -> Table:
    """The replicas the status lists (failures and errors first), as the local engine shows them."""
    table = Table(title=f"{name} · run {status.get('runId', '?')}", title_justify="left")
    for col, justify in (
        ("replica", "right"),
        ("seed", "right"),
        ("verdict", "left"),
        ("3-D distance", "right"),
        ("2-D distance", "right"),
        ("points", "right"),
    ):
        table.add_column(col, justify=justify)  # type: ignore[arg-type]
    table.add_column("reason", overflow="fold")
    style = {"pass": "green", "fail": "red", "error": "yellow"}

    def metres(value: float | None) -> str:
        return "-" if value is None else f"{value:.2f} m"

    for r in sorted(status.get("results") or [], key=lambda r: r["index"]):
        points = r.get("points")
        table.add_row(
            str(r["index"]),
            str(r["seed"]),
            f"[{style.get(r['verdict'], '')}]{r['verdict']}[/]",
            metres(r.get("minDistance")),
            metres(r.get("minDistance2D")),
            "-" if points is None else str(points),
            r.get("reason", ""),
        )
    return table


def _namespace(manifest: Mapping[str, Any], namespace: str | None) -> str:
    if namespace:
        return namespace
    given = manifest.get("metadata", {}).get("namespace")
    if given:
        return str(given)
    import kubernetes

    try:
        _, active = kubernetes.config.list_kube_config_contexts()
        return str(active.get("context", {}).get("namespace") or "default")
    except (kubernetes.config.ConfigException, OSError):
        return "default"


def _apply(custom: Any, namespace: str, manifest: dict[str, Any], *, dry_run: bool = False) -> str:
    """Create the UavTest, or give the existing one this spec (``dry_run``: have the API server
    check it without keeping it); the name of the run this starts."""
    from kubernetes.client.exceptions import ApiException

    from uavtest.controller.runs import generation_run_name, rerun_name, spec_hash

    name = str(manifest["metadata"]["name"])
    args = (names.API_GROUP, names.VERSION, namespace, names.PLURAL)
    extra = {"dry_run": "All"} if dry_run else {}
    try:
        try:
            existing = custom.get_namespaced_custom_object(*args, name)
        except ApiException as e:
            if e.status != 404:
                raise
            created = custom.create_namespaced_custom_object(*args, manifest, **extra)
            return generation_run_name(name, int(created["metadata"].get("generation") or 1))
        body = dict(existing)
        meta = dict(body["metadata"])
        token = None
        if spec_hash(existing.get("spec") or {}) == spec_hash(manifest.get("spec") or {}):
            # the same flight: keep the stored spec (no new generation), ask for a re-run
            token = f"cli-{time.time_ns()}"
            meta["annotations"] = {**(meta.get("annotations") or {}), names.RERUN_ANNOTATION: token}
        else:
            body["spec"] = manifest["spec"]
        body["metadata"] = meta
        replaced = custom.replace_namespaced_custom_object(*args, name, body, **extra)
    except ApiException as e:
        if e.status in (400, 422):
            raise BadInput(f"the cluster rejected the test {name}: {_api_message(e)}") from None
        if e.status == 404:
            raise InfrastructureError(
                f"no UavTest API in the cluster (or no namespace {namespace}): install the CRDs "
                "(kubectl apply -f crds/) or the Helm chart"
            ) from None
        if e.status == 409:
            raise InfrastructureError(
                f"uavtest/{name} changed meanwhile; run again: {_api_message(e)}"
            ) from None
        raise InfrastructureError(f"applying the UavTest failed: {_api_message(e)}") from None
    if token is not None:
        return rerun_name(name, token)
    return generation_run_name(name, int(replaced["metadata"].get("generation") or 1))


def _api_message(e: Any) -> str:
    import json

    try:
        return str(json.loads(e.body).get("message") or e.reason)
    except (TypeError, ValueError):
        return str(e.reason)


def _follow(
    custom: Any, namespace: str, wanted: list[str], console: Console, *, timeout: float | None = None
) -> dict[str, dict[str, Any]]:
    """Watch the UavTestRuns ``wanted`` (they may not exist yet) until every status is final or
    ``timeout`` seconds pass; show a progress line per run meanwhile; return each one's latest
    status (``is_final`` tells which)."""
    import kubernetes
    from kubernetes.client.exceptions import ApiException
    from urllib3.exceptions import HTTPError

    deadline = math.inf if timeout is None else time.monotonic() + timeout
    statuses: dict[str, dict[str, Any]] = {name: {} for name in wanted}
    selector = {"field_selector": f"metadata.name={wanted[0]}"} if len(wanted) == 1 else {}
    columns = (
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[line]}"),
        TimeElapsedColumn(),
    )

    def all_final() -> bool:
        return all(is_final(st) for st in statuses.values())

    with Progress(*columns, console=console, transient=False) as progress:
        tasks = {name: progress.add_task(name, total=None, line="Pending") for name in wanted}
        resource_version = None
        failures = 0
        while not all_final():
            left = deadline - time.monotonic()
            if left <= 0:
                break
            watch = kubernetes.watch.Watch()
            try:
                for event in watch.stream(
                    custom.list_namespaced_custom_object,
                    names.API_GROUP,
                    names.VERSION,
                    namespace,
                    names.RUN_PLURAL,
                    resource_version=resource_version,
                    timeout_seconds=watch_seconds(left),
                    **selector,
                ):
                    obj = event["object"]
                    if event["type"] == "ERROR":
                        resource_version = None
                        break
                    resource_version = obj["metadata"].get("resourceVersion")
                    name = obj["metadata"].get("name")
                    if name not in statuses:
                        continue
                    if event["type"] == "DELETED":
                        raise InfrastructureError(f"uavtestrun/{name} was deleted before it finished")
                    status = statuses[name] = obj.get("status") or {}
                    done = sum(int(status.get(k) or 0) for k in ("passed", "failed", "errors"))
                    progress.update(
                        tasks[name],
                        total=status.get("replicas") or None,
                        completed=done,
                        line=progress_text(status),
                    )
                    failures = 0
                    if all_final() or time.monotonic() >= deadline:
                        break
            except ApiException as e:
                if e.status == 410:  # resourceVersion too old: list again
                    resource_version = None
                    continue
                raise InfrastructureError(
                    f"watching uavtestrun/{', '.join(wanted)} failed: {_api_message(e)}"
                ) from None
            except HTTPError as e:
                failures += 1
                if failures > 5:
                    raise InfrastructureError(
                        f"lost the cluster while watching {', '.join(wanted)}: {e}"
                    ) from None
                time.sleep(min(2.0**failures, 30.0, max(deadline - time.monotonic(), 0.0)))
            finally:
                watch.stop()
    return statuses


def still_running_message(name: str, namespace: str, status: Mapping[str, Any], timeout: float) -> str:
    """What to tell a user whose ``--timeout`` ran out: the test goes on, and how to follow it."""
    where = f"uavtestrun/{name} -n {namespace}"
    return (
        f"gave up waiting after {timeout:g} s (--timeout): uavtestrun/{name} is still running in namespace "
        f"{namespace} ({progress_text(status)}); follow it with `kubectl get {where} -w` "
        f"or `kubectl wait --for=condition=Complete {where}`"
    )


def summary_from_status(name: str, namespace: str, status: Mapping[str, Any]) -> RunSummary:
    """The local engine's ``--json`` shape (``RunSummary``) from what a final status holds.

    The status keeps each replica's index, seed, verdict, reason, distances and points (at most
    ``MAX_STATUS_RESULTS`` of them; the counters always cover every replica); flight times and the
    unmodelled parameters are only in ``summary.json`` in the store.
    """
    results = [
        ReplicaResult(
            index=int(r["index"]),
            seed=int(r["seed"]),
            verdict=Verdict(r["verdict"]),
            reason=str(r.get("reason") or ""),
            metrics=None
            if r.get("minDistance") is None
            else FlightMetrics(
                min_obstacle_distance=float(r["minDistance"]),
                min_obstacle_distance_2d=r.get("minDistance2D"),
                competition_points=r.get("points"),
            ),
        )
        for r in status.get("results") or []
    ]
    summary = summarize(results, test=name, namespace=namespace, run_id=str(status.get("runId") or ""))
    counts = {k: int(status.get(k) or 0) for k in ("replicas", "passed", "failed", "errors")}
    update: dict[str, Any] = {**counts, "warnings": list(status.get("warnings") or [])}
    if int(status.get("resultsOmitted") or 0):  # stats over a part of the replicas would mislead
        update.update(min_obstacle_distance=None, min_obstacle_distance_2d=None, competition_points=None)
    update["flakiness"] = status.get("flakiness")
    update["flaky"] = bool(status.get("flaky"))
    if counts["failed"]:
        update["verdict"] = Verdict.FAIL
    elif counts["passed"]:
        update["verdict"] = Verdict.PASS
    else:
        update["verdict"] = Verdict.ERROR
    return RunSummary.model_validate({**summary.model_dump(), **update})


def with_download(run_code: int, download_error: str | None) -> int:
    """The exit code once ``--out`` was tried: a failing test stays 1; a download that did not
    happen turns a pass (or bench errors) into 3, since the run did not deliver what was asked."""
    if download_error is None or run_code in (ExitCode.FAIL, ExitCode.BAD_INPUT):
        return run_code
    return int(ExitCode.INFRASTRUCTURE)


def apply_overrides(test: UavTest, *, replicas: int | None, seed: int | None) -> UavTest:
    """``test`` with ``--replicas`` and ``--seed`` in its spec; BadInput naming the option."""
    update: dict[str, Any] = {}
    if replicas is not None:
        if not 1 <= replicas <= MAX_REPLICAS:
            raise BadInput(
                "replicas out of range", field="--replicas", value=replicas, allowed=f"1..{MAX_REPLICAS}"
            )
        update["replicas"] = replicas
    if seed is not None:
        if not 0 <= seed <= MAX_SEED:
            raise BadInput("seed out of range", field="--seed", value=seed, allowed=f"0..{MAX_SEED}")
        update["seed"] = seed
    if not update:
        return test
    return test.model_copy(update={"spec": test.spec.model_copy(update=update)})


@dataclass(frozen=True)
class ClusterRunOptions:
    """``uavtest run --engine kubernetes``'s options."""

    tests: list[Path]
    namespace: str | None = None
    wait: bool = True
    replicas: int | None = None
    seed: int | None = None
    out: Path | None = None
    json_out: bool = False
    timeout: float | None = None
    junit: Path | None = None


def _download(status: Mapping[str, Any], name: str, ns: str, out: Path, console: Console) -> str | None:
    """Copy the run's artifacts to ``out``; None, or why it did not work (said on stderr)."""
    from uavtest.store.open import open_store

    run_id = str(status.get("runId") or "")
    where = (status.get("artifacts") or {}).get("store")
    try:
        if not run_id or not where:
            raise InfrastructureError("the status names no artifacts (no runId / artifacts.store)")
        store = open_store(store_root(str(where), ns, name, run_id))
        files = download_run(store, run_prefix(ns, name, run_id), out)
    except UavTestError as e:
        console.print(f"[bold red]--out:[/] artifacts not downloaded: {e}", highlight=False, soft_wrap=True)
        return str(e)
    folder = out.resolve() / run_prefix(ns, name, run_id)
    console.print(f"artifacts: {len(files)} files in {folder}", highlight=False)
    return None


def _summary(status: Mapping[str, Any], name: str, ns: str, out: Path | None, downloaded: bool) -> RunSummary:
    """The run's summary.json when it came home with --out, else what the status holds."""
    if downloaded and out is not None and status.get("runId"):
        path = out / aggregate_key(ns, name, str(status["runId"]), SUMMARY)
        try:
            return RunSummary.model_validate_json(path.read_bytes())
        except (OSError, ValidationError):
            pass
    return summary_from_status(name, ns, status)


def replica_links(
    status: Mapping[str, Any], name: str, ns: str, indices: list[int]
) -> dict[int, dict[str, str]]:
    """Each replica's flight log and result URI, from the status' ``artifacts.store`` (empty when the
    status names none)."""
    run_id = str(status.get("runId") or "")
    where = (status.get("artifacts") or {}).get("store")
    if not run_id or not where:
        return {}
    try:
        root = store_root(str(where), ns, name, run_id).rstrip("/")
    except UavTestError:
        return {}
    return {
        i: {f: f"{root}/{replica_key(ns, name, run_id, i, f)}" for f in (FLIGHT_LOG, RESULT)} for i in indices
    }


@dataclass
class _Prepared:
    source: Path
    test: UavTest
    manifest: dict[str, Any]
    namespace: str
    name: str = ""
    run: str = ""  # the UavTestRun the apply started


def _prepare(opts: ClusterRunOptions, console: Console) -> list[_Prepared]:
    """Every test read, overridden and rendered before anything is created; each wrong file said,
    then BadInput (exit 2, nothing created)."""
    from uavtest.spec.loaders import load_test
    from uavtest.spec.render import render

    prepared: list[_Prepared] = []
    wrong: list[str] = []
    for path in opts.tests:
        try:
            test = apply_overrides(load_test(Path(path)), replicas=opts.replicas, seed=opts.seed)
        except BadInput as e:
            if len(opts.tests) == 1:
                raise
            console.print(f"[bold red]error:[/] {e}", highlight=False, soft_wrap=True)
            wrong.append(str(path))
            continue
        manifest = render(test)
        ns = _namespace(manifest, opts.namespace)
        manifest["metadata"]["namespace"] = ns
        prepared.append(_Prepared(Path(path), test, manifest, ns, name=str(manifest["metadata"]["name"])))
    if wrong:
        raise BadInput(
            f"{len(wrong)} of {len(opts.tests)} test files are wrong (above); nothing was created",
            value=", ".join(wrong),
        )
    return prepared


def _report(
    p: _Prepared, status: Mapping[str, Any], opts: ClusterRunOptions, console: Console
) -> tuple[int, RunSummary | None, str]:
    """Say one final (or timed-out) test's results; its exit code, summary and (when not final) why."""
    if not is_final(status):  # only when --timeout ran out
        text = still_running_message(p.run or p.name, p.namespace, status, opts.timeout or 0.0)
        console.print(text, highlight=False, soft_wrap=True)
        return int(ExitCode.INFRASTRUCTURE), None, text
    console.print(results_table(p.name, status))
    console.print(status.get("message") or progress_text(status), highlight=False)
    summary_uri = (status.get("artifacts") or {}).get("summary")
    if summary_uri:
        console.print(f"summary: {summary_uri}", highlight=False)
    code = int(exit_code_for(status))
    download_error = None
    if opts.out is not None and code != ExitCode.BAD_INPUT:
        download_error = _download(status, p.name, p.namespace, opts.out, console)
    summary = _summary(status, p.name, p.namespace, opts.out, download_error is None and opts.out is not None)
    return with_download(code, download_error), summary, ""


def run_in_cluster(opts: ClusterRunOptions, *, console: Console | None = None) -> int:
    """Create each rendered test as a new UavTest; with ``wait``, follow them all and return one
    exit code (``uavtest.run_many.combined_exit``).

    Every file is read and checked by the API server (a dry run) before any is created: a wrong
    one exits 2 and nothing is created. ``--out`` is checked first too (exit 2 without the S3
    settings); a download that fails afterwards is said on stderr and makes a passing run exit 3 (a
    failing one stays 1). ``--timeout`` running out exits 3 and leaves the UavTests running.
    """
    import os

    from uavtest.controller.kube import api_client
    from uavtest.run_many import (
        TestOutcome,
        combined_exit,
        exit_meaning,
        json_report,
        junit_report,
        suite_table,
        write_junit,
    )

    console = console or Console(stderr=True)
    if opts.timeout is not None and not opts.timeout > 0:
        raise BadInput("must be positive", field="--timeout", value=opts.timeout, allowed="seconds > 0")
    if opts.out is not None and opts.wait:
        check_download_settings(os.environ)
    prepared = _prepare(opts, console)
    import kubernetes

    try:
        client = api_client()
    except (kubernetes.config.ConfigException, OSError) as e:
        raise InfrastructureError(f"no cluster to talk to (KUBECONFIG / in-cluster config): {e}") from None
    statuses: dict[str, dict[str, Any]] = {}
    with client:
        custom = kubernetes.client.CustomObjectsApi(client)
        if len(prepared) > 1:
            for p in prepared:
                _apply(custom, p.namespace, p.manifest, dry_run=True)
        for p in prepared:
            p.run = _apply(custom, p.namespace, p.manifest)
            spec = p.test.spec
            console.print(
                f"applied uavtest/{p.name} in namespace {p.namespace}, run uavtestrun/{p.run}: "
                f"{spec.replicas} replica(s), "
                f"seeds {spec.replica_seed(0)}..{spec.replica_seed(spec.replicas - 1)}",
                highlight=False,
            )
        if not opts.wait:
            return int(ExitCode.PASS)
        for ns in dict.fromkeys(p.namespace for p in prepared):
            wanted = [p.run for p in prepared if p.namespace == ns]
            statuses.update(_follow(custom, ns, wanted, console, timeout=opts.timeout))
    outcomes = []
    for p in prepared:
        code, summary, why = _report(p, statuses[p.run], opts, console)
        links = {}
        if summary is not None:
            links = replica_links(statuses[p.run], p.name, p.namespace, [r.index for r in summary.results])
        outcomes.append(TestOutcome(p.source, p.name, code, summary, why, p.namespace, links))
    if opts.junit is not None:
        write_junit(opts.junit, junit_report(outcomes), console)
    if opts.json_out:
        print(json_report(outcomes))
    code = combined_exit(o.code for o in outcomes)
    if len(outcomes) > 1:
        console.print(suite_table(outcomes))
        console.print(f"exit {int(code)}: {exit_meaning(code)}", highlight=False)
    return int(code)
