"""``uavtest run TEST --engine kubernetes``: create the test in a cluster, follow its status, exit.

Each call is a new run: the rendered test is created with ``generateName`` (a UavTest's spec is
immutable; one object is one run). Progress comes from watching the object's status, and the exit
code is the local engine's: 0 every replica passed, 1 some replica failed, 2 bad input (also a
test the API server rejects), 3 bench errors only, or the cluster could not be used.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from uavtest.controller import names
from uavtest.controller.status import is_final
from uavtest.errors import BadInput, ExitCode, InfrastructureError

__all__ = ["exit_code_for", "progress_text", "results_table", "run_in_cluster"]

_WATCH_SECONDS = 60


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
        ("min distance", "right"),
    ):
        table.add_column(col, justify=justify)  # type: ignore[arg-type]
    table.add_column("reason", overflow="fold")
    style = {"pass": "green", "fail": "red", "error": "yellow"}
    for r in sorted(status.get("results") or [], key=lambda r: r["index"]):
        dist = r.get("minDistance")
        table.add_row(
            str(r["index"]),
            str(r["seed"]),
            f"[{style.get(r['verdict'], '')}]{r['verdict']}[/]",
            "-" if dist is None else f"{dist:.2f} m",
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


def _create(custom: Any, namespace: str, manifest: dict[str, Any]) -> str:
    from kubernetes.client.exceptions import ApiException

    try:
        created = custom.create_namespaced_custom_object(
            names.API_GROUP, names.VERSION, namespace, names.PLURAL, manifest
        )
    except ApiException as e:
        if e.status in (400, 422):
            raise BadInput(f"the cluster rejected the test: {_api_message(e)}") from None
        if e.status == 404:
            raise InfrastructureError(
                f"no UavTest API in the cluster (or no namespace {namespace}): install the CRD "
                "(kubectl apply -f crds/) or the Helm chart"
            ) from None
        raise InfrastructureError(f"creating the UavTest failed: {_api_message(e)}") from None
    return str(created["metadata"]["name"])


def _api_message(e: Any) -> str:
    import json

    try:
        return str(json.loads(e.body).get("message") or e.reason)
    except (TypeError, ValueError):
        return str(e.reason)


def _follow(custom: Any, namespace: str, name: str, console: Console) -> dict[str, Any]:
    """Watch the UavTest until its status is final; show progress meanwhile; return the status."""
    import kubernetes
    from kubernetes.client.exceptions import ApiException
    from urllib3.exceptions import HTTPError

    status: dict[str, Any] = {}
    columns = (
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[line]}"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=console, transient=False) as progress:
        task = progress.add_task(name, total=None, line="Pending")
        resource_version = None
        failures = 0
        while not is_final(status):
            watch = kubernetes.watch.Watch()
            try:
                for event in watch.stream(
                    custom.list_namespaced_custom_object,
                    names.API_GROUP,
                    names.VERSION,
                    namespace,
                    names.PLURAL,
                    field_selector=f"metadata.name={name}",
                    resource_version=resource_version,
                    timeout_seconds=_WATCH_SECONDS,
                ):
                    obj = event["object"]
                    if event["type"] == "DELETED":
                        raise InfrastructureError(f"uavtest/{name} was deleted before it finished")
                    if event["type"] == "ERROR":
                        resource_version = None
                        break
                    resource_version = obj["metadata"].get("resourceVersion")
                    status = obj.get("status") or {}
                    done = sum(int(status.get(k) or 0) for k in ("passed", "failed", "errors"))
                    progress.update(
                        task, total=status.get("replicas") or None, completed=done, line=progress_text(status)
                    )
                    failures = 0
                    if is_final(status):
                        break
            except ApiException as e:
                if e.status == 410:  # resourceVersion too old: list again
                    resource_version = None
                    continue
                raise InfrastructureError(f"watching uavtest/{name} failed: {_api_message(e)}") from None
            except HTTPError as e:
                failures += 1
                if failures > 5:
                    raise InfrastructureError(
                        f"lost the cluster while watching uavtest/{name}: {e}"
                    ) from None
                time.sleep(min(2.0**failures, 30.0))  # back off before reconnecting the watch
            finally:
                watch.stop()
    return status


def run_in_cluster(
    test_path: Path, namespace: str | None = None, wait: bool = True, *, console: Console | None = None
) -> int:
    """Create the rendered test as a new UavTest; with ``wait``, follow it and return its exit code."""
    from uavtest.controller.kube import api_client
    from uavtest.spec.loaders import load_test
    from uavtest.spec.render import render

    console = console or Console(stderr=True)
    manifest = render(load_test(Path(test_path)))
    ns = _namespace(manifest, namespace)
    meta = manifest["metadata"]
    base = str(meta.pop("name"))
    meta["generateName"] = f"{base[:52]}-"
    meta["namespace"] = ns
    import kubernetes

    try:
        client = api_client()
    except (kubernetes.config.ConfigException, OSError) as e:
        raise InfrastructureError(f"no cluster to talk to (KUBECONFIG / in-cluster config): {e}") from None
    with client:
        custom = kubernetes.client.CustomObjectsApi(client)
        name = _create(custom, ns, manifest)
        console.print(f"created uavtest/{name} in namespace {ns}")
        if not wait:
            return int(ExitCode.PASS)
        status = _follow(custom, ns, name, console)
    console.print(results_table(name, status))
    console.print(status.get("message") or progress_text(status))
    summary = (status.get("artifacts") or {}).get("summary")
    if summary:
        console.print(f"summary: {summary}")
    return int(exit_code_for(status))
