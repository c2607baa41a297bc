"""Arming: PX4's pre-arm checks as a table, and vehicle_status arming/disarming reasons."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import TYPE_CHECKING

from uavtest.sitl.commander.mode_requirements import can_arm
from uavtest.sitl.mav import MavResult

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["ARMING_CHECKS", "RESOLVE_FAILURES", "ArmingCheck", "Reason", "arming_denied"]


class Reason(IntEnum):
    """vehicle_status.latest_(dis)arming_reason."""

    EXTERNAL = 4
    MISSION_START = 5
    AUTO_DISARM_LAND = 7
    AUTO_DISARM_PREFLIGHT = 8
    FAILURE_DETECTOR = 11
    FAILSAFE = 14  # arm_disarm_reason_t::failsafe (events enums.json)


@dataclass(frozen=True, slots=True)
class ArmingCheck:
    """Arming is refused with ``result`` (and ``text``, when set) while ``fails`` holds."""

    fails: Callable[[Vehicle], bool]
    result: MavResult
    text: str | None


#: Commander::arm: the mode the vehicle is in cannot arm (``mode_requirements.can_arm``: a
#: stick mode without manual control, Mission without a valid mission, Offboard without
#: setpoints, Return / Land / Descend / Orbit, ...). PX4 v1.15 SIH answers TEMPORARILY_REJECTED
#: with this text alone; the cause goes out only as an EVENT ("No manual control input", "Mode
#: not suitable for arming", ...), which the built-in vehicle does not send.
RESOLVE_FAILURES = "Arming denied: Resolve system health failures first"


def _mode_cannot_arm(v: Vehicle) -> bool:
    return not can_arm(v.nav_state, v.commander.mode_flags(v.time_us))


#: in PX4's order: the first failing check decides
ARMING_CHECKS: tuple[ArmingCheck, ...] = (
    ArmingCheck(lambda v: not v.ready, MavResult.TEMPORARILY_REJECTED, "Arming denied: system not ready"),
    ArmingCheck(lambda v: v.crashed, MavResult.DENIED, "Arming denied: vehicle crashed"),
    ArmingCheck(_mode_cannot_arm, MavResult.TEMPORARILY_REJECTED, RESOLVE_FAILURES),
)


def arming_denied(v: Vehicle) -> ArmingCheck | None:
    """The first pre-arm check that fails, or None when the vehicle may arm."""
    for check in ARMING_CHECKS:
        if check.fails(v):
            return check
    return None
