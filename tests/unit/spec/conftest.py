"""Fixtures of the spec tests: the real ``uavtest`` command line and small native test files."""

from __future__ import annotations

import copy
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from uavtest.spec.yaml_io import dump_yaml

CliRun = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def cli() -> CliRun:
    """Run ``uavtest ARGS...`` as a user does (a real process through ``uavtest.cli.main``)."""

    def run(*args: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-c", "from uavtest.cli import main; main()", *map(str, args)],
            capture_output=True,
            text=True,
            timeout=120,
            cwd=cwd,
        )

    return run


@pytest.fixture
def uavtest(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> CliRun:
    """Run ``uavtest ARGS...`` in this process through the real ``uavtest.cli.main`` boundary (fast)."""
    from uavtest.cli import main

    def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
        capsys.readouterr()
        monkeypatch.setattr(sys, "argv", ["uavtest", *map(str, args)])
        code: int | str | None = 0
        try:
            main()
        except SystemExit as e:
            code = e.code
        out, err = capsys.readouterr()
        return subprocess.CompletedProcess(["uavtest", *map(str, args)], int(code or 0), out, err)

    return run


def _native(spec: dict[str, Any], name: str = "hover") -> dict[str, Any]:
    return {"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest", "metadata": {"name": name}, "spec": spec}


@pytest.fixture
def native() -> Callable[..., dict[str, Any]]:
    """``native(spec, name="hover")``: a native UavTest document around ``spec``."""
    return _native


@pytest.fixture
def write(tmp_path: Path) -> Callable[..., Path]:
    """Write a file under tmp_path: a dict becomes YAML, a string is written as is."""

    def _write(relative: str, content: dict[str, Any] | str) -> Path:
        path = tmp_path / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(dump_yaml(content) if isinstance(content, dict) else content)
        return path

    return _write


_SQUARE_PLAN: dict[str, Any] = {
    "fileType": "Plan",
    "version": 1,
    "mission": {
        "version": 2,
        "plannedHomePosition": [47.3977419, 8.5455938, 488.0],
        "items": [
            {
                "type": "SimpleItem",
                "command": 530,
                "frame": 2,
                "params": [0, 2, None, None, None, None, None],
            },
            {
                "type": "SimpleItem",
                "command": 22,
                "frame": 3,
                "params": [0, 0, 0, None, 47.3977419, 8.5455938, 10],
            },
            {
                "type": "SimpleItem",
                "command": 16,
                "frame": 3,
                "params": [2, 0, 0, None, 47.3980, 8.5455938, 10],
            },
            {"type": "SimpleItem", "command": 178, "frame": 2, "params": [1, 4.5, -1, 0, 0, 0, 0]},
            {"type": "SimpleItem", "command": 19, "frame": 3, "params": [5, 0, 0, 0, 47.3980, 8.5460, 12]},
            {"type": "SimpleItem", "command": 20, "frame": 2, "params": [0, 0, 0, 0, 0, 0, 0]},
        ],
    },
}


@pytest.fixture
def square_plan() -> dict[str, Any]:
    """A QGC plan: 530 (ignored), takeoff 10 m, waypoint (hold 2 s), speed 4.5, loiter 5 s at 12 m, RTL."""
    return copy.deepcopy(_SQUARE_PLAN)
