"""The uavtest commands the CI examples (examples/ci) run, as argument lists."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any

import yaml

__all__ = ["load", "option", "uavtest_commands"]


def load(path: Path) -> dict[str, Any]:
    doc = yaml.safe_load(path.read_text())
    assert isinstance(doc, dict), path
    return doc


def uavtest_commands(doc: dict[str, Any]) -> list[list[str]]:
    """Every ``uavtest ...`` line a GitHub workflow's ``run:`` or a GitLab job's ``script:`` runs."""
    lines: list[str] = []
    for job in (doc.get("jobs") or {}).values():  # GitHub Actions
        lines += [ln for step in job.get("steps", []) for ln in str(step.get("run", "")).splitlines()]
    for key, job in doc.items():  # GitLab CI
        if isinstance(job, dict) and not str(key).startswith(".") and "script" in job:
            lines += [str(ln) for ln in job["script"]]
    return [shlex.split(ln) for ln in lines if ln.strip().startswith("uavtest ")]


def option(argv: list[str], name: str) -> str:
    """The value after ``name`` in ``argv``."""
    return argv[argv.index(name) + 1]
