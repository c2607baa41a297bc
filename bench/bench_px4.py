"""PX4 SITL (SIH) and the built-in simulator side by side: one test, the same replicas, one sitting.

The test (default: the competition's mission2) is rendered as a UavTest twice — ``simulator:
builtin`` and ``simulator: px4`` (optionally with ``speedFactor``) — and flown with ``uavtest run
--replicas N --jobs J`` by each, one after the other. For each: verdicts, wall time, flights per
hour (N / wall), and real-time factors — the run's (simulated flight seconds of all replicas per
wall second) and one replica's (median of its flight seconds per its wall seconds, start-up
included) — then the built-in simulator's advantage as ratios. PX4 comes from UAVTEST_PX4_BIN
(or --px4-bin); its speed factor is the test's, else the engine's default for J at a time.

    UAVTEST_PX4_BIN=.../build/px4_sitl_default/bin/px4 \\
        python bench/bench_px4.py [--replicas 4] [--jobs 2] [--speed-factor X] [--test FILE] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from rich.console import Console
from rich.table import Table

REPO = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("UAVTEST_SHARED_DATA", REPO.parent / "shared" / "data"))
MISSION2 = SHARED / "competition" / "snippets" / "case_studies" / "mission2.yaml"
PACE = re.compile(r"PX4 at (\S+)x real time \(([^)]*)\)")


@dataclass
class Flown:
    """One ``uavtest run`` of the benchmark."""

    label: str
    replicas: int
    wall: float
    passed: int
    failed: int
    errors: int
    sim_total: float
    replica_rtf: float
    pace: str = "lockstep"
    reasons: tuple[str, ...] = ()

    @property
    def flights_per_hour(self) -> float:
        return self.replicas / self.wall * 3600.0

    @property
    def run_rtf(self) -> float:
        return self.sim_total / self.wall


def render_as(test: Path, into: Path, simulator: str, speed_factor: float | None) -> Path:
    """``test`` as a self-contained UavTest for ``simulator`` (``uavtest render``, then edited)."""
    cmd = [sys.executable, "-m", "uavtest.cli", "render", str(test)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise SystemExit(f"uavtest render {test} exited {proc.returncode}: {proc.stderr[-2000:]}")
    manifest: dict[str, Any] = yaml.safe_load(proc.stdout)
    vehicle = manifest["spec"].setdefault("vehicle", {})
    vehicle["simulator"] = simulator
    if simulator == "px4" and speed_factor is not None:
        vehicle["speedFactor"] = speed_factor
    into.write_text(yaml.safe_dump(manifest, sort_keys=False))
    return into


def fly(label: str, test: Path, replicas: int, jobs: int, env: dict[str, str], keep: Path | None) -> Flown:
    with tempfile.TemporaryDirectory(prefix="uavtest-bench-px4-") as tmp:
        out = str(keep) if keep is not None else tmp
        cmd = [sys.executable, "-m", "uavtest.cli", "run", str(test), "--out", out, "--json"]
        cmd += ["--replicas", str(replicas), "--jobs", str(jobs)]
        start = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
        wall = time.perf_counter() - start
    if proc.returncode not in (0, 1, 3):
        sys.stderr.write(proc.stderr[-3000:])
        raise SystemExit(f"uavtest run exited {proc.returncode}: {' '.join(cmd)}")
    summary = json.loads(proc.stdout)
    results = summary["results"]
    timed = [r for r in results if r.get("wall_time") and r.get("sim_time")]
    per_replica = [r["sim_time"] / r["wall_time"] for r in timed]
    pace = PACE.search(" ".join(proc.stderr.split()))
    return Flown(
        label=label,
        replicas=replicas,
        wall=wall,
        passed=summary["passed"],
        failed=summary["failed"],
        errors=summary["errors"],
        sim_total=sum(r.get("sim_time") or 0.0 for r in results),
        replica_rtf=statistics.median(per_replica) if per_replica else 0.0,
        pace=f"{pace.group(1)}x ({pace.group(2)})" if pace else "lockstep",
        reasons=tuple(r["reason"] for r in results if r.get("reason")),
    )


def table(runs: list[Flown], title: str) -> Table:
    out = Table(title=title)
    for name, justify in [
        ("simulator", "left"),
        ("pace", "left"),
        ("pass / fail / error", "center"),
        ("wall s", "right"),
        ("flights/h", "right"),
        ("run RTF", "right"),
        ("replica RTF", "right"),
    ]:
        out.add_column(name, justify=justify)  # type: ignore[arg-type]
    for r in runs:
        out.add_row(
            r.label,
            r.pace,
            f"{r.passed} / {r.failed} / {r.errors}",
            f"{r.wall:.1f}",
            f"{r.flights_per_hour:,.0f}",
            f"{r.run_rtf:.1f}x",
            f"{r.replica_rtf:.1f}x",
        )
    if len(runs) == 2 and all(r.wall > 0 and r.sim_total > 0 and r.replica_rtf > 0 for r in runs):
        builtin, px4 = runs
        out.add_section()
        out.add_row(
            "built-in / PX4",
            "",
            "",
            f"{px4.wall / builtin.wall:.1f}x less",
            f"{builtin.flights_per_hour / px4.flights_per_hour:.1f}x",
            f"{builtin.run_rtf / px4.run_rtf:.1f}x",
            f"{builtin.replica_rtf / px4.replica_rtf:.1f}x",
        )
    return out


def main() -> None:
    formatter = argparse.RawDescriptionHelpFormatter
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=formatter)
    parser.add_argument("--test", type=Path, default=MISSION2, help="UavTest, Aerialist or competition test")
    parser.add_argument("--replicas", type=int, default=4, help="replicas per simulator")
    parser.add_argument("--jobs", type=int, default=2, help="replicas at once")
    parser.add_argument("--speed-factor", type=float, default=None, help="PX4's; default: the engine's")
    parser.add_argument("--px4-bin", type=Path, default=os.environ.get("UAVTEST_PX4_BIN"))
    parser.add_argument("--keep", type=Path, default=None, help="keep the runs' artifacts in this folder")
    args = parser.parse_args()
    if not args.test.is_file():
        raise SystemExit(f"{args.test} not found (set UAVTEST_SHARED_DATA to the real data folder)")
    if args.px4_bin is None or not Path(args.px4_bin).is_file():
        raise SystemExit("set UAVTEST_PX4_BIN (or --px4-bin) to PX4's build/px4_sitl_default/bin/px4")
    console = Console()
    env = {**os.environ, "UAVTEST_PX4_BIN": str(Path(args.px4_bin).resolve())}
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="uavtest-bench-px4-tests-") as tmp:
        builtin = render_as(args.test, Path(tmp) / "builtin.yaml", "builtin", None)
        px4 = render_as(args.test, Path(tmp) / "px4.yaml", "px4", args.speed_factor)
        runs = []
        for label, test in [("built-in (lockstep)", builtin), ("PX4 SITL (SIH)", px4)]:
            what = f"{args.replicas} replicas of {args.test.name}, {args.jobs} at a time"
            console.print(f"flying {what}: {label}")
            runs.append(fly(label, test, args.replicas, args.jobs, env, args.keep))
    load_after = os.getloadavg()
    title = (
        f"{args.test.name}: {args.replicas} replicas, {args.jobs} at a time, {os.cpu_count()} cores "
        f"(load average {load_before[0]:.1f} before, {load_after[0]:.1f} after)"
    )
    console.print(table(runs, title))
    for r in runs:
        for reason in dict.fromkeys(r.reasons):
            console.print(f"[yellow]{r.label}:[/] {reason}", highlight=False)


if __name__ == "__main__":
    main()
