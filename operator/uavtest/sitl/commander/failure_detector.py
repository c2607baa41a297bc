"""Failure injection and detection (PX4 ``commander/failure_detector/FailureDetector.cpp``).

``FailureInjector`` (same file in PX4) takes MAV_CMD_INJECT_FAILURE for SYSTEM_MOTOR: OK clears
motor ``instance`` (1-based; 0 all) and only an instance PX4 knows is ACCEPTED; OFF and WRONG
block it (always ACCEPTED). Other units are not its business (None).

What a blocked motor does is the simulator's part: PX4 only reports the ESC offline
(``manipulateEscStatus``); the built-in vehicle also models its physics — a quadrotor that loses
one of four motors cannot hold its attitude, it tumbles (rolls at ``TUMBLE_RATE``) and falls.

``FailureDetector`` publishes ``failure_detector_status`` (run at 5 Hz): ``fd_motor`` and
``motor_failure_mask`` once an ESC is offline while armed (``FD_ACT_EN``), and ``fd_roll`` when
the roll has exceeded ``FD_FAIL_R`` for ``FD_FAIL_R_TTRI`` (the tumble is a roll; pitch, altitude
and external failures are not modelled). The commander reacts as failsafe.cpp: ``fd_critical_failure`` disarms
within ``COM_LKDOWN_TKO`` + ``COM_SPOOLUP_TIME`` of arming, terminates when the flight
termination circuit breaker ``CBRK_FLIGHTTERM`` is not 121212, else it is a warning;
``fd_motor_failure`` takes ``COM_ACT_FAIL_ACT`` (0: warning).
"""

from __future__ import annotations

import math

from uavtest.sitl.mav import MavResult
from uavtest.sitl.uorb import FailureDetectorStatus

__all__ = [
    "FAILURE_MOTOR",
    "FAILURE_PITCH",
    "FAILURE_ROLL",
    "TUMBLE_RATE",
    "FailureDetector",
    "FailureInjector",
]

FAILURE_UNIT_SYSTEM_MOTOR = 101
FAILURE_TYPE_OK, FAILURE_TYPE_OFF, FAILURE_TYPE_WRONG = 0, 1, 4
ESC_MAX = 8  # esc_status_s::CONNECTED_ESC_MAX
MOTORS = 4  # the quadrotor's motors
#: vehicle_status.failure_detector_status bits
FAILURE_ROLL, FAILURE_PITCH, FAILURE_MOTOR = 1, 2, 128
TUMBLE_RATE = math.radians(360.0)  # rad/s: roll rate of a quad with a motor out


class FailureInjector:
    """Blocked / wrong ESCs (bit i: motor i+1), and the tumble they cause (simulator state)."""

    __slots__ = ("esc_blocked", "esc_wrong", "falling", "tumble")

    def __init__(self) -> None:
        self.esc_blocked = 0
        self.esc_wrong = 0
        self.tumble = 0.0  # roll (rad) of a vehicle tumbling with a motor out
        self.falling = False  # lost a motor in the air

    def inject(self, failure_type: int, instance: int) -> MavResult | None:
        if failure_type == FAILURE_TYPE_OK:
            if instance == 0:
                self.esc_blocked = self.esc_wrong = 0
                return MavResult.ACCEPTED
            if 1 <= instance <= ESC_MAX:
                self.esc_blocked &= ~(1 << (instance - 1))
                self.esc_wrong &= ~(1 << (instance - 1))
                return MavResult.ACCEPTED
            return MavResult.UNSUPPORTED
        if failure_type in (FAILURE_TYPE_OFF, FAILURE_TYPE_WRONG):
            mask = (
                (1 << ESC_MAX) - 1
                if instance == 0
                else (1 << (instance - 1))
                if 1 <= instance <= ESC_MAX
                else 0
            )
            if failure_type == FAILURE_TYPE_OFF:
                self.esc_blocked |= mask
            else:
                self.esc_wrong |= mask
            return MavResult.ACCEPTED
        return MavResult.UNSUPPORTED

    @property
    def motor_out(self) -> bool:
        """A motor of the quadrotor produces no thrust (blocked)."""
        return bool(self.esc_blocked & ((1 << MOTORS) - 1))

    @property
    def offline_mask(self) -> int:
        return (self.esc_blocked | self.esc_wrong) & ((1 << MOTORS) - 1)


class FailureDetector:
    """failure_detector_status from the attitude and the ESCs, on change (and at 1 Hz by the caller)."""

    __slots__ = ("_roll_since", "fd_motor", "fd_roll", "motor_failure_mask", "status_bits")

    def __init__(self) -> None:
        self.fd_roll = False
        self.fd_motor = False
        self.motor_failure_mask = 0
        self._roll_since: int | None = None
        self.status_bits = 0  # vehicle_status.failure_detector_status bits

    def update(self, t: int, armed: bool, roll: float, esc_offline: int, params) -> bool:
        """Advance; True when a flag changed."""
        before = (self.fd_roll, self.fd_motor)
        if abs(roll) > math.radians(params["FD_FAIL_R"]) and params["FD_FAIL_R"] > 0:
            if self._roll_since is None:
                self._roll_since = t
            if t - self._roll_since >= params["FD_FAIL_R_TTRI"] * 1e6:
                self.fd_roll = True
        else:
            self._roll_since = None
            self.fd_roll = False
        if armed and int(params["FD_ACT_EN"]) and esc_offline:
            self.fd_motor = True
            self.motor_failure_mask = esc_offline
        elif not esc_offline:
            self.fd_motor = False
            self.motor_failure_mask = 0
        self.status_bits = (FAILURE_ROLL if self.fd_roll else 0) | (FAILURE_MOTOR if self.fd_motor else 0)
        return (self.fd_roll, self.fd_motor) != before

    def topic(self, t: int) -> FailureDetectorStatus:
        return FailureDetectorStatus(
            t,
            self.fd_roll,
            False,
            False,
            False,
            False,
            False,
            False,
            self.fd_motor,
            0.0,
            self.motor_failure_mask,
        )
