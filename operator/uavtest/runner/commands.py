"""Stage 4: the test's timed commands, on the vehicle clock (pure state machine).

A command whose time has come (or passed) becomes one or more steps, run one at a time in order:
COMMAND_LONG steps wait for their COMMAND_ACK (resent on silence, bounded), sticks steps take
effect at once. Aerialist semantics: ``mode mission`` or ``mode takeoff`` while disarmed arms
first. While sticks are active MANUAL_CONTROL goes out every ``stick_period_ms`` of vehicle time;
a switch to a mode that flies by itself (mission, hold, return, land, takeoff) centres them (a
ground station's joystick keeps sending: stopping would be an RC loss to PX4), a disarm ends
them. A refused arm is retried every second of vehicle time (PX4 refuses until its preflight
checks pass) for ``arm_give_up_s``, then the scheduler gives up (``gave_up``: the vehicle refused
to fly); other refusals (DENIED, TEMPORARILY_REJECTED, FAILED) are recorded in ``refusals`` and the
flight goes on (the vehicle decided — the verdict will tell), but for a mode mission refused for now
right after the mission's upload (``MISSION_CHECK_MS``: PX4 is still checking it), which is sent
again; no ACK at all, or UNSUPPORTED, is a
bench error (``error``; for UNSUPPORTED worded by ``unsupported_reason``).

Offboard setpoints (``action: setpoint``) take effect at once, like sticks: from then on
SET_POSITION_TARGET_LOCAL_NED (or _GLOBAL_INT) goes out every ``setpoint_period_ms`` (20 Hz) of
vehicle time, until the next setpoint replaces it, an accepted switch to another mode (``mode`` not
offboard, ``goto``, ``orbit``, ``land_start``) or a disarm ends it. PX4 accepts offboard only once
setpoints are streaming, so ``mode offboard`` waits until the stream has run ``offboard_warmup_ms``
(0.5 s) of vehicle time; a test writes its first setpoint before (or at the time of) ``mode
offboard``. Without any setpoint the mode is sent anyway and the vehicle refuses it (recorded).

Faults (the test's ``faults``) are steps too, in time order with the commands: COMMAND_LONG
MAV_CMD_INJECT_FAILURE, with the same ACK rules; each outcome is kept in ``faults``.

Arm settle (``arm_settle_ms``, 0 = off): PX4's pre-arm checks pass while its estimator is still
settling, and a takeoff commanded at that moment can stall a metre above the ground. With a settle
time the arm waits until SYS_STATUS has reported ready-to-arm (MAV_SYS_STATUS_PREARM_CHECK) without
a break for that long; a vehicle that sends no SYS_STATUS is armed at once, and after
``arm_give_up_ms`` of waiting the arm is sent anyway (the vehicle decides). A wait longer than
``LATE_MS`` shifts the commands after it, as a late command does: a test that takes over 24 s
after its mission starts gets its 24 s of mission on PX4 too.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

from uavtest.mavlink_numbers import (
    REPOSITION_FLAGS_CHANGE_MODE,
    FailureType,
    FailureUnit,
    MavFrame,
    PositionTargetMask,
)
from uavtest.runner.events import (
    CommandAck,
    CommandInt,
    CommandLong,
    ManualControl,
    Outgoing,
    PositionTargetGlobal,
    PositionTargetLocal,
)
from uavtest.runner.px4 import (
    AUTO_MODES,
    FORCE_DISARM_MAGIC,
    MODE_FLAG_CUSTOM_MODE_ENABLED,
    PX4_MODES,
    AckResult,
    Cmd,
    result_name,
)
from uavtest.spec.geo import ned_to_geodetic
from uavtest.spec.models import (
    Command,
    CommandAction,
    Fault,
    FaultType,
    FaultUnit,
    FlightMode,
    Goto,
    Home,
    Orbit,
    Setpoint,
    SetpointFrame,
    Sticks,
    YawCommand,
    YawDirection,
)

__all__ = [
    "MISSION_CHECK_MS",
    "MISSION_RECHECK_MS",
    "OFFBOARD_WARMUP_MS",
    "SETPOINT_PERIOD_MS",
    "CommandScheduler",
    "FaultRecord",
    "Refusal",
    "Step",
    "StepKind",
    "arm_command",
    "command_name",
    "disarm_command",
    "expand",
    "fault_command",
    "goto_command",
    "land_start_command",
    "manual_control",
    "mode_command",
    "orbit_command",
    "position_target",
    "speed_command",
    "unsupported_reason",
    "yaw_command",
]

log = logging.getLogger(__name__)

#: offboard setpoints go out every this many ms of vehicle time (20 Hz, as MAVSDK's offboard plugin)
SETPOINT_PERIOD_MS = 50
#: ``mode offboard`` waits until setpoints have streamed this long (PX4 wants them before the switch)
OFFBOARD_WARMUP_MS = 500
NEUTRAL_STICKS = ManualControl(x=0, y=0, z=500, r=0)  # centred sticks, hover throttle
#: a step into an auto mode with the sticks off centre centres them this long first: PX4 takes a
#: stick *moving* (COM_RC_STICK_OV, 30 % of its travel per second, low-passed over 0.1 s) in an
#: auto mode as the pilot taking over (COM_RC_OVERRIDE), so letting go after the switch would
#: undo it; full stick to centre has settled under that rate within 0.5 s of 20 Hz samples
STICK_SETTLE_MS = 600
#: a mode position / altitude / manual with no sticks streaming starts them, centred, this long
#: first: PX4 v1.15 refuses a manual mode without manual control ("Switching to Position is
#: currently not available", mode_requirements.cpp), as the offboard warm-up waits for setpoints
STICK_WARMUP_MS = 500
#: the modes flown by the sticks
MANUAL_MODES = frozenset({FlightMode.MANUAL, FlightMode.ALTITUDE, FlightMode.POSITION})
#: an uploaded mission is usable to PX4 only once its navigator has checked it and the commander's
#: health checks (every 100 ms of vehicle time, Commander.cpp) have cleared ``auto_mission_missing``:
#: until then mode mission is TEMPORARILY_REJECTED ("Switching to Mission is currently not
#: available"), which MAVLink defines as "retrying later should work". Such a refusal within this
#: long after the upload's MISSION_ACK is sent again every ``MISSION_RECHECK_MS``, then recorded.
MISSION_CHECK_MS = 1000
MISSION_RECHECK_MS = 200
LATE_MS = 1000  # a command that runs later than this after its time shifts the rest of the schedule
SCHEDULE_SHIFTED = (
    "the command schedule was shifted: a command ran more than 1 s late because the vehicle was not "
    "ready for it (PX4 SITL answers ~35 s after boot); later commands kept their spacing"
)
#: COMMAND_INT x / y meaning "not given" (PX4 turns it into NaN: the current position)
INT32_MAX = 2**31 - 1


class StepKind(Enum):
    ARM = "arm"
    DISARM = "disarm"
    MODE = "mode"
    SPEED = "speed"
    STICKS = "sticks"
    SETPOINT = "setpoint"
    GOTO = "goto"
    ORBIT = "orbit"
    LAND_START = "land_start"
    YAW = "yaw"
    FAULT = "fault"


#: steps that, once accepted, put the vehicle in a mode other than offboard: setpoints stop
_LEAVES_OFFBOARD = frozenset({StepKind.GOTO, StepKind.ORBIT, StepKind.LAND_START})


@dataclass(frozen=True, slots=True)
class Step:
    kind: StepKind
    label: str
    command: CommandLong | CommandInt | None = None  # None for sticks and setpoints
    mode: FlightMode | None = None
    sticks: ManualControl | None = None
    setpoint: PositionTargetLocal | PositionTargetGlobal | None = None  # time_ms filled when sent
    fault: Fault | None = None


@dataclass(slots=True)
class FaultRecord:
    """One injected fault: when it was due and sent, and how the vehicle answered."""

    unit: str
    type: str
    instance: int
    at: float  # seconds on the vehicle clock, from the test
    sent_ms: int | None = None  # vehicle time it was (first) sent
    ack_ms: int | None = None
    result: str | None = None  # MAV_RESULT name; None: not answered (yet)

    def to_json(self) -> dict[str, object]:
        return dataclasses.asdict(self)


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


#: commands PX4 v1.15's commander answers UNSUPPORTED itself (Commander.cpp has no handler):
#: telling the user to fly them on PX4 would send them nowhere
NOT_IN_PX4_V115 = frozenset({"MAV_CMD_CONDITION_YAW"})


def unsupported_reason(what: str, simulator: str | None) -> str:
    """The bench error for a command the vehicle answered MAV_RESULT_UNSUPPORTED.

    ``what``: "mode offboard" or "MAV_CMD_DO_ORBIT"; ``simulator``: "builtin", "px4" or None
    (a vehicle of unknown kind).
    """
    if what in NOT_IN_PX4_V115:
        return (
            f"{what} is not supported by PX4 v1.15 either (nor by the built-in simulator, which follows it)"
        )
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


def _mask(**ignored: bool) -> int:
    """POSITION_TARGET_TYPEMASK with the IGNORE bit of every field named True (accelerations are
    always ignored, FORCE_SET never set)."""
    mask = PositionTargetMask.AX_IGNORE | PositionTargetMask.AY_IGNORE | PositionTargetMask.AZ_IGNORE
    for name, ignore in ignored.items():
        if ignore:
            mask |= PositionTargetMask[f"{name.upper()}_IGNORE"]
    return int(mask)


def position_target(setpoint: Setpoint) -> PositionTargetLocal | PositionTargetGlobal:
    """The SET_POSITION_TARGET message of a setpoint (time_ms 0: stamped when sent). Degrees
    become radians; a field not given is flagged ignored in type_mask and sent as 0."""
    sp = setpoint

    def v(value: float | None) -> float:
        return 0.0 if value is None else float(value)

    yaw = math.radians(v(sp.yaw))
    yaw_rate = math.radians(v(sp.yaw_rate))
    velocity = dict(vx=sp.vx is None, vy=sp.vy is None, vz=sp.vz is None)
    yaws = dict(yaw=sp.yaw is None, yaw_rate=sp.yaw_rate is None)
    if sp.frame is SetpointFrame.GLOBAL:
        no_position = sp.lat is None
        mask = _mask(x=no_position, y=no_position, z=no_position, **velocity, **yaws)
        return PositionTargetGlobal(
            0, mask, round(v(sp.lat) * 1e7), round(v(sp.lon) * 1e7), v(sp.alt),
            v(sp.vx), v(sp.vy), v(sp.vz), yaw, yaw_rate,
        )  # fmt: skip
    mask = _mask(x=sp.x is None, y=sp.y is None, z=sp.z is None, **velocity, **yaws)
    return PositionTargetLocal(
        0, mask, v(sp.x), v(sp.y), v(sp.z), v(sp.vx), v(sp.vy), v(sp.vz), yaw, yaw_rate
    )


def _global_point(
    home: Home, x: float | None, y: float | None, lat: float | None, lon: float | None
) -> tuple[int, int]:
    """COMMAND_INT x / y (degE7) of a local or global point; INT32_MAX when neither is given."""
    if x is not None and y is not None:
        lat, lon = ned_to_geodetic(x, y, home.lat, home.lon)
    if lat is None or lon is None:
        return INT32_MAX, INT32_MAX
    return round(lat * 1e7), round(lon * 1e7)


def goto_command(goto: Goto, home: Home) -> CommandInt:
    """COMMAND_INT MAV_CMD_DO_REPOSITION as MAVSDK's goto_location and QGC send it: frame
    MAV_FRAME_GLOBAL (altitude AMSL: PX4 ignores the frame and reads z as AMSL), param1 speed
    (-1: the vehicle's), param2 MAV_DO_REPOSITION_FLAGS_CHANGE_MODE (PX4 answers UNSUPPORTED
    without it), param4 yaw in radians as PX4 reads it (NaN: keep the vehicle's)."""
    lat, lon = _global_point(home, goto.x, goto.y, goto.lat, goto.lon)
    amsl = home.alt - goto.z if goto.z is not None else home.alt + (goto.alt or 0.0)
    yaw = math.radians(goto.yaw) if goto.yaw is not None else math.nan
    params = (goto.speed if goto.speed is not None else -1.0, float(REPOSITION_FLAGS_CHANGE_MODE), 0.0, yaw)
    return CommandInt(Cmd.DO_REPOSITION, MavFrame.GLOBAL, params, lat, lon, float(amsl))


def orbit_command(orbit: Orbit, home: Home) -> CommandInt:
    """COMMAND_INT MAV_CMD_DO_ORBIT: param1 radius (negative: counter-clockwise), param2 tangential
    velocity (NaN: PX4's), param3 yaw behaviour NaN (PX4's default), param4 0 orbits (forever);
    x / y the centre (INT32_MAX: where the vehicle is), z AMSL (NaN: the current altitude)."""
    lat, lon = _global_point(home, orbit.x, orbit.y, None, None)
    radius = orbit.radius if orbit.clockwise else -orbit.radius
    velocity = orbit.velocity if orbit.velocity is not None else math.nan
    amsl = home.alt - orbit.z if orbit.z is not None else math.nan
    return CommandInt(Cmd.DO_ORBIT, MavFrame.GLOBAL, (radius, velocity, math.nan, 0.0), lat, lon, amsl)


def land_start_command() -> CommandLong:
    """MAV_CMD_DO_LAND_START: jump to the mission's landing sequence (lat / lon 0: the nearest)."""
    return CommandLong(Cmd.DO_LAND_START, (0.0,) * 7)


_YAW_DIRECTION = {
    YawDirection.COUNTER_CLOCKWISE: -1.0,
    YawDirection.SHORTEST: 0.0,
    YawDirection.CLOCKWISE: 1.0,
}


def yaw_command(yaw: YawCommand) -> CommandLong:
    """MAV_CMD_CONDITION_YAW: param1 heading deg (absolute: 0..360), param2 rate deg/s (0: the
    vehicle's), param3 direction (-1 ccw, 0 shortest, 1 cw), param4 1 relative / 0 absolute."""
    heading = yaw.heading if yaw.relative else yaw.heading % 360.0
    rate = abs(yaw.rate) if yaw.rate is not None else 0.0
    params = (heading, rate, _YAW_DIRECTION[yaw.direction], 1.0 if yaw.relative else 0.0, 0.0, 0.0, 0.0)
    return CommandLong(Cmd.CONDITION_YAW, params)


_FAILURE_UNIT = {
    FaultUnit.GYRO: FailureUnit.SENSOR_GYRO,
    FaultUnit.ACCEL: FailureUnit.SENSOR_ACCEL,
    FaultUnit.MAG: FailureUnit.SENSOR_MAG,
    FaultUnit.BARO: FailureUnit.SENSOR_BARO,
    FaultUnit.GPS: FailureUnit.SENSOR_GPS,
    FaultUnit.OPTICAL_FLOW: FailureUnit.SENSOR_OPTICAL_FLOW,
    FaultUnit.VIO: FailureUnit.SENSOR_VIO,
    FaultUnit.DISTANCE_SENSOR: FailureUnit.SENSOR_DISTANCE_SENSOR,
    FaultUnit.AIRSPEED: FailureUnit.SENSOR_AIRSPEED,
    FaultUnit.BATTERY: FailureUnit.SYSTEM_BATTERY,
    FaultUnit.MOTOR: FailureUnit.SYSTEM_MOTOR,
    FaultUnit.SERVO: FailureUnit.SYSTEM_SERVO,
    FaultUnit.AVOIDANCE: FailureUnit.SYSTEM_AVOIDANCE,
    FaultUnit.RC_SIGNAL: FailureUnit.SYSTEM_RC_SIGNAL,
    FaultUnit.MAVLINK_SIGNAL: FailureUnit.SYSTEM_MAVLINK_SIGNAL,
}


def fault_command(fault: Fault) -> CommandLong:
    """COMMAND_LONG MAV_CMD_INJECT_FAILURE: param1 FAILURE_UNIT, param2 FAILURE_TYPE, param3 instance."""
    unit = _FAILURE_UNIT[fault.unit]
    kind = FailureType[FaultType(fault.type).name]
    return CommandLong(Cmd.INJECT_FAILURE, (float(unit), float(kind), float(fault.instance), 0, 0, 0, 0))


def _label(command: Command | Fault) -> str:
    return fault_label(command) if isinstance(command, Fault) else command.action.value


def fault_label(fault: Fault) -> str:
    instance = f" #{fault.instance}" if fault.instance else ""
    return f"fault {fault.unit.value}{instance} {fault.type.value}"


def manual_control(sticks: Sticks) -> ManualControl:
    return ManualControl(
        x=round(sticks.x * 1000), y=round(sticks.y * 1000), z=round(sticks.z * 1000), r=round(sticks.r * 1000)
    )


def _setpoint_label(sp: Setpoint) -> str:
    given = {k: v for k, v in sp.dump().items() if k != "frame"}
    frame = " global" if sp.frame is SetpointFrame.GLOBAL else ""
    return "setpoint" + frame + " " + ",".join(f"{k}={v:g}" for k, v in given.items())


def expand(command: Command | Fault, home: Home | None = None) -> list[Step]:
    """The steps of one command or fault (before knowing whether the vehicle is armed: arming is
    skipped at run time when it already is). ``home`` places local goto / orbit points."""
    home = home or Home()
    if isinstance(command, Fault):
        return [Step(StepKind.FAULT, fault_label(command), fault_command(command), fault=command)]
    action = command.action
    if action is CommandAction.SETPOINT:
        assert command.setpoint is not None
        sp = command.setpoint
        return [Step(StepKind.SETPOINT, _setpoint_label(sp), setpoint=position_target(sp))]
    if action is CommandAction.GOTO:
        assert command.goto is not None
        point = ",".join(f"{k}={v:g}" for k, v in command.goto.dump().items())
        return [Step(StepKind.GOTO, f"goto {point}", goto_command(command.goto, home))]
    if action is CommandAction.ORBIT:
        assert command.orbit is not None
        o = command.orbit
        label = f"orbit r={o.radius:g}" + ("" if o.clockwise else " counter-clockwise")
        return [Step(StepKind.ORBIT, label, orbit_command(o, home))]
    if action is CommandAction.LAND_START:
        return [Step(StepKind.LAND_START, "land_start", land_start_command())]
    if action is CommandAction.YAW:
        assert command.yaw is not None
        y = command.yaw
        label = f"yaw {y.heading:g}" + (" relative" if y.relative else "")
        return [Step(StepKind.YAW, label, yaw_command(y))]
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
        faults: Sequence[Fault] = (),
        home: Home | None = None,
        ack_timeout_s: float = 1.0,
        send_attempts: int = 5,
        arm_retry_ms: int = 1000,
        arm_give_up_ms: int = 60_000,
        arm_settle_ms: int = 0,
        stick_period_ms: int = 50,
        setpoint_period_ms: int = SETPOINT_PERIOD_MS,
        offboard_warmup_ms: int = OFFBOARD_WARMUP_MS,
        simulator: str | None = None,
    ) -> None:
        # commands before faults at the same time (stable sort)
        self._pending: deque[Command | Fault] = deque(sorted([*commands, *faults], key=lambda c: c.at))
        self.home = home or Home()
        self._steps: deque[Step] = deque()
        self.ack_timeout_s = ack_timeout_s
        self.send_attempts = send_attempts
        self.arm_retry_ms = arm_retry_ms
        self.arm_give_up_ms = arm_give_up_ms
        self.arm_settle_ms = arm_settle_ms
        self.stick_period_ms = stick_period_ms
        self.setpoint_period_ms = setpoint_period_ms
        self.offboard_warmup_ms = offboard_warmup_ms
        self.simulator = simulator  # "builtin" / "px4" / None: how UNSUPPORTED is worded
        self.error: str | None = None
        self.notes: list[str] = []  # refusals the vehicle made; shown in the log and the result
        self.refusals: list[Refusal] = []  # the same, structured (for the verdict's reason)
        self.gave_up: Refusal | None = None  # an arm refused until arm_give_up_ms: no flight
        #: vehicle ms the vehicle accepted the test's mission (``MISSION_CHECK_MS``); None: no upload
        self.mission_accepted_ms: int | None = None
        self._sent_ms = 0  # vehicle time the current step was last sent
        self.sent: list[tuple[int, str]] = []  # (vehicle ms, label) of every step started
        self.sticks: ManualControl | None = None
        self._last_stick_ms = -math.inf
        self._sticks_centred_ms: int | None = None  # vehicle time the runner centred them
        self._sticks_since_ms: int | None = None  # vehicle time the sticks started streaming
        self.setpoint: PositionTargetLocal | PositionTargetGlobal | None = None  # being streamed
        self._last_setpoint_ms = -math.inf
        self._setpoint_since_ms: int | None = None  # vehicle time the stream started
        self._hold_until_ms: float | None = None  # mode offboard waits for the stream to warm up
        self.faults: list[FaultRecord] = []  # every fault sent, with its answer
        self._current: Step | None = None
        self._confirmation = 0
        self._ack_deadline = math.inf
        self._retry_at_ms: float | None = None  # a refused arm (or mode mission) waits for this vehicle time
        self._first_refusal_ms: int | None = None
        self._status_seen = False  # the vehicle reports its pre-arm state (SYS_STATUS)
        self._ready_since_ms: int | None = None  # vehicle time it became ready to arm (None: not ready)
        self._waiting_since_ms: int | None = None  # an arm waits for the vehicle to settle, since then
        self.shift_ms = 0.0  # how far the schedule moved because a command ran late (``_take_next``)
        #: vehicle ms the flight waited for the vehicle to settle before arming: the runner's
        #: wait, which the test's timeout does not count (PX4 needs it, the built-in vehicle not)
        self.settle_wait_ms = 0.0
        self.delays: list[str] = []  # a note per shift, with its times (the runner's log)
        self.warnings: list[str] = []  # the same, worded once for the result and the run's summary

    @property
    def idle(self) -> bool:
        """No command left to run or waiting for its ACK (sticks may still be streaming)."""
        return not self._pending and not self._steps and self._current is None

    @property
    def next_at_ms(self) -> float:
        """Vehicle time of the next command not yet due (inf when none)."""
        return self._due_ms(self._pending[0]) if self._pending else math.inf

    def _due_ms(self, command: Command | Fault) -> float:
        """When ``command`` is due: its ``at`` on the vehicle clock, plus the schedule's shift."""
        return command.at * 1000.0 + self.shift_ms

    def _take_next(self, now_ms: int) -> None:
        """Start the next command; one that runs more than ``LATE_MS`` late shifts the rest.

        A command runs late when the vehicle was not ready for it: PX4 SITL answers only ~35 s
        after boot and the runner then waits for its estimator to settle before arming, so a
        schedule written from boot would otherwise fire all at once. The later commands keep
        their spacing from this one; each shift is noted (``delays``) and reported.
        """
        command = self._pending.popleft()
        self._shift(now_ms - self._due_ms(command), now_ms, f"{_label(command)} ran", at=command.at)
        self._steps.extend(expand(command, self.home))

    def _shift(self, late_ms: float, now_ms: int, what: str, at: float | None = None) -> None:
        """Move the commands not yet started ``late_ms`` later when that is more than ``LATE_MS``:
        the vehicle was not ready (``at``: the late command's own time; None: the wait of one
        already started, an arm settling, which the commands after it wait out too)."""
        if late_ms <= LATE_MS:
            return
        self.shift_ms += late_ms
        since = f"from t={at:g} s on" if at is not None else "still to come"
        note = (
            f"commands {since} run {self.shift_ms / 1000:.1f} s late: the vehicle was not ready for "
            f"them ({what} at t={now_ms / 1000:.1f} s); later commands keep their spacing"
        )
        log.warning("%s", note)
        self.delays.append(note)
        if SCHEDULE_SHIFTED not in self.warnings:
            self.warnings.append(SCHEDULE_SHIFTED)

    def settle_waited_ms(self, now_ms: float) -> float:
        """Vehicle ms the arm has waited for the vehicle to settle so far, a wait going on now
        included (``settle_wait_ms``)."""
        going = now_ms - self._waiting_since_ms if self._waiting_since_ms is not None else 0.0
        return self.settle_wait_ms + max(0.0, going)

    @property
    def busy(self) -> bool:
        """A command sequence is running: a step waits for its ACK (not for a retry time), or more
        steps are queued behind it."""
        return bool(self._steps) or (self._current is not None and self._retry_at_ms is None)

    @property
    def next_event_ms(self) -> float:
        """Vehicle time of the next thing to do on the vehicle clock: a command not yet due, a
        refused arm's retry, a mode offboard waiting for setpoints, the next setpoint (inf when
        none)."""
        retry = self._retry_at_ms if self._retry_at_ms is not None else math.inf
        hold = self._hold_until_ms if self._hold_until_ms is not None else math.inf
        return min(self.next_at_ms, retry, hold, self.next_setpoint_ms)

    @property
    def next_setpoint_ms(self) -> float:
        """Vehicle time the next offboard setpoint is due (inf when none is streaming)."""
        if self.setpoint is None:
            return math.inf
        return self._last_setpoint_ms + self.setpoint_period_ms

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
        if self._current is not None:
            out += self._resend_if_due(now_ms, wall)
        while self._current is None and not self.error:
            if not self._steps:  # the previous command is done: take the next one that is due
                if not self._pending or self._due_ms(self._pending[0]) > now_ms:
                    break
                self._take_next(now_ms)
                continue
            if self._warming_up(self._steps[0], now_ms):
                break
            out += self._start(self._steps.popleft(), now_ms, wall, armed=armed)
        if self.sticks is not None and now_ms - self._last_stick_ms >= self.stick_period_ms:
            self._last_stick_ms = now_ms
            out.append(self.sticks)
        if self.setpoint is not None and now_ms - self._last_setpoint_ms >= self.setpoint_period_ms:
            self._last_setpoint_ms = now_ms
            out.append(dataclasses.replace(self.setpoint, time_ms=now_ms))
        return out

    def _warming_up(self, step: Step, now_ms: int) -> bool:
        """A mode offboard waits until setpoints have streamed ``offboard_warmup_ms``; a step into
        an auto mode while the sticks are off centre centres them and waits ``STICK_SETTLE_MS``
        (a ground station's joystick let go before the switch, not after it)."""
        self._hold_until_ms = None
        mode_auto = step.kind is StepKind.MODE and step.mode in AUTO_MODES
        enters_auto = mode_auto or step.kind in _LEAVES_OFFBOARD
        if enters_auto and self.sticks is not None:
            if self.sticks != NEUTRAL_STICKS:
                log.info(
                    "t=%.2f s: sticks centred %d ms before %s (moving sticks take an auto mode over: "
                    "COM_RC_OVERRIDE)",
                    now_ms / 1000,
                    STICK_SETTLE_MS,
                    step.label,
                )
                self._centre_sticks(now_ms)
            if self._sticks_centred_ms is None:
                return False
            return self._hold_until(self._sticks_centred_ms + STICK_SETTLE_MS, now_ms)
        if step.kind is StepKind.MODE and step.mode in MANUAL_MODES:
            if self.sticks is None:
                log.info(
                    "t=%.2f s: sticks streamed, centred, %d ms before %s (PX4 refuses a manual mode "
                    "without manual control)",
                    now_ms / 1000,
                    STICK_WARMUP_MS,
                    step.label,
                )
                self._centre_sticks(now_ms)
            if self._sticks_since_ms is None:
                return False
            return self._hold_until(self._sticks_since_ms + STICK_WARMUP_MS, now_ms)
        if step.kind is not StepKind.MODE or step.mode is not FlightMode.OFFBOARD:
            return False
        if self._setpoint_since_ms is None:
            log.warning(
                "t=%.2f s: %s with no setpoint streaming: PX4 refuses offboard until setpoints arrive "
                "(write an action: setpoint before it)",
                now_ms / 1000,
                step.label,
            )
            return False
        return self._hold_until(self._setpoint_since_ms + self.offboard_warmup_ms, now_ms)

    def _centre_sticks(self, now_ms: int) -> None:
        """Stream centred sticks from now on (sent at once; started now if none were streaming)."""
        if self.sticks is None:
            self._sticks_since_ms = now_ms
        self.sticks = NEUTRAL_STICKS
        self._last_stick_ms = -math.inf
        self._sticks_centred_ms = now_ms

    def _hold_until(self, ready_ms: int, now_ms: int) -> bool:
        """Hold the next step until ``ready_ms`` (True while it must wait)."""
        if now_ms >= ready_ms:
            return False
        self._hold_until_ms = ready_ms
        return True

    def _stop_setpoints(self) -> None:
        self.setpoint = None
        self._setpoint_since_ms = None
        self._last_setpoint_ms = -math.inf

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
            if self.sticks is None:
                self._sticks_since_ms = now_ms
            self.sticks = step.sticks
            self._last_stick_ms = -math.inf
            self._sticks_centred_ms = None
            return []
        if step.kind is StepKind.SETPOINT:
            if self.setpoint is None:
                self._setpoint_since_ms = now_ms
            self.setpoint = step.setpoint
            self._last_setpoint_ms = -math.inf  # the new one goes out at once (update streams it)
            return []
        if step.kind is StepKind.DISARM:
            self.sticks = None
            self._sticks_since_ms = None
            self._stop_setpoints()
        if step.kind is StepKind.FAULT:
            f = step.fault
            assert f is not None
            self.faults.append(FaultRecord(f.unit.value, f.type.value, f.instance, f.at, sent_ms=now_ms))
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
                waited = now_ms - self._waiting_since_ms
                self.settle_wait_ms += waited
                self._shift(waited, now_ms, f"{step.label} waited to arm")
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
            if step.kind is StepKind.FAULT:
                self.error = (
                    f"no COMMAND_ACK for {step.label} (MAV_CMD_INJECT_FAILURE) after {self.send_attempts} "
                    "tries: the vehicle did not confirm the failure (PX4 answers only for the units "
                    "one of its modules simulates)"
                )
                self._ack_deadline = math.inf
                return []
            self.error = f"no COMMAND_ACK for {step.label} after {self.send_attempts} tries"
            self._ack_deadline = math.inf
            return []
        self._confirmation += 1
        self._ack_deadline = wall + self.ack_timeout_s
        log.warning("no ACK for %s; sending it again (%d)", step.label, self._confirmation + 1)
        c = step.command
        if isinstance(c, CommandInt):
            return [c]  # COMMAND_INT has no confirmation counter
        return [CommandLong(c.command, c.params, confirmation=self._confirmation)]

    def handle_ack(self, ack: CommandAck, now_ms: int, wall: float) -> Step | None:
        """Take a COMMAND_ACK; returns the step it accepted (None otherwise)."""
        step = self._current
        if step is None or step.command is None or ack.command != step.command.command:
            return None
        result = ack.result
        if step.kind is StepKind.FAULT and result != AckResult.IN_PROGRESS and self.faults:
            self.faults[-1].ack_ms = now_ms
            self.faults[-1].result = result_name(AckResult, result)
        if result == AckResult.ACCEPTED:
            if self._retrying_refusal():
                self.refusals.pop()  # the vehicle armed in the end
            if step.kind is StepKind.MODE and step.mode in AUTO_MODES and self.sticks is not None:
                # a ground station's joystick keeps sending, centred: PX4 ignores centred sticks in
                # the auto modes, and stopping them would be an RC loss (NAV_RCL_ACT) there
                self.sticks = NEUTRAL_STICKS
            if (step.kind is StepKind.MODE and step.mode is not FlightMode.OFFBOARD) or (
                step.kind in _LEAVES_OFFBOARD
            ):
                self._stop_setpoints()
            self._done()
            return step
        if result == AckResult.IN_PROGRESS:
            self._ack_deadline = wall + 5 * self.ack_timeout_s
            return None
        name = result_name(AckResult, result)
        if result == AckResult.UNSUPPORTED:
            if step.kind is StepKind.MODE:
                what = step.label
            elif step.kind is StepKind.FAULT:
                assert step.fault is not None
                what = f"failure injection of {step.fault.unit.value}/{step.fault.type.value}"
            else:
                what = command_name(ack.command)
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
        if self._mission_still_checked(step, result, now_ms):
            log.info(
                "t=%.2f s: vehicle refused %s (%s) %d ms after accepting the mission (PX4 checks a new "
                "mission first); trying again in %d ms",
                now_ms / 1000,
                step.label,
                name,
                now_ms - (self.mission_accepted_ms or 0),
                MISSION_RECHECK_MS,
            )
            self._retry_at_ms = now_ms + MISSION_RECHECK_MS
            self._ack_deadline = math.inf
            return None
        note = f"t={now_ms / 1000:.2f} s: vehicle refused {step.label} (COMMAND_ACK {name})"
        log.warning(note)
        self.notes.append(note)
        # the step's first send (``sent``), a mode mission sent again included: the vehicle's words
        # since then are quoted with the refusal
        self.refusals.append(Refusal(step.label, name, self.sent[-1][0], now_ms))
        self._done()
        return None

    def _mission_still_checked(self, step: Step, result: int, now_ms: int) -> bool:
        """A mode mission refused for now while the vehicle may still be checking the mission just
        uploaded (``MISSION_CHECK_MS``): sent again rather than recorded."""
        return (
            step.kind is StepKind.MODE
            and step.mode is FlightMode.MISSION
            and result == AckResult.TEMPORARILY_REJECTED
            and self.mission_accepted_ms is not None
            and now_ms - self.mission_accepted_ms < MISSION_CHECK_MS
        )

    def _retrying_refusal(self) -> bool:
        return bool(self.refusals) and not self.refusals[-1].final

    def _done(self) -> None:
        self._current = None
        self._waiting_since_ms = None
        self._ack_deadline = math.inf
        self._retry_at_ms = None
