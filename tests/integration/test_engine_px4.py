"""``uavtest run`` with ``vehicle.simulator: px4``: real PX4 SITL from UAVTEST_PX4_BIN (else skipped)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = [pytest.mark.integration, pytest.mark.px4, pytest.mark.slow]


@pytest.fixture
def px4_bin() -> Path:
    value = os.environ.get("UAVTEST_PX4_BIN")
    if not value or not Path(value).is_file():
        pytest.skip("UAVTEST_PX4_BIN does not name a PX4 SITL binary")
    return Path(value)


def test_two_px4_replicas_fly_on_their_own_instances(px4_bin: Path, repo_root: Path, tmp_path: Path) -> None:
    test = tmp_path / "hover-px4.yaml"
    text = (repo_root / "examples/hover.yaml").read_text()
    text = text.replace("  vehicle:\n", "  vehicle:\n    simulator: px4\n")
    text = text.replace("timeout: 120", "timeout: 300")  # PX4 flies in real time and boots ~36 s
    test.write_text(text)
    cmd = [sys.executable, "-m", "uavtest.cli", "run", str(test), "--replicas", "2", "--jobs", "2"]
    cmd += ["--out", str(tmp_path / "runs"), "--json"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=1800, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert summary["passed"] == 2
    for r in summary["results"]:
        assert 4.0 < r["metrics"]["max_altitude"] < 6.5
