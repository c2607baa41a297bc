"""Fly a mission with the vehicle in-process (no sockets): for tests, benchmarks and tools.

Does what a MAVLink client would: wait until ready, arm, switch to mission mode, then step
the vehicle until it disarms (or a limit), recording the true trajectory and mission events.
The vehicle has no MAVLink link here (``SimConfig.links`` empty): it builds no telemetry stream
nobody reads, only the broadcast events (STATUSTEXT, MISSION_ITEM_REACHED) ``Flight`` records.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from uavtest.px4.modes import AutoSubMode, MainMode
from uavtest.sitl.mav import MavCmd, Msg
from uavtest.sitl.mission import NavItem
from uavtest.sitl.recorder import LogSink
from uavtest.sitl.vehicle import SimConfig, Vehicle

__all__ = ["Flight", "fly_mission"]

_CLIENT = (255, 190)


@dataclass
class Flight:
    """What happened: samples (t, x, y, z) every ``sample_us``, items reached, takeoff/landing times."""

    samples: list[tuple[float, float, float, float]] = field(default_factory=list)
    reached: list[tuple[int, float]] = field(default_factory=list)
    texts: list[tuple[float, str]] = field(default_factory=list)
    takeoff_s: float | None = None
    landed_s: float | None = None
    disarmed: bool = False
    vehicle: Vehicle | None = None

    @property
    def flight_time(self) -> float | None:
        if self.takeoff_s is None or self.landed_s is None:
            return None
        return self.landed_s - self.takeoff_s


def _command(vehicle: Vehicle, command: int, *params: float) -> int:
    fields: dict[str, object] = {"command": command, "target_system": 1, "target_component": 1}
    for i, p in enumerate(params, start=1):
        fields[f"param{i}"] = p
    ack = vehicle.receive(Msg("COMMAND_LONG", fields, *_CLIENT))[0]
    return int(ack.fields["result"])


def fly_mission(
    config: SimConfig,
    items: Sequence[NavItem],
    *,
    sink: LogSink | None = None,
    limit_s: float = 600.0,
    sample_us: int = 100_000,
    stop: Callable[[Vehicle, Flight], bool] | None = None,
) -> Flight:
    """Arm, start the mission and fly until the vehicle disarms, ``limit_s`` seconds pass or
    ``stop`` (asked every ``sample_us``) says the flight is over."""
    vehicle = Vehicle(dataclasses.replace(config, links=()), sink)
    vehicle.load_mission(list(items))
    flight = Flight(vehicle=vehicle)
    vehicle.fly_until(lambda v: v.ready, 10_000_000)
    if _command(vehicle, MavCmd.COMPONENT_ARM_DISARM, 1.0) != 0:
        return flight
    _command(vehicle, MavCmd.DO_SET_MODE, 1.0, float(MainMode.AUTO), float(AutoSubMode.MISSION))
    limit_us = vehicle.time_us + int(limit_s * 1e6)
    while vehicle.time_us < limit_us:
        out = vehicle.advance(vehicle.time_us + sample_us)
        now = vehicle.time_us / 1e6
        for msg in out:
            if msg.name == "MISSION_ITEM_REACHED":
                flight.reached.append((int(msg.fields["seq"]), now))
            elif msg.name == "STATUSTEXT":
                flight.texts.append((now, str(msg.fields["text"])))
        b = vehicle.body
        flight.samples.append((now, b.x, b.y, b.z))
        if vehicle.takeoff_us and flight.takeoff_s is None:
            flight.takeoff_s = vehicle.takeoff_us / 1e6
        if not vehicle.armed:
            flight.disarmed = True
            break
        if stop is not None and stop(vehicle, flight):
            break
    if vehicle.takeoff_us:
        flight.takeoff_s = vehicle.takeoff_us / 1e6
    if vehicle.landed and vehicle.landed_at_us > vehicle.takeoff_us > 0:
        flight.landed_s = vehicle.landed_at_us / 1e6
    vehicle.recorder.stop()
    return flight
