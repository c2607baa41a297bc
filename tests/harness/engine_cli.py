"""Run ``uavtest run`` as a real subprocess and read its JSON summary (integration tests)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["RunOutput", "uavtest_run"]


@dataclass
class RunOutput:
    code: int
    summary: dict[str, Any] | None
    stdout: str
    stderr: str

    @property
    def by_index(self) -> dict[int, dict[str, Any]]:
        assert self.summary is not None, self.stderr[-3000:]
        return {r["index"]: r for r in self.summary["results"]}


def uavtest_run(test: Path, out: Path, *args: str, json_out: bool = True, timeout: float = 900) -> RunOutput:
    cmd = [sys.executable, "-m", "uavtest.cli", "run", str(test), "--out", str(out), *args]
    if json_out:
        cmd.append("--json")
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    summary = None
    if json_out and proc.stdout.strip().startswith("{"):
        summary = json.loads(proc.stdout)
    return RunOutput(proc.returncode, summary, proc.stdout, proc.stderr)
