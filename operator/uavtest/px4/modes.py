"""PX4 flight modes as data, one home for the runner and the simulator.

Numbers from PX4 ``src/modules/commander/px4_custom_mode.h`` and ``msg/VehicleStatus.msg``
(v1.15). HEARTBEAT's ``custom_mode`` packs the main mode in bits 16-23 and the sub mode in
bits 24-31 (``union px4_custom_mode { struct { uint16 reserved; uint8 main_mode; uint8 sub_mode; } }``).
"""

from __future__ import annotations

from enum import IntEnum

__all__ = [
    "ARMING_STATE_ARMED",
    "ARMING_STATE_DISARMED",
    "AUTO_NAV_STATES",
    "MANUAL_NAV_STATES",
    "MODE_OF_NAV_STATE",
    "NAV_STATE_OF_MODE",
    "AutoSubMode",
    "MainMode",
    "NavState",
    "base_mode_flags",
    "custom_mode",
    "encode_custom_mode",
    "mode_name",
    "nav_state_from_custom_mode",
    "split_custom_mode",
]


class MainMode(IntEnum):
    """PX4_CUSTOM_MAIN_MODE."""

    MANUAL = 1
    ALTCTL = 2
    POSCTL = 3
    AUTO = 4
    ACRO = 5
    OFFBOARD = 6
    STABILIZED = 7
    RATTITUDE = 8


class AutoSubMode(IntEnum):
    """PX4_CUSTOM_SUB_MODE_AUTO."""

    READY = 1
    TAKEOFF = 2
    LOITER = 3
    MISSION = 4
    RTL = 5
    LAND = 6
    RTGS = 7
    FOLLOW_TARGET = 8
    PRECLAND = 9


class NavState(IntEnum):
    """vehicle_status.nav_state (NAVIGATION_STATE_*)."""

    MANUAL = 0
    ALTCTL = 1
    POSCTL = 2
    AUTO_MISSION = 3
    AUTO_LOITER = 4
    AUTO_RTL = 5
    ACRO = 10
    DESCEND = 12
    TERMINATION = 13
    OFFBOARD = 14
    STAB = 15
    AUTO_TAKEOFF = 17
    AUTO_LAND = 18
    AUTO_FOLLOW_TARGET = 19
    AUTO_PRECLAND = 20
    ORBIT = 21


ARMING_STATE_DISARMED = 1  # vehicle_status.ARMING_STATE_DISARMED
ARMING_STATE_ARMED = 2

#: (main, sub) → nav_state, for the modes this simulator flies. Sub 0 = "no sub mode".
NAV_STATE_OF_MODE: dict[tuple[int, int], NavState] = {
    (MainMode.MANUAL, 0): NavState.MANUAL,
    (MainMode.STABILIZED, 0): NavState.STAB,
    (MainMode.ACRO, 0): NavState.ACRO,
    (MainMode.ALTCTL, 0): NavState.ALTCTL,
    (MainMode.POSCTL, 0): NavState.POSCTL,
    (MainMode.OFFBOARD, 0): NavState.OFFBOARD,
    (MainMode.AUTO, AutoSubMode.MISSION): NavState.AUTO_MISSION,
    (MainMode.AUTO, AutoSubMode.LOITER): NavState.AUTO_LOITER,
    (MainMode.AUTO, AutoSubMode.RTL): NavState.AUTO_RTL,
    (MainMode.AUTO, AutoSubMode.TAKEOFF): NavState.AUTO_TAKEOFF,
    (MainMode.AUTO, AutoSubMode.LAND): NavState.AUTO_LAND,
}

#: nav_state → (main, sub) as PX4 reports it in HEARTBEAT.custom_mode.
MODE_OF_NAV_STATE: dict[NavState, tuple[int, int]] = {v: k for k, v in NAV_STATE_OF_MODE.items()}
MODE_OF_NAV_STATE[NavState.DESCEND] = (MainMode.AUTO, AutoSubMode.LAND)
MODE_OF_NAV_STATE[NavState.TERMINATION] = (MainMode.MANUAL, 0)
#: px4_custom_mode.h: NAVIGATION_STATE_ORBIT reports POSCTL / PX4_CUSTOM_SUB_MODE_POSCTL_ORBIT (1)
MODE_OF_NAV_STATE[NavState.ORBIT] = (MainMode.POSCTL, 1)

MANUAL_NAV_STATES = frozenset(
    {NavState.MANUAL, NavState.STAB, NavState.ACRO, NavState.ALTCTL, NavState.POSCTL}
)
AUTO_NAV_STATES = frozenset(
    {
        NavState.AUTO_MISSION,
        NavState.AUTO_LOITER,
        NavState.AUTO_RTL,
        NavState.AUTO_TAKEOFF,
        NavState.AUTO_LAND,
    }
)

# MAV_MODE_FLAG bits
_CUSTOM_MODE_ENABLED = 1
_AUTO_ENABLED = 4
_GUIDED_ENABLED = 8
_STABILIZE_ENABLED = 16
_MANUAL_INPUT_ENABLED = 64
_SAFETY_ARMED = 128


def encode_custom_mode(main: int, sub: int = 0) -> int:
    """HEARTBEAT.custom_mode of a main/sub mode pair: main << 16 | sub << 24."""
    return (int(main) << 16) | (int(sub) << 24)


def custom_mode(nav_state: NavState) -> int:
    """HEARTBEAT.custom_mode of a nav_state: main << 16 | sub << 24."""
    main, sub = MODE_OF_NAV_STATE[nav_state]
    return encode_custom_mode(main, sub)


def split_custom_mode(value: int) -> tuple[int, int]:
    """(main, sub) of a HEARTBEAT.custom_mode."""
    return (value >> 16) & 0xFF, (value >> 24) & 0xFF


def nav_state_from_custom_mode(main: int, sub: int) -> NavState | None:
    """The nav_state a DO_SET_MODE main/sub asks for; None when this simulator cannot fly it.

    PX4 treats ``AUTO`` without a sub mode, and POSCTL's sub modes, like the plain mode.
    """
    if main == MainMode.AUTO and sub == 0:
        sub = AutoSubMode.LOITER
    if main != MainMode.AUTO:
        sub = 0
    return NAV_STATE_OF_MODE.get((main, sub))


def base_mode_flags(nav_state: NavState, armed: bool) -> int:
    """HEARTBEAT.base_mode as PX4 fills it for a nav_state."""
    flags = _CUSTOM_MODE_ENABLED | (_SAFETY_ARMED if armed else 0)
    if nav_state in (NavState.MANUAL, NavState.ACRO):
        flags |= _MANUAL_INPUT_ENABLED
    elif nav_state in (NavState.STAB, NavState.ALTCTL):
        flags |= _MANUAL_INPUT_ENABLED | _STABILIZE_ENABLED
    elif nav_state == NavState.POSCTL:
        flags |= _MANUAL_INPUT_ENABLED | _STABILIZE_ENABLED | _GUIDED_ENABLED
    else:
        flags |= _AUTO_ENABLED | _STABILIZE_ENABLED | _GUIDED_ENABLED
    return flags


def mode_name(main: int, sub: int) -> str:
    """PX4's name of a main/sub mode (``AUTO.MISSION``, ``POSCTL``), or ``main/sub`` numbers."""
    try:
        name = MainMode(main).name
    except ValueError:
        return f"{main}/{sub}"
    if main != MainMode.AUTO:
        return name
    try:
        return f"{name}.{AutoSubMode(sub).name}"
    except ValueError:
        return f"{main}/{sub}"
