"""One replica's life against any MAVLink vehicle (PX4 SITL, the built-in sitl, a real drone).

connect → set params → upload the mission → timed commands → monitor → collect the ULog →
analyse → store ``flight.ulg``, ``trajectory.csv``, ``result.json``.

- ``uavtest.runner.core``: the pure stage machine (decoded messages and clocks in, messages out);
  ``params``, ``mission``, ``commands``, ``monitor``, ``logdownload`` are its pure parts;
  ``grants`` sizes the lockstep grants (large while nothing happens, short around events).
- ``uavtest.runner.link``: the only pymavlink adapter (UDP ``udpin:HOST:PORT``).
- ``uavtest.runner.main``: ``run_replica`` / ``run_replica_command`` (``uavtest runner``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

__all__ = ["CoreConfig", "FlightReport", "ReplicaCore", "RunnerOptions", "run_replica", "run_replica_command"]

if TYPE_CHECKING:
    from uavtest.runner.core import CoreConfig, FlightReport, ReplicaCore
    from uavtest.runner.main import RunnerOptions, run_replica, run_replica_command


def __getattr__(name: str) -> object:
    # imported on use: `import uavtest.runner` stays cheap (no pymavlink, no analysis)
    if name in {"CoreConfig", "FlightReport", "ReplicaCore"}:
        from uavtest.runner import core

        return getattr(core, name)
    if name in {"RunnerOptions", "run_replica", "run_replica_command"}:
        from uavtest.runner import main

        return getattr(main, name)
    raise AttributeError(name)
