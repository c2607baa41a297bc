"""How much vehicle time the runner grants a lockstep simulator at once (pure).

Every grant is one UDP round trip, the main cost of a lockstep flight, so grants are large while
nothing is going on and small only where the runner must act on time. The size depends only on
the test's script and on what the vehicle reported — never on the wall clock — so the same seed
flies the same trajectory:

- ``max_ms`` (``--step-ms``, default ``DEFAULT_STEP_MS``) while the flight just goes on;
- ``FINE_MS`` while a command sequence runs (a step waits for its ACK, more steps are queued):
  each step goes out one fine grant after the previous one was answered;
- ``STICKS_MS`` while sticks are streamed (MANUAL_CONTROL at >= 10 Hz of vehicle time, as PX4's
  RC-loss check expects);
- ``NEAR_MS`` while the vehicle is within ``NEAR_M`` of an obstacle, so a collision the monitor
  sees is acted on (force disarm) within about one telemetry period;
- and a grant always ends exactly at the next event: a command's time, a refused arm's retry,
  the flight timeout, the next GCS heartbeat (so they go out once per vehicle second and the
  grants line up on whole seconds after the first).
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_STEP_MS", "FINE_MS", "NEAR_M", "NEAR_MS", "STICKS_MS", "grant_until"]

DEFAULT_STEP_MS = 1000
FINE_MS = 50
STICKS_MS = 100
NEAR_MS = 100
NEAR_M = 10.0


def grant_until(
    seen_ms: int,
    *,
    max_ms: int,
    busy: bool = False,
    sticks: bool = False,
    obstacle_distance: float = math.inf,
    next_event_ms: float = math.inf,
) -> int:
    """The vehicle time (ms) to grant up to, from ``seen_ms`` (the time the simulator waits at)."""
    step = max(1, max_ms)
    if busy:
        step = min(step, FINE_MS)
    if sticks:
        step = min(step, STICKS_MS)
    if obstacle_distance < NEAR_M:
        step = min(step, NEAR_MS)
    if seen_ms < next_event_ms < seen_ms + step:
        step = max(1, math.ceil(next_event_ms - seen_ms))
    return seen_ms + step
