"""Speed of the local engine on the competition's mission2, next to PX4 SIH on this machine.

(a) real-time factor of one replica with the runner in the loop: simulated flight seconds per
    wall second, start-up of both processes included (``uavtest run --replicas 1``);
(b) throughput of ``uavtest run --replicas 40`` in flights per hour, J = number of cores;
(c) with ``--tests N``: throughput of one ``uavtest run FOLDER --replicas 1`` over N copies of the
    test under their own names (a generator's output flown once each), flights per hour.

PX4 v1.15 SIH on this 2-core machine (issue 3): at most ~18x real time (speed factor 20 uses
1.2 cores, higher factors fail), ~36 s of simulated boot, ~520 competition flights per hour.
Targets: (a) >= 50x, aim 300x; (b) >= 1,500 flights/h, aim 5,000.

With ``--avoidance none|local-planner|both`` the test is flown with that ``vehicle.avoidance``
(a rendered copy of it; ``both``: the whole bench twice, avoidance off then on). The competition's
files say ``simulator: ros``, which flies with the local planner; the issue keeps avoidance on
within 2x of off.

    python bench/bench_engine.py [--replicas 40] [--single-runs 3] [--jobs J] [--test FILE]
                                 [--launch fork|exec|both] [--skip-throughput]
                                 [--avoidance as-test|none|local-planner|both] [--tests N]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("UAVTEST_SHARED_DATA", REPO.parent / "shared" / "data"))
MISSION2 = SHARED / "competition" / "snippets" / "case_studies" / "mission2.yaml"

PX4_SIH_RTF = 18.0
PX4_SIH_FLIGHTS_PER_HOUR = 520.0


def uavtest_run(test: Path, out: Path, *args: str, launch: str = "fork") -> tuple[dict, float, int]:
    """Run ``uavtest run --json``; the summary, the wall seconds and the exit code."""
    cmd = [sys.executable, "-m", "uavtest.cli", "run", str(test), "--out", str(out), "--json", *args]
    env = {**os.environ, "UAVTEST_LAUNCH": launch}
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    wall = time.perf_counter() - start
    if proc.returncode not in (0, 1):
        sys.stderr.write(proc.stderr[-3000:])
        raise SystemExit(f"uavtest run exited {proc.returncode}: {' '.join(cmd)}")
    return json.loads(proc.stdout), wall, proc.returncode


def single_replica(test: Path, runs: int, launch: str) -> None:
    print(
        f"(a) one replica, runner in the loop, {test.name}, {runs} run(s) "
        "(a single replica's sitl and runner are always exec'd cold: start-up included)"
    )
    command_rtf, replica_rtf = [], []
    for k in range(runs):
        with tempfile.TemporaryDirectory(prefix="uavtest-bench-") as tmp:
            args = ("--replicas", "1", "--seed", str(k))
            summary, wall, _ = uavtest_run(test, Path(tmp), *args, launch=launch)
        result = summary["results"][0]
        sim = result.get("sim_time") or 0.0
        flight = (result.get("metrics") or {}).get("flight_time") or 0.0
        replica_wall = result.get("wall_time") or wall
        command_rtf.append(sim / wall)
        replica_rtf.append(sim / replica_wall)
        print(
            f"    run {k}: {result['verdict']}, simulated {sim:.1f} s (flight {flight:.1f} s), "
            f"replica wall {replica_wall:.2f} s, whole command {wall:.2f} s"
        )
    print(
        f"    real-time factor, replica (processes started -> verdict stored): "
        f"{statistics.median(replica_rtf):.0f}x   [target >= 50x, aim 300x; PX4 SIH <= {PX4_SIH_RTF:.0f}x]"
    )
    print(
        f"    real-time factor, whole `uavtest run` (+ CLI start, aggregation, plot): "
        f"{statistics.median(command_rtf):.0f}x"
    )


def throughput(test: Path, replicas: int, jobs: int | None, launch: str) -> None:
    extra = ["--jobs", str(jobs)] if jobs else []
    print(
        f"(b) uavtest run --replicas {replicas} {' '.join(extra)} on {test.name}, "
        f"{os.cpu_count()} cores, UAVTEST_LAUNCH={launch}"
    )
    with tempfile.TemporaryDirectory(prefix="uavtest-bench-") as tmp:
        summary, wall, code = uavtest_run(test, Path(tmp), "--replicas", str(replicas), *extra, launch=launch)
    sim = sum(r.get("sim_time") or 0.0 for r in summary["results"])
    per_hour = replicas / wall * 3600.0
    print(
        f"    {summary['passed']} passed, {summary['failed']} failed, {summary['errors']} error "
        f"(exit {code}) in {wall:.1f} s wall; {sim:.0f} simulated s in all ({sim / wall:.0f}x real time)"
    )
    print(
        f"    throughput: {per_hour:,.0f} flights/h   "
        f"[target >= 1,500, aim 5,000; PX4 SIH ~{PX4_SIH_FLIGHTS_PER_HOUR:,.0f}]"
    )


def several_tests(test: Path, count: int, launch: str) -> None:
    """(c): ``count`` copies of ``test``, each its own UavTest, flown once each by one command."""
    from uavtest.spec.loaders import load_test
    from uavtest.spec.render import render
    from uavtest.spec.yaml_io import dump_yaml

    print(f"(c) uavtest run FOLDER --replicas 1 over {count} copies of {test.name}, UAVTEST_LAUNCH={launch}")
    manifest = render(load_test(test))
    with tempfile.TemporaryDirectory(prefix="uavtest-bench-") as tmp:
        folder = Path(tmp) / "tests"
        folder.mkdir()
        for k in range(count):
            manifest["metadata"]["name"] = f"{test.stem}-{k:03d}"
            (folder / f"{test.stem}-{k:03d}.yaml").write_text(dump_yaml(manifest))
        summaries, wall, code = uavtest_run(folder, Path(tmp) / "out", "--replicas", "1", launch=launch)
    results = [r for summary in summaries for r in summary["results"]]
    passed = sum(r["verdict"] == "pass" for r in results)
    print(f"    {passed} of {len(results)} passed (exit {code}) in {wall:.1f} s wall")
    print(f"    throughput: {len(results) / wall * 3600.0:,.0f} flights/h")


def with_avoidance(test: Path, avoidance: str, folder: Path) -> Path:
    """A self-contained copy of ``test`` (``uavtest render``) flown with ``avoidance``."""
    from uavtest.spec.loaders import load_test
    from uavtest.spec.render import render
    from uavtest.spec.yaml_io import dump_yaml

    manifest = render(load_test(test))
    manifest["spec"].setdefault("vehicle", {})["avoidance"] = avoidance
    out = folder / f"{test.stem}-{avoidance}.yaml"
    out.write_text(dump_yaml(manifest))
    return out


def main() -> None:
    formatter = argparse.RawDescriptionHelpFormatter
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=formatter)
    parser.add_argument("--test", type=Path, default=MISSION2)
    parser.add_argument("--replicas", type=int, default=40)
    parser.add_argument("--single-runs", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=None)
    parser.add_argument("--skip-throughput", action="store_true")
    parser.add_argument("--tests", type=int, default=0, help="(c): one-replica tests in one command")
    parser.add_argument(
        "--launch", choices=["fork", "exec", "both"], default="both", help="how replica processes start"
    )
    parser.add_argument(
        "--avoidance",
        choices=["as-test", "none", "local-planner", "both"],
        default="as-test",
        help="vehicle.avoidance to fly the test with (both: avoidance off, then on)",
    )
    args = parser.parse_args()
    if not args.test.is_file():
        raise SystemExit(f"{args.test} not found (set UAVTEST_SHARED_DATA to the real data folder)")
    launches = ["fork", "exec"] if args.launch == "both" else [args.launch]
    print(f"load average before: {' '.join(f'{x:.1f}' for x in os.getloadavg())} (other work on the machine)")
    modes = ["none", "local-planner"] if args.avoidance == "both" else [args.avoidance]
    with tempfile.TemporaryDirectory(prefix="uavtest-bench-tests-") as folder:
        for mode in modes:
            test = args.test if mode == "as-test" else with_avoidance(args.test, mode, Path(folder))
            if mode != "as-test":
                print(f"== vehicle.avoidance: {mode}")
            single_replica(test, args.single_runs, "exec")
            if not args.skip_throughput:
                for launch in launches:
                    throughput(test, args.replicas, args.jobs, launch)
            if args.tests > 0:
                for launch in launches:
                    several_tests(test, args.tests, launch)


if __name__ == "__main__":
    main()
