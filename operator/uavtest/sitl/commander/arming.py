"""Arming: PX4's pre-arm checks as a table, and vehicle_status arming/disarming reasons."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import TYPE_CHECKING

from uavtest.px4.modes import NavState
from uavtest.sitl.mav import MavResult

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["ARMING_CHECKS", "ArmingCheck", "Reason", "arming_denied"]


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


#: in PX4's order: the first failing check decides
ARMING_CHECKS: tuple[ArmingCheck, ...] = (
    ArmingCheck(lambda v: not v.ready, MavResult.TEMPORARILY_REJECTED, "Arming denied: system not ready"),
    # modeCheck.cpp: offboard intended without setpoints → "No offboard signal" blocks arming
    ArmingCheck(
        lambda v: v.nav_state == NavState.OFFBOARD and not v.offboard.signal(v.time_us),
        MavResult.DENIED,
        "Arming denied: No offboard signal",
    ),
    ArmingCheck(lambda v: v.crashed, MavResult.DENIED, "Arming denied: vehicle crashed"),
    ArmingCheck(
        lambda v: v.nav_state == NavState.AUTO_MISSION and not v.nav.mission_valid,
        MavResult.DENIED,
        "Arming denied: no valid mission",
    ),
)


def arming_denied(v: Vehicle) -> ArmingCheck | None:
    """The first pre-arm check that fails, or None when the vehicle may arm."""
    for check in ARMING_CHECKS:
        if check.fails(v):
            return check
    return None
