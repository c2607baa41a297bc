"""How PX4's manual flight tasks read the sticks (``flight_mode_manager/tasks/Utility/Sticks``).

``Sticks::checkAndUpdateStickInputs`` (PX4 v1.15) rescales each stick with a deadzone
(``MPC_HOLD_DZ``: zero around the centre, the rest stretched back to [-1, 1]) and an expo curve
(``MPC_XY_MAN_EXPO`` for pitch and roll, ``MPC_Z_MAN_EXPO`` for the throttle, ``MPC_YAW_EXPO`` for
yaw: a mix of the linear and the cubic stick), as ``math::expo_deadzone`` does. Altitude and
position mode fly on these; stabilized mode's tilt takes the raw sticks.
"""

from __future__ import annotations

import math

__all__ = ["deadzone", "expo", "expo_deadzone", "limit_unit_length"]


def expo(value: float, e: float) -> float:
    """``math::expo``: (1 - e) x + e x³, x and e clamped to [-1, 1] and [0, 1]."""
    x = max(-1.0, min(1.0, value))
    ec = max(0.0, min(1.0, e))
    return (1.0 - ec) * x + ec * x * x * x


def deadzone(value: float, dz: float) -> float:
    """``math::deadzone``: zero within ``dz`` of the centre, linear (and continuous) outside."""
    x = max(-1.0, min(1.0, value))
    dzc = max(0.0, min(0.99, dz))
    if abs(x) <= dzc:
        return 0.0
    return (x - math.copysign(dzc, x)) / (1.0 - dzc)


def expo_deadzone(value: float, e: float, dz: float) -> float:
    """``math::expo_deadzone``: the deadzone first, then the expo curve."""
    return expo(deadzone(value, dz), e)


def limit_unit_length(x: float, y: float) -> tuple[float, float]:
    """``Sticks::limitStickUnitLengthXY``: a diagonal stick is no longer than a straight one."""
    n = math.hypot(x, y)
    return (x / n, y / n) if n > 1.0 else (x, y)
