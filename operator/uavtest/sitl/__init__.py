"""uavtest.sitl: the built-in PX4-compatible simulator (``uavtest sitl``).

A multicopter that speaks MAVLink 2 like PX4 SITL, flies missions, hold, takeoff, land,
return and stick modes with PX4's parameters, in a world of box obstacles and wind, and writes
a PX4-style ULog. The vehicle is pure code (``vehicle.Vehicle``: messages and clock ticks in,
messages out), a façade over modules named like PX4's: ``commander/`` (arming checks, failsafe
tables, vehicle command dispatch), ``navigator/``, ``mc_pos_control`` (flight tasks and position
control), ``ekf2`` (estimate), ``land_detector``, ``simulator_sih`` (physics, wind, obstacles),
``mavlink_streams`` (telemetry) and ``recorder`` (PX4's logger), exchanging the ``uorb`` topic
dataclasses that the ULog records as they are. ``main.run_sitl`` is the process edge (UDP
links, lockstep or speed factor, signals, log files, and ``logserver.LogServer`` serving
finished logs over MAVLink);
``inprocess.fly_mission`` flies a mission without sockets.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

__all__ = ["SimConfig", "Vehicle"]

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import SimConfig, Vehicle


def __getattr__(name: str) -> Any:
    """``SimConfig`` and ``Vehicle`` on first use (PEP 562): a process that needs one module of the
    simulator (the runner's range sensor needs ``sensor_obstacle_distance_sim``) does not import
    the whole vehicle at start-up."""
    if name in __all__:
        from uavtest.sitl import vehicle

        return getattr(vehicle, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
