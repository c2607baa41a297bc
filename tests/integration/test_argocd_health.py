"""The chart's Argo CD health check (charts/uavtest/files/argocd/health.lua) run by a real Lua.

Argo CD runs the script with the object as the global ``obj`` and reads the table it returns.
Here a real Lua interpreter does the same (Debian's lua5.4, unpacked into the cluster cache with
apt-get download + dpkg-deb -x, never installed; the script keeps to Lua 5.1, which Argo CD's
gopher-lua speaks) on objects the operator's own status builders produce.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.controller.runs import test_status_from
from uavtest.controller.status import status_from
from uavtest.controller.views import run_view, test_view

pytestmark = pytest.mark.integration

SCRIPT = Path(__file__).resolve().parents[2] / "charts" / "uavtest" / "files" / "argocd" / "health.lua"
CACHE = Path(os.environ.get("UAVTEST_CACHE") or Path.home() / ".cache" / "uavtest")
LUA_DIR = CACHE / "deb" / "lua"


def lua_command() -> tuple[list[str], dict[str, str]]:
    """A Lua interpreter: one on PATH, else Debian's lua5.4 unpacked into the cache (fetched once)."""
    for name in ("lua5.1", "lua5.4", "lua"):
        if found := shutil.which(name):
            return [found], dict(os.environ)
    x = LUA_DIR / "x"
    binary = x / "usr" / "bin" / "lua5.4"
    if not binary.is_file():
        LUA_DIR.mkdir(parents=True, exist_ok=True)
        got = subprocess.run(
            ["apt-get", "download", "lua5.4", "liblua5.4-0"], cwd=LUA_DIR, capture_output=True, text=True
        )
        debs = sorted(LUA_DIR.glob("*.deb"))
        if got.returncode != 0 or not debs:
            pytest.skip(f"no Lua interpreter and apt-get download failed: {got.stderr[-500:]}")
        for deb in debs:
            subprocess.run(["dpkg-deb", "-x", str(deb), str(x)], check=True)
    env = {**os.environ, "LD_LIBRARY_PATH": str(x / "usr" / "lib" / "x86_64-linux-gnu")}
    return [str(binary)], env


def lua_literal(value: Any) -> str:
    if value is None:
        return "nil"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(value, list):
        return "{" + ", ".join(lua_literal(v) for v in value) + "}"
    return "{" + ", ".join(f"[{lua_literal(str(k))}] = {lua_literal(v)}" for k, v in value.items()) + "}"


def health(obj: dict[str, Any]) -> tuple[str, str]:
    """(status, message) the script returns for ``obj``, as Argo CD would call it."""
    cmd, env = lua_command()
    driver = (
        f"obj = {lua_literal(obj)}\n"
        f"local check = assert(loadfile({lua_literal(str(SCRIPT))}))\n"
        "local hs = check()\n"
        "io.write(hs.status, '\\n', hs.message or '')\n"
    )
    done = subprocess.run([*cmd, "-"], input=driver, capture_output=True, text=True, env=env, timeout=30)
    assert done.returncode == 0, done.stderr
    status, _, message = done.stdout.partition("\n")
    return status, message


def run_body(name: str = "hover-g1", created: str = "2026-03-01T10:00:00Z") -> dict[str, Any]:
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTestRun",
        "metadata": {
            "name": name,
            "namespace": "ci",
            "uid": "5f0c3a9e-1",
            "generation": 1,
            "creationTimestamp": created,
        },
        "spec": {"testName": "hover", "testSpec": {"replicas": 2}},
        "status": {},
    }


def finished(body: dict[str, Any], *verdicts: Verdict) -> dict[str, Any]:
    results = [
        ReplicaResult(index=i, seed=i, verdict=v, metrics=FlightMetrics(min_obstacle_distance=2.0))
        for i, v in enumerate(verdicts)
    ]
    summary = summarize(results, test="hover", namespace="ci", run_id="5f0c3a9e")
    st = status_from(run_view(body), None, [], store_url="s3://b", summary=summary)
    return {**body, "status": st.dump()}


def flying(body: dict[str, Any]) -> dict[str, Any]:
    st = status_from(run_view(body), None, [], store_url="s3://b")
    return {**body, "status": st.dump()}


def test_a_run_is_healthy_when_passed_progressing_while_flying_degraded_when_failed() -> None:
    assert health(run_body())[0] == "Progressing"  # no status yet
    assert health(flying(run_body()))[0] == "Progressing"
    assert health(finished(run_body(), Verdict.PASS, Verdict.PASS))[0] == "Healthy"
    status, message = health(finished(run_body(), Verdict.PASS, Verdict.FAIL))
    assert status == "Degraded" and "1 failed" in message


def test_a_test_follows_its_newest_run_and_waits_for_a_new_spec() -> None:
    def test_obj(generation: int, *runs: dict[str, Any]) -> dict[str, Any]:
        body = {
            "apiVersion": "uavtest.io/v1alpha1",
            "kind": "UavTest",
            "metadata": {"name": "hover", "namespace": "ci", "generation": generation},
            "spec": {"replicas": 2},
            "status": {"observedGeneration": 1},
        }
        st = test_status_from(test_view(body), [run_view(r) for r in runs])
        return {**body, "status": st.dump()}

    passed = finished(run_body(), Verdict.PASS)
    failed = finished(run_body("hover-s1", "2026-03-01T11:00:00Z"), Verdict.FAIL)
    assert health(test_obj(1, passed))[0] == "Healthy"
    assert health(test_obj(1, passed, failed))[0] == "Degraded"
    assert health(test_obj(1, passed, failed, flying(run_body("hover-s2", "2026-03-01T12:00:00Z"))))[0] == (
        "Progressing"
    )
    assert health(test_obj(2, passed))[0] == "Progressing"  # generation 2 not started yet
