"""Benchmarks of uavtest.analysis (issue 2): prints numbers, asserts nothing.

  python bench/bench_analysis.py [--data ../shared/data]

(a) trajectory extraction from the largest .ulg in the shared data (target < 1 s);
(b) averaging 100 synthetic 5-minute trajectories at 10–50 Hz, of different lengths (target < 2 s);
(c) DTW and discrete Fréchet between two 5-minute trajectories (at the 2 Hz the analysis uses,
    and at 10 Hz for scale).
Each figure is the best of ``--repeat`` runs (default 3), wall clock.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from uavtest.analysis.average import average_trajectories
from uavtest.analysis.similarity import dtw, frechet
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import VERDICT_TOPICS, read_ulog, trajectory_from_ulog

REPO = Path(__file__).resolve().parent.parent


def best_of(repeat: int, fn: Callable[[], Any]) -> tuple[float, Any]:
    best, result = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def synthetic_flight(rng: np.random.Generator, duration: float, rate: float) -> Trajectory:
    """A wandering 3-D flight: takeoff, a random smooth path at 5–15 m, landing."""
    t = np.arange(0.0, duration, 1.0 / rate)
    knots = np.linspace(0.0, duration, 12)
    x = np.interp(t, knots, np.cumsum(rng.normal(0, 20, knots.size)))
    y = np.interp(t, knots, np.cumsum(rng.normal(0, 20, knots.size)))
    alt = np.interp(t, knots, np.r_[0, rng.uniform(5, 15, knots.size - 2), 0])
    noise = rng.normal(0, 0.05, (3, t.size))
    return Trajectory(t, x + noise[0], y + noise[1], -alt + noise[2], np.zeros_like(t))


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    default_data = Path(os.environ.get("UAVTEST_SHARED_DATA", REPO.parent / "shared" / "data"))
    parser.add_argument("--data", type=Path, default=default_data)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    # (a) ------------------------------------------------------------------ extraction
    logs = sorted(args.data.rglob("*.ulg"), key=lambda p: p.stat().st_size)
    if logs:
        largest = logs[-1]
        size = largest.stat().st_size / 1e6
        full, tr = best_of(args.repeat, lambda: trajectory_from_ulog(read_ulog(largest)))
        some, _ = best_of(args.repeat, lambda: trajectory_from_ulog(read_ulog(largest, VERDICT_TOPICS)))
        print(f"(a) extraction, largest log {largest.name} ({size:.1f} MB, {len(tr)} flight samples):")
        print(
            f"    all topics + cut: {full:.3f} s   the verdict's topics + cut: {some:.3f} s   (target < 1 s)"
        )
    else:
        print(f"(a) skipped: no .ulg under {args.data}")

    # (b) ------------------------------------------------------------------ averaging
    rng = np.random.default_rng(2)
    flights = [
        synthetic_flight(rng, rng.uniform(270, 330), rng.choice([10.0, 25.0, 50.0])) for _ in range(100)
    ]
    samples = sum(len(f) for f in flights)
    avg_time, avg = best_of(args.repeat, lambda: average_trajectories(flights))
    csv_time, _ = best_of(args.repeat, avg.to_csv)
    print(f"(b) averaging 100 flights of 270–330 s at 10/25/50 Hz ({samples} samples): {avg_time:.3f} s")
    print(f"    (+ average.csv {csv_time:.3f} s)   target < 2 s")

    # (c) ------------------------------------------------------------------ similarity
    a, b = synthetic_flight(rng, 300.0, 50.0), synthetic_flight(rng, 290.0, 50.0)
    for rate in (2.0, 10.0):
        n = int(300 * rate)
        d_time, d = best_of(args.repeat, lambda rate=rate: dtw(a, b, rate=rate))
        f_time, f = best_of(args.repeat, lambda rate=rate: frechet(a, b, rate=rate))
        print(
            f"(c) two 5-minute flights at {rate:g} Hz (~{n} points each): "
            f"DTW {d_time:.3f} s ({d.per_step:.1f} m/step), Fréchet {f_time:.3f} s ({f:.1f} m)"
        )


if __name__ == "__main__":
    main()
