"""Stage 4: the test's timed commands, on the vehicle clock (pure state machine).

A command whose time has come (or passed) becomes one or more steps, run one at a time in order:
COMMAND_LONG steps wait for their COMMAND_ACK (resent on silence, bounded), sticks steps take
effect at once. Aerialist semantics: ``mode mission`` or ``mode takeoff`` while disarmed arms
first. While sticks are active MANUAL_CONTROL goes out every ``stick_period_ms`` of vehicle time;
a switch to a mode that flies by itself (mission, hold, return, land, takeoff) or a disarm ends
them. A refused arm is retried every second of vehicle time (PX4 refuses until its preflight
checks pass) for ``arm_give_up_s``, then the scheduler gives up (``gave_up``: the vehicle refused
to fly); other refusals (DENIED, TEMPORARILY_REJECTED, FAILED) are recorded in ``refusals`` and the
flight goes on (the vehicle decided — the verdict will tell); no ACK at all, or UNSUPPORTED, is a
bench error (``error``; for UNSUPPORTED worded by ``unsupported_reason``).

Arm settle (``arm_settle_ms``, 0 = off): PX4's pre-arm checks pass while its estimator is still
settling, and a takeoff commanded at that moment can stall a metre above the ground. With a settle
time the arm waits until SYS_STATUS has reported ready-to-arm (MAV_SYS_STATUS_PREARM_CHECK) without
a break for that long; a vehicle that sends no SYS_STATUS is armed at once, and after
``arm_give_up_ms`` of waiting the arm is sent anyway (the vehicle decides).
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

from uavtest.runner.events import CommandAck, CommandLong, ManualControl, Outgoing
from uavtest.runner.px4 import (
    AUTO_MODES,
    FORCE_DISARM_MAGIC,
    MODE_FLAG_CUSTOM_MODE_ENABLED,
    PX4_MODES,
    AckResult,
    Cmd,
    result_name,
)
from uavtest.spec.models import Command, CommandAction, FlightMode, Sticks

__all__ = [
    "CommandScheduler",
    "Refusal",
    "Step",
    "StepKind",
    "arm_command",
    "command_name",
    "disarm_command",
    "expand",
    "manual_control",
    "mode_command",
    "speed_command",
    "unsupported_reason",
]

log = logging.getLogger(__name__)


class StepKind(Enum):
    ARM = "arm"
    DISARM = "disarm"
    MODE = "mode"
    SPEED = "speed"
    STICKS = "sticks"


@dataclass(frozen=True, slots=True)
class Step:
    kind: StepKind
    label: str
    command: CommandLong | None = None  # None for sticks
    mode: FlightMode | None = None
    sticks: ManualControl | None = None


@dataclass(frozen=True, slots=True)
class Refusal:
    """The vehicle refused a step: COMMAND_ACK DENIED / TEMPORARILY_REJECTED / FAILED."""

    label: str  # the step, e.g. "mode offboard", "arm (for mode mission)"
    result: str  # the MAV_RESULT name, e.g. "DENIED"
    sent_ms: int  # vehicle time the step was (last) sent
    ack_ms: int  # vehicle time of the refusing ACK
    final: bool = True  # False: an arm refusal that is being retried


def command_name(command: int) -> str:
    """``MAV_CMD_DO_ORBIT``-style name of a MAV_CMD number (the number when unknown)."""
    try:
        return f"MAV_CMD_{Cmd(command).name}"
    except ValueError:
        return f"MAV_CMD {command}"


def unsupported_reason(what: str, simulator: str | None) -> str:
    """The bench error for a command the vehicle answered MAV_RESULT_UNSUPPORTED.

    ``what``: "mode offboard" or "MAV_CMD_DO_ORBIT"; ``simulator``: "builtin", "px4" or None
    (a vehicle of unknown kind).
    """
    if simulator == "builtin":
        return f"the built-in simulator does not support {what}; fly this test with simulator: px4"
    if simulator == "px4":
        return f"PX4 does not support {what}"
    return f"the vehicle does not support {what} (COMMAND_ACK UNSUPPORTED)"


def arm_command() -> CommandLong:
    return CommandLong(Cmd.COMPONENT_ARM_DISARM, (1.0, 0, 0, 0, 0, 0, 0))


def disarm_command(*, force: bool = False) -> CommandLong:
    return CommandLong(Cmd.COMPONENT_ARM_DISARM, (0.0, FORCE_DISARM_MAGIC if force else 0.0, 0, 0, 0, 0, 0))


def mode_command(mode: FlightMode) -> CommandLong:
    main, sub = PX4_MODES[mode]
    return CommandLong(
        Cmd.DO_SET_MODE, (float(MODE_FLAG_CUSTOM_MODE_ENABLED), float(main), float(sub), 0, 0, 0, 0)
    )


def speed_command(speed: float) -> CommandLong:
    return CommandLong(Cmd.DO_CHANGE_SPEED, (1.0, float(speed), -1.0, 0, 0, 0, 0))


def manual_control(sticks: Sticks) -> ManualControl:
    return ManualControl(
        x=round(sticks.x * 1000), y=round(sticks.y * 1000), z=round(sticks.z * 1000), r=round(sticks.r * 1000)
    )


def expand(command: Command) -> list[Step]:
    """The steps of one command (before knowing whether the vehicle is armed: arming is skipped
    at run time when it already is)."""
    action = command.action
    if action is CommandAction.ARM:
        return [Step(StepKind.ARM, "arm", arm_command())]
    if action is CommandAction.DISARM:
        return [Step(StepKind.DISARM, "disarm", disarm_command())]
    if action is CommandAction.SPEED:
        assert command.speed is not None
        return [Step(StepKind.SPEED, f"speed {command.speed:g}", speed_command(command.speed))]
    if action is CommandAction.STICKS:
        assert command.sticks is not None
        mc = manual_control(command.sticks)
        return [Step(StepKind.STICKS, f"sticks {mc.x},{mc.y},{mc.z},{mc.r}", sticks=mc)]
    assert command.mode is not None
    steps = [Step(StepKind.MODE, f"mode {command.mode.value}", mode_command(command.mode), mode=command.mode)]
    if command.mode in (FlightMode.MISSION, FlightMode.TAKEOFF):
        steps.insert(0, Step(StepKind.ARM, f"arm (for mode {command.mode.value})", arm_command()))
    return steps


class CommandScheduler:
    """Runs the commands at their vehicle times; ``error`` is set on a bench fault."""

    def __init__(
        self,
        commands: Sequence[Command],
        *,
        ack_timeout_s: float = 1.0,
        send_attempts: int = 5,
        arm_retry_ms: int = 1000,
        arm_give_up_ms: int = 60_000,
        arm_settle_ms: int = 0,
        stick_period_ms: int = 50,
        simulator: str | None = None,
    ) -> None:
        self._pending = deque(sorted(commands, key=lambda c: c.at))
        self._steps: deque[Step] = deque()
        self.ack_timeout_s = ack_timeout_s
        self.send_attempts = send_attempts
        self.arm_retry_ms = arm_retry_ms
        self.arm_give_up_ms = arm_give_up_ms
        self.arm_settle_ms = arm_settle_ms
        self.stick_period_ms = stick_period_ms
        self.simulator = simulator  # "builtin" / "px4" / None: how UNSUPPORTED is worded
        self.error: str | None = None
        self.notes: list[str] = []  # refusals the vehicle made; shown in the log and the result
        self.refusals: list[Refusal] = []  # the same, structured (for the verdict's reason)
        self.gave_up: Refusal | None = None  # an arm refused until arm_give_up_ms: no flight
        self._sent_ms = 0  # vehicle time the current step was last sent
        self.sent: list[tuple[int, str]] = []  # (vehicle ms, label) of every step started
        self.sticks: ManualControl | None = None
        self._last_stick_ms = -math.inf
        self._current: Step | None = None
        self._confirmation = 0
        self._ack_deadline = math.inf
        self._retry_at_ms: float | None = None  # a refused arm waits for this vehicle time
        self._first_refusal_ms: int | None = None
        self._status_seen = False  # the vehicle reports its pre-arm state (SYS_STATUS)
        self._ready_since_ms: int | None = None  # vehicle time it became ready to arm (None: not ready)
        self._waiting_since_ms: int | None = None  # an arm waits for the vehicle to settle, since then

    @property
    def idle(self) -> bool:
        """No command left to run or waiting for its ACK (sticks may still be streaming)."""
        return not self._pending and not self._steps and self._current is None

    @property
    def next_at_ms(self) -> float:
        """Vehicle time of the next command not yet due (inf when none)."""
        return self._pending[0].at * 1000.0 if self._pending else math.inf

    @property
    def busy(self) -> bool:
        """A command sequence is running: a step waits for its ACK (not for a retry time), or more
        steps are queued behind it."""
        return bool(self._steps) or (self._current is not None and self._retry_at_ms is None)

    @property
    def next_event_ms(self) -> float:
        """Vehicle time of the next thing to do on the vehicle clock: a command not yet due or a
        refused arm's retry (inf when none)."""
        retry = self._retry_at_ms if self._retry_at_ms is not None else math.inf
        return min(self.next_at_ms, retry)

    @property
    def ack_deadline(self) -> float:
        return self._ack_deadline

    def on_sys_status(self, ready_to_arm: bool, now_ms: int) -> None:
        """Track how long the vehicle has been ready to arm without a break."""
        self._status_seen = True
        if not ready_to_arm:
            self._ready_since_ms = None
        elif self._ready_since_ms is None:
            self._ready_since_ms = now_ms

    def _settled_at(self, now_ms: int) -> float | None:
        """Vehicle time an arm should wait for (None: arm now)."""
        if self.arm_settle_ms <= 0 or not self._status_seen:
            return None
        if self._ready_since_ms is None:
            return now_ms + self.arm_retry_ms  # not ready: look again later
        at = self._ready_since_ms + self.arm_settle_ms
        return at if at > now_ms else None

    def update(self, now_ms: int, wall: float, *, armed: bool) -> list[Outgoing]:
        """Run what is due at vehicle time ``now_ms``: new steps, resends, sticks."""
        if self.error:
            return []
        out: list[Outgoing] = []
        while self._pending and self._pending[0].at * 1000.0 <= now_ms:
            self._steps.extend(expand(self._pending.popleft()))
        if self._current is not None:
            out += self._resend_if_due(now_ms, wall)
        while self._current is None and self._steps and not self.error:
            out += self._start(self._steps.popleft(), now_ms, wall, armed=armed)
        if self.sticks is not None and now_ms - self._last_stick_ms >= self.stick_period_ms:
            self._last_stick_ms = now_ms
            out.append(self.sticks)
        return out

    def _start(self, step: Step, now_ms: int, wall: float, *, armed: bool) -> list[Outgoing]:
        if step.kind is StepKind.ARM and armed:
            return []
        if step.kind is StepKind.DISARM and not armed:
            return []
        if step.kind is StepKind.ARM:
            wait = self._settled_at(now_ms)
            if wait is not None:
                log.info(
                    "t=%.2f s: %s waits until the vehicle has been ready to arm for %g s",
                    now_ms / 1000,
                    step.label,
                    self.arm_settle_ms / 1000,
                )
                self._current = step
                self._waiting_since_ms = now_ms
                self._first_refusal_ms = None
                self._retry_at_ms = wait
                self._ack_deadline = math.inf
                return []
        return self._send(step, now_ms, wall)

    def _send(self, step: Step, now_ms: int, wall: float) -> list[Outgoing]:
        self.sent.append((now_ms, step.label))
        log.info("t=%.2f s: %s", now_ms / 1000, step.label)
        if step.kind is StepKind.STICKS:
            self.sticks = step.sticks
            self._last_stick_ms = -math.inf
            return []
        if step.kind is StepKind.DISARM:
            self.sticks = None
        assert step.command is not None
        self._current = step
        self._sent_ms = now_ms
        self._confirmation = 0
        self._first_refusal_ms = None
        self._retry_at_ms = None
        self._ack_deadline = wall + self.ack_timeout_s
        return [step.command]

    def _resend_if_due(self, now_ms: int, wall: float) -> list[Outgoing]:
        step = self._current
        assert step is not None and step.command is not None
        if self._retry_at_ms is not None:
            if now_ms < self._retry_at_ms:
                return []
            if self._waiting_since_ms is not None:  # an arm waiting for the vehicle to settle
                wait = self._settled_at(now_ms)
                if wait is not None and now_ms - self._waiting_since_ms < self.arm_give_up_ms:
                    self._retry_at_ms = wait
                    return []
                if wait is not None:
                    given = self.arm_give_up_ms / 1000
                    log.warning("vehicle not settled after %g s; sending %s anyway", given, step.label)
                self._waiting_since_ms = None
                self._retry_at_ms = None
                return self._send(step, now_ms, wall)
            self._retry_at_ms = None
            self._sent_ms = now_ms
            self._confirmation = 0
            self._ack_deadline = wall + self.ack_timeout_s
            return [step.command]
        if wall < self._ack_deadline:
            return []
        if self._confirmation + 1 >= self.send_attempts:
            self.error = f"no COMMAND_ACK for {step.label} after {self.send_attempts} tries"
            self._ack_deadline = math.inf
            return []
        self._confirmation += 1
        self._ack_deadline = wall + self.ack_timeout_s
        log.warning("no ACK for %s; sending it again (%d)", step.label, self._confirmation + 1)
        c = step.command
        return [CommandLong(c.command, c.params, confirmation=self._confirmation)]

    def handle_ack(self, ack: CommandAck, now_ms: int, wall: float) -> Step | None:
        """Take a COMMAND_ACK; returns the step it accepted (None otherwise)."""
        step = self._current
        if step is None or step.command is None or ack.command != step.command.command:
            return None
        result = ack.result
        if result == AckResult.ACCEPTED:
            if self._retrying_refusal():
                self.refusals.pop()  # the vehicle armed in the end
            if step.kind is StepKind.MODE and step.mode in AUTO_MODES:
                self.sticks = None
            self._done()
            return step
        if result == AckResult.IN_PROGRESS:
            self._ack_deadline = wall + 5 * self.ack_timeout_s
            return None
        name = result_name(AckResult, result)
        if result == AckResult.UNSUPPORTED:
            what = step.label if step.kind is StepKind.MODE else command_name(ack.command)
            self.error = unsupported_reason(what, self.simulator)
            self._done()
            return None
        if step.kind is StepKind.ARM:
            if self._first_refusal_ms is None:
                self._first_refusal_ms = now_ms
            refusal = Refusal(step.label, name, self._sent_ms, now_ms, final=False)
            if self._retrying_refusal():
                self.refusals[-1] = refusal  # one entry per refused arm, however often retried
            else:
                self.refusals.append(refusal)
            if now_ms - self._first_refusal_ms >= self.arm_give_up_ms:
                given = f"{self.arm_give_up_ms / 1000:g} s"
                note = (
                    f"t={now_ms / 1000:.2f} s: vehicle refused {step.label} for {given} (COMMAND_ACK {name})"
                )
                log.warning(note)
                self.notes.append(note)
                self.gave_up = self.refusals[-1] = Refusal(step.label, name, self._sent_ms, now_ms)
                self._pending.clear()
                self._steps.clear()
                self._done()
                return None
            log.info("vehicle refused to arm (%s); trying again in %d ms", name, self.arm_retry_ms)
            self._retry_at_ms = now_ms + self.arm_retry_ms
            self._ack_deadline = math.inf
            return None
        note = f"t={now_ms / 1000:.2f} s: vehicle refused {step.label} (COMMAND_ACK {name})"
        log.warning(note)
        self.notes.append(note)
        self.refusals.append(Refusal(step.label, name, self._sent_ms, now_ms))
        self._done()
        return None

    def _retrying_refusal(self) -> bool:
        return bool(self.refusals) and not self.refusals[-1].final

    def _done(self) -> None:
        self._current = None
        self._waiting_since_ms = None
        self._ack_deadline = math.inf
        self._retry_at_ms = None
