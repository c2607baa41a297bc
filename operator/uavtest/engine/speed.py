"""How fast PX4 SITL runs: ``vehicle.speedFactor`` as ``PX4_SIM_SPEED_FACTOR``, and its default.

PX4 SITL free-runs: its clock goes ``PX4_SIM_SPEED_FACTOR`` times the wall clock (PX4's rcS also
stretches its link-loss timeouts by that factor). Every replica then needs that much CPU, all the
time; when it cannot get it, PX4's estimator and controllers miss their deadlines and flights
end ``error`` or fail. So the default is the fastest that was reliable on a measured machine,
scaled by the CPU one replica gets (cores / replicas flown at once):

    default = clamp(floor(SPEED_PER_CORE * cores / at_once), 1, DEFAULT_SPEED_MAX)

A replica is two processes: PX4 and the runner, which must read PX4's telemetry as fast as PX4
sends it (the mission upload and the range sensor's scans have deadlines on PX4's clock). Measured
on a 2-core machine, one replica of ``examples/collision-prevention.yaml`` (stop 47): PX4 SIH took
0.95 cores at 10x, 1.2-1.45 at 15x, 1.6-1.9 at 20x (about 0.09 core per unit of speed), the runner
0.2-0.27 cores besides. At 20x the two wanted more than the machine had: the runner fell 7-43 s of
vehicle time behind PX4 and connected ~22 s of wall time late, and one flight of three ended
``fail`` with PX4 refusing mode mission; at 15x 5 of 5 passed (two with the runner 2.1 s behind
once), at 10x 2 of 2 with no lag. Hence ``SPEED_PER_CORE`` = 7.5 (a replica's PX4 and runner in
~0.9 of its share). The earlier value, 10, came from 4 replicas 2 at a time with factor 10: 4/4
passed, but that is 1.15 cores of demand per core. ``DEFAULT_SPEED_MAX`` = 20 because a single
PX4 SIH reached at most ~18x real time there, whatever the factor asked.

The built-in simulator runs in lockstep, as fast as the runner grants time: a speed factor means
nothing to it, and is ignored with a warning (``speed_factor_notice``).

Wall-clock budgets (``wall_timeout``) are derived from vehicle seconds (``spec.timeout``) and the
speed factor, with room for PX4 falling behind the factor when the machine is busy.
"""

from __future__ import annotations

import math
import os

from uavtest.spec.collision_prevention import range_sensor_of
from uavtest.spec.models import Simulator, UavTestSpec

__all__ = [
    "DEFAULT_SPEED_MAX",
    "PX4_BOOT_S",
    "SCAN_SPEED_MAX",
    "SPEED_PER_CORE",
    "available_cores",
    "default_speed_factor",
    "px4_speed_choice",
    "px4_speed_env",
    "px4_speed_factor",
    "speed_factor_notice",
    "speed_factor_source",
    "wall_timeout",
]

SPEED_PER_CORE = 7.5  # PX4 SIH speed factor per core a replica (PX4 + runner) gets (measured, see above)
DEFAULT_SPEED_MAX = 20.0  # a single PX4 SIH did not run faster than ~18x on the measured machine
#: the default's cap when the runner feeds PX4 a range sensor's scans: PX4's Collision Prevention
#: drops a scan older than 0.5 s of its clock (RANGE_STREAM_TIMEOUT_US), so the runner must be
#: scheduled within 500 ms / factor of wall time, every time. Measured on 2 cores
#: (``examples/collision-prevention.yaml``, stop 47): at 15x the runner was descheduled long enough
#: for 0.6-0.8 s of PX4's clock (40-53 ms), PX4 stopped short on missing data where the built-in
#: vehicle's replay of its inputs flew on; at 10x 2 of 2 without such a gap.
SCAN_SPEED_MAX = 10.0
PX4_BOOT_S = 60.0  # vehicle seconds before PX4 flies: ~36 s to ready-to-arm, 10 s arm settle, margin
PX4_SLOWDOWN = 2.0  # PX4 may reach only half its speed factor on a busy machine
START_S = 120.0  # wall seconds for start-up, aggregation of a replica's log, stopping
BUILTIN_START_S = 120.0


def available_cores() -> int:
    """CPUs this process may run on (its affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def default_speed_factor(cores: int, at_once: int) -> float:
    """The default PX4 speed factor for ``at_once`` replicas sharing ``cores`` CPUs. Pure."""
    if cores < 1 or at_once < 1:
        raise ValueError(f"cores and replicas at once must be >= 1, got {cores} and {at_once}")
    return float(min(DEFAULT_SPEED_MAX, max(1, math.floor(SPEED_PER_CORE * cores / at_once))))


def px4_speed_factor(spec: UavTestSpec, *, cores: int, at_once: int) -> float:
    """``vehicle.speedFactor`` when given, else the default for this machine and parallelism, at
    most ``SCAN_SPEED_MAX`` when the runner is PX4's range sensor."""
    return px4_speed_choice(spec, cores=cores, at_once=at_once)[0]


def speed_factor_source(spec: UavTestSpec, *, cores: int, at_once: int) -> str:
    """Where ``px4_speed_factor`` came from, for the run's first line."""
    return px4_speed_choice(spec, cores=cores, at_once=at_once)[1]


def px4_speed_choice(spec: UavTestSpec, *, cores: int, at_once: int) -> tuple[float, str]:
    """PX4's speed factor for this test, machine and parallelism, and where it came from."""
    if spec.vehicle.speed_factor is not None:
        return float(spec.vehicle.speed_factor), "vehicle.speedFactor"
    default = default_speed_factor(cores, at_once)
    how = f"default for {at_once} at a time on {cores} cores"
    if range_sensor_of(spec) is not None and default > SCAN_SPEED_MAX:
        return SCAN_SPEED_MAX, f"{how}, at most {SCAN_SPEED_MAX:g}x while the runner is PX4's range sensor"
    return default, how


def px4_speed_env(speed_factor: float) -> dict[str, str]:
    """PX4 SITL's environment for a speed factor (read by its rcS and its simulator clock)."""
    return {"PX4_SIM_SPEED_FACTOR": f"{speed_factor:g}"}


def wall_timeout(timeout_s: float, simulator: Simulator, speed_factor: float | None) -> float:
    """Wall seconds one attempt of a replica may take; ``timeout_s`` is vehicle (flight) time.

    The built-in simulator runs in lockstep, far faster than real time: its budget is the
    flight time as if it ran in real time. PX4 runs at ``speed_factor`` (1 when None): boot,
    arm settle and flight at half that speed, plus start-up.
    """
    if simulator is not Simulator.PX4:
        return timeout_s + BUILTIN_START_S
    speed = speed_factor or 1.0
    return PX4_SLOWDOWN * (timeout_s + PX4_BOOT_S) / speed + START_S


def speed_factor_notice(spec: UavTestSpec) -> str | None:
    """A warning when ``vehicle.speedFactor`` is given but the simulator does not use it."""
    if spec.vehicle.speed_factor is None or spec.vehicle.simulator is Simulator.PX4:
        return None
    return (
        f"vehicle.speedFactor {spec.vehicle.speed_factor:g} is ignored: the built-in simulator runs "
        "in lockstep, as fast as the runner grants time (speedFactor applies to simulator: px4)"
    )
