"""From a test spec to what the core needs, in wire form (pure)."""

from __future__ import annotations

import logging

from uavtest.runner.core import CoreConfig
from uavtest.runner.grants import DEFAULT_STEP_MS
from uavtest.runner.mission import wire_items
from uavtest.spec.commands import resolved_commands
from uavtest.spec.mission import mission_items
from uavtest.spec.models import Command, CommandAction, FlightMode, UavTestSpec

__all__ = ["flight_commands", "plan_flight"]

log = logging.getLogger(__name__)


def flight_commands(spec: UavTestSpec) -> list[Command]:
    """The test's timed commands; a test with a mission and no commands starts the mission at once
    (``mode mission`` at 0 s, which arms first, as Aerialist does)."""
    commands = resolved_commands(spec)
    if spec.mission is not None and not commands:
        log.info("no commands: mode mission at 0 s (arms first)")
        commands = [Command(at=0.0, action=CommandAction.MODE, mode=FlightMode.MISSION)]
    return commands


def plan_flight(
    spec: UavTestSpec,
    *,
    endpoint: str,
    timeout_s: float | None = None,
    connect_timeout_s: float = 30.0,
    step_ms: int = DEFAULT_STEP_MS,
    download_log: bool = False,
) -> CoreConfig:
    """The core's configuration for one flight of ``spec`` through ``endpoint``."""
    return CoreConfig(
        endpoint=endpoint,
        params=dict(spec.vehicle.params),
        mission=wire_items(mission_items(spec), spec.world.home),
        commands=flight_commands(spec),
        obstacles=list(spec.world.obstacles),
        geofence=spec.assertions.geofence,
        timeout_s=timeout_s if timeout_s is not None else spec.timeout,
        connect_timeout_s=connect_timeout_s,
        step_ms=step_ms,
        download_log=download_log,
    )
