"""From a test spec to what the core needs, in wire form (pure)."""

from __future__ import annotations

import logging

from uavtest.runner.core import CoreConfig
from uavtest.runner.grants import DEFAULT_STEP_MS
from uavtest.runner.mission import wire_items
from uavtest.spec.collision_prevention import range_sensor_of
from uavtest.spec.commands import resolved_commands
from uavtest.spec.mission import mission_items
from uavtest.spec.models import Command, CommandAction, FlightMode, Simulator, UavTestSpec

__all__ = ["PX4_ARM_SETTLE_S", "default_arm_settle", "flight_commands", "flight_params", "plan_flight"]

log = logging.getLogger(__name__)

#: PX4 SITL passes its pre-arm checks while the estimator is still settling; a takeoff commanded
#: right then stalled about a metre up in 2 of 6 runs (PX4 v1.15 SIH). Arming once PX4 has been
#: ready this long (vehicle seconds) is what a pilot does. The built-in simulator needs none.
PX4_ARM_SETTLE_S = 10.0


def flight_commands(spec: UavTestSpec) -> list[Command]:
    """The test's timed commands; a test with a mission and no commands starts the mission at once
    (``mode mission`` at 0 s, which arms first, as Aerialist does)."""
    commands = resolved_commands(spec)
    if spec.mission is not None and not commands:
        log.info("no commands: mode mission at 0 s (arms first)")
        commands = [Command(at=0.0, action=CommandAction.MODE, mode=FlightMode.MISSION)]
    return commands


def flight_params(spec: UavTestSpec) -> dict[str, float | int]:
    """The parameters set before flight: the test's, plus SYS_FAILURE_EN=1 when it injects faults
    (PX4 answers MAV_CMD_INJECT_FAILURE with DENIED unless failure injection is enabled)."""
    params: dict[str, float | int] = dict(spec.vehicle.params)
    if spec.faults and "SYS_FAILURE_EN" not in params:
        log.info("the test injects faults: SYS_FAILURE_EN=1")
        params["SYS_FAILURE_EN"] = 1
    return params


def plan_flight(
    spec: UavTestSpec,
    *,
    endpoint: str,
    timeout_s: float | None = None,
    connect_timeout_s: float = 30.0,
    step_ms: int = DEFAULT_STEP_MS,
    download_log: bool = False,
    arm_settle_s: float | None = None,
) -> CoreConfig:
    """The core's configuration for one flight of ``spec`` through ``endpoint``."""
    return CoreConfig(
        endpoint=endpoint,
        params=flight_params(spec),
        mission=wire_items(mission_items(spec), spec.world.home),
        commands=flight_commands(spec),
        faults=list(spec.faults),
        home=spec.world.home,
        obstacles=list(spec.world.obstacles),
        geofence=spec.assertions.geofence,
        timeout_s=timeout_s if timeout_s is not None else spec.timeout,
        connect_timeout_s=connect_timeout_s,
        step_ms=step_ms,
        download_log=download_log,
        arm_settle_s=arm_settle_s if arm_settle_s is not None else default_arm_settle(spec),
        simulator=spec.vehicle.simulator.value,
        # PX4 SITL (SIH) has no range sensor: the runner sends its scans (the built-in has its own)
        range_sensor=range_sensor_of(spec) if spec.vehicle.simulator is Simulator.PX4 else None,
    )


def default_arm_settle(spec: UavTestSpec) -> float:
    """Vehicle seconds the vehicle must have been ready to arm before the runner arms it."""
    return PX4_ARM_SETTLE_S if spec.vehicle.simulator is Simulator.PX4 else 0.0
