"""Stage 4: timed commands on the vehicle clock, Aerialist semantics, ACK handling, sticks."""

from __future__ import annotations

import itertools

import pytest

from uavtest.runner.commands import (
    MISSION_CHECK_MS,
    MISSION_RECHECK_MS,
    STICK_SETTLE_MS,
    STICK_WARMUP_MS,
    CommandScheduler,
    Refusal,
    arm_command,
    command_name,
    disarm_command,
    mode_command,
    speed_command,
    unsupported_reason,
)
from uavtest.runner.events import CommandAck, CommandLong, ManualControl
from uavtest.runner.px4 import AckResult, Cmd, custom_mode, mode_name
from uavtest.spec.models import Command, FlightMode, Sticks

ARM = Cmd.COMPONENT_ARM_DISARM
MODE = Cmd.DO_SET_MODE


def cmd(at: float, action: str, **kw: object) -> Command:
    return Command.model_validate({"at": at, "action": action, **kw})


def test_px4_mode_encoding() -> None:
    assert mode_command(FlightMode.MISSION).params[:3] == (1.0, 4.0, 4.0)  # custom flag, AUTO, MISSION
    assert mode_command(FlightMode.POSITION).params[:3] == (1.0, 3.0, 0.0)
    assert custom_mode(FlightMode.HOLD) == (4 << 16) | (3 << 24)
    assert mode_name(custom_mode(FlightMode.RETURN)) == "return"
    assert disarm_command(force=True).params[:2] == (0.0, 21196.0)
    assert speed_command(5).params[:3] == (1.0, 5.0, -1.0)


def test_commands_wait_for_their_vehicle_time() -> None:
    s = CommandScheduler([cmd(2.0, "speed", speed=3)])
    assert s.update(1999, 0.0, armed=True) == []
    assert s.update(2000, 0.0, armed=True) == [speed_command(3)]


def test_a_command_whose_time_has_passed_runs_at_once() -> None:
    s = CommandScheduler([cmd(0.000001, "mode", mode="hold")])
    assert s.update(35_000, 0.0, armed=True) == [mode_command(FlightMode.HOLD)]


def test_mode_mission_while_disarmed_arms_first_then_switches() -> None:
    s = CommandScheduler([cmd(1.0, "mode", mode="mission")])
    assert s.update(1000, 0.0, armed=False) == [arm_command()]
    assert s.update(1050, 0.1, armed=False) == []  # waiting for the ACK
    s.handle_ack(CommandAck(ARM, AckResult.ACCEPTED), 1050, 0.1)
    assert s.update(1100, 0.2, armed=True) == [mode_command(FlightMode.MISSION)]
    s.handle_ack(CommandAck(MODE, AckResult.ACCEPTED), 1100, 0.2)
    assert s.idle
    assert [label for _, label in s.sent] == ["arm (for mode mission)", "mode mission"]


def test_mode_mission_while_armed_only_switches() -> None:
    s = CommandScheduler([cmd(1.0, "mode", mode="takeoff")])
    assert s.update(1000, 0.0, armed=True) == [mode_command(FlightMode.TAKEOFF)]


def test_a_refused_arm_is_retried_every_second_of_vehicle_time_then_given_up() -> None:
    s = CommandScheduler([cmd(0, "arm")], arm_retry_ms=1000, arm_give_up_ms=3000)
    assert s.update(0, 0.0, armed=False) == [arm_command()]
    s.handle_ack(CommandAck(ARM, AckResult.TEMPORARILY_REJECTED), 10, 0.0)
    assert s.update(900, 5.0, armed=False) == []  # wall time passing does not resend: vehicle time does
    assert s.update(1010, 5.0, armed=False) == [arm_command()]
    s.handle_ack(CommandAck(ARM, AckResult.DENIED), 1020, 5.0)
    assert s.update(2020, 5.0, armed=False) == [arm_command()]
    assert len(s.refusals) == 1 and not s.refusals[0].final  # one entry while retried
    s.handle_ack(CommandAck(ARM, AckResult.DENIED), 3010, 5.0)
    # the vehicle refused: not a bench error, the flight is over (no flight), the verdict will say why
    assert s.error is None
    assert s.gave_up == Refusal("arm", "DENIED", sent_ms=2020, ack_ms=3010)
    assert s.refusals == [s.gave_up] and s.idle
    assert "vehicle refused arm for 3 s (COMMAND_ACK DENIED)" in s.notes[-1]


def test_an_arm_accepted_after_refusals_leaves_no_refusal() -> None:
    s = CommandScheduler([cmd(0, "arm")], arm_retry_ms=1000)
    s.update(0, 0.0, armed=False)
    s.handle_ack(CommandAck(ARM, AckResult.TEMPORARILY_REJECTED), 10, 0.0)
    s.update(1010, 1.0, armed=False)
    s.handle_ack(CommandAck(ARM, AckResult.ACCEPTED), 1020, 1.0)
    assert s.refusals == [] and s.gave_up is None and s.error is None


def test_a_command_without_ack_is_resent_with_a_rising_confirmation_then_is_an_error() -> None:
    s = CommandScheduler([cmd(0, "mode", mode="hold")], ack_timeout_s=1.0, send_attempts=3)
    s.update(0, 0.0, armed=True)
    assert s.update(10, 0.5, armed=True) == []
    resent = s.update(20, 1.0, armed=True)
    assert resent == [CommandLong(MODE, mode_command(FlightMode.HOLD).params, confirmation=1)]
    assert s.update(30, 2.0, armed=True)[0].confirmation == 2  # type: ignore[union-attr]
    assert s.update(40, 3.0, armed=True) == []
    assert s.error == "no COMMAND_ACK for mode hold after 3 tries"


def test_an_unsupported_command_is_a_bench_error_and_a_denied_mode_a_refusal() -> None:
    s = CommandScheduler([cmd(0, "mode", mode="offboard"), cmd(1, "speed", speed=2)])
    s.update(0, 0.0, armed=True)
    s.handle_ack(CommandAck(MODE, AckResult.DENIED), 0, 0.0)
    assert s.error is None and "refused mode offboard" in s.notes[0]
    assert s.refusals == [Refusal("mode offboard", "DENIED", sent_ms=0, ack_ms=0)]
    s.update(1000, 0.0, armed=True)
    s.handle_ack(CommandAck(Cmd.DO_CHANGE_SPEED, AckResult.UNSUPPORTED), 1000, 0.0)
    assert s.error == "the vehicle does not support MAV_CMD_DO_CHANGE_SPEED (COMMAND_ACK UNSUPPORTED)"


@pytest.mark.parametrize(
    ("simulator", "step", "command", "reason"),
    [
        (
            "builtin",
            cmd(0, "mode", mode="offboard"),
            MODE,
            "the built-in simulator does not support mode offboard; fly this test with simulator: px4",
        ),
        (
            "builtin",
            cmd(0, "speed", speed=3),
            Cmd.DO_CHANGE_SPEED,
            "the built-in simulator does not support MAV_CMD_DO_CHANGE_SPEED; "
            "fly this test with simulator: px4",
        ),
        ("px4", cmd(0, "mode", mode="offboard"), MODE, "PX4 does not support mode offboard"),
    ],
)
def test_unsupported_is_a_bench_error_naming_the_simulator_and_the_command(
    simulator: str, step: Command, command: int, reason: str
) -> None:
    """A fake ACK stream: the vehicle answers MAV_RESULT_UNSUPPORTED to the command."""
    s = CommandScheduler([step, cmd(5, "disarm")], simulator=simulator)
    (sent,) = s.update(0, 0.0, armed=True)
    assert isinstance(sent, CommandLong) and sent.command == command
    s.handle_ack(CommandAck(command, AckResult.UNSUPPORTED), 0, 0.0)
    assert s.error == reason
    assert s.update(6000, 1.0, armed=True) == []  # nothing more is sent after a bench error


def test_unsupported_names_any_mav_cmd() -> None:
    assert command_name(34) == "MAV_CMD_DO_ORBIT"
    assert command_name(9999) == "MAV_CMD 9999"  # no name in our table
    assert command_name(Cmd.COMPONENT_ARM_DISARM) == "MAV_CMD_COMPONENT_ARM_DISARM"
    assert unsupported_reason("MAV_CMD_DO_ORBIT", "builtin") == (
        "the built-in simulator does not support MAV_CMD_DO_ORBIT; fly this test with simulator: px4"
    )
    assert unsupported_reason("MAV_CMD_DO_ORBIT", "px4") == "PX4 does not support MAV_CMD_DO_ORBIT"


@pytest.mark.parametrize("result", [AckResult.DENIED, AckResult.TEMPORARILY_REJECTED, AckResult.FAILED])
def test_every_refusal_of_a_mode_is_recorded_not_an_error(result: AckResult) -> None:
    s = CommandScheduler([cmd(2, "mode", mode="position")])
    s.update(2000, 0.0, armed=True)  # no sticks yet: they start, centred; the mode waits for them
    s.update(2000 + STICK_WARMUP_MS, 0.0, armed=True)
    s.handle_ack(CommandAck(MODE, result), 2510, 0.0)
    assert s.error is None and s.idle
    assert s.refusals == [Refusal("mode position", result.name, sent_ms=2500, ack_ms=2510)]


def test_a_manual_mode_gets_sticks_first_as_px4_wants_manual_control() -> None:
    """PX4 v1.15 refuses position / altitude / manual mode without manual control ("Switching to
    Position is currently not available"): with no sticks streaming, the runner starts them
    centred and sends the mode STICK_WARMUP_MS later; with sticks already there, at once."""
    s = CommandScheduler([cmd(2.0, "mode", mode="position")])
    out = [(t, m) for t in range(0, 3000, 10) for m in s.update(t, t / 1000, armed=True)]
    sticks = [(t, m) for t, m in out if isinstance(m, ManualControl)]
    mode = [t for t, m in out if m == mode_command(FlightMode.POSITION)]
    assert sticks[0][0] == 2000 and {m for _, m in sticks} == {ManualControl(0, 0, 500, 0)}
    assert mode == [2000 + STICK_WARMUP_MS]
    t = CommandScheduler([cmd(1.0, "sticks", sticks=Sticks(x=0.0, z=0.5)), cmd(2.0, "mode", mode="altitude")])
    out = [(k, m) for k in range(0, 3000, 10) for m in t.update(k, k / 1000, armed=True)]
    assert [k for k, m in out if m == mode_command(FlightMode.ALTITUDE)] == [2000]


def test_sticks_stream_at_20_hz_of_vehicle_time_and_centre_in_an_auto_mode() -> None:
    """Before a switch to an auto mode the sticks are centred and given STICK_SETTLE_MS to settle
    (PX4 takes sticks moving in an auto mode as the pilot taking over, COM_RC_OVERRIDE); they keep
    coming, centred (a joystick on a ground station keeps sending: stopping them would be an RC
    loss to PX4); a disarm ends them."""
    s = CommandScheduler(
        [
            cmd(1.0, "sticks", sticks=Sticks(x=0.5, y=-1, z=0.5, r=0)),
            cmd(3.0, "mode", mode="land"),
            cmd(5.0, "disarm"),
        ]
    )
    sent: list[tuple[int, ManualControl]] = []
    mode_sent: list[int] = []
    for t in range(0, 6000, 10):  # telemetry every 10 ms of vehicle time
        for msg in s.update(t, t / 1000, armed=True):
            if isinstance(msg, ManualControl):
                sent.append((t, msg))
            elif msg == mode_command(FlightMode.LAND):
                mode_sent.append(t)
                s.handle_ack(CommandAck(MODE, AckResult.ACCEPTED), t, t / 1000)
            elif isinstance(msg, CommandLong) and msg.command == ARM:
                s.handle_ack(CommandAck(ARM, AckResult.ACCEPTED), t, t / 1000)
    times = [t for t, _ in sent]
    assert times[0] == 1000 and all(b - a == 50 for a, b in itertools.pairwise(times))
    assert all(m == ManualControl(500, -1000, 500, 0) for t, m in sent if t < 3000)
    assert all(m == ManualControl(0, 0, 500, 0) for t, m in sent if t >= 3000)
    assert mode_sent == [3000 + STICK_SETTLE_MS]  # once the centred sticks have settled
    assert times[-1] < 5000, "a disarm ends them"


def test_ack_of_another_command_is_not_taken_for_ours() -> None:
    s = CommandScheduler([cmd(0, "mode", mode="hold")])
    s.update(0, 0.0, armed=True)
    s.handle_ack(CommandAck(ARM, AckResult.ACCEPTED), 0, 0.0)
    assert not s.idle


def test_with_an_arm_settle_the_arm_waits_until_the_vehicle_has_been_ready_that_long() -> None:
    s = CommandScheduler([cmd(1.0, "mode", mode="mission")], arm_settle_ms=10_000, arm_retry_ms=1000)
    s.on_sys_status(False, 500)
    assert s.update(1000, 0.0, armed=False) == []  # PX4 still failing its pre-arm checks
    s.on_sys_status(True, 35_600)  # ready ...
    s.on_sys_status(False, 36_000)  # ... but not for good: the settle starts again
    s.on_sys_status(True, 37_000)
    assert s.update(36_500, 0.0, armed=False) == []
    assert s.update(46_999, 0.0, armed=False) == []
    s.on_sys_status(True, 47_000)  # still ready: the clock does not restart
    assert s.update(47_000, 0.0, armed=False) == [arm_command()]
    s.handle_ack(CommandAck(ARM, AckResult.ACCEPTED), 47_050, 0.1)
    assert s.update(47_100, 0.1, armed=True) == [mode_command(FlightMode.MISSION)]
    assert s.sent[0] == (47_000, "arm (for mode mission)")


def test_the_commands_after_a_settling_arm_keep_their_spacing_from_it() -> None:
    """PX4 SITL armed 11.7 s after its mission command was due (the settle): the pilot's switch
    to position mode 24 s after the mission must still come 24 s after it, not 12 s."""
    from uavtest.runner.commands import SCHEDULE_SHIFTED

    s = CommandScheduler(
        [cmd(1.0, "mode", mode="mission"), cmd(25.0, "mode", mode="hold")], arm_settle_ms=10_000
    )
    s.on_sys_status(True, 36_800)
    sent: list[int] = []
    for now in range(35_100, 90_000, 100):  # the runner's flight starts at 35.1 s
        for _msg in s.update(now, now / 1000, armed=bool(sent)):
            sent.append(now)
        if s._current is not None and s._current.command is not None and s._retry_at_ms is None:
            s.handle_ack(CommandAck(s._current.command.command, AckResult.ACCEPTED), now, now / 1000)
    assert sent[0] == 46_800, "armed once ready for 10 s"
    assert sent[-1] - sent[0] == 24_000, "hold comes 24 s after the arm and the mission, as written"
    assert s.warnings == [SCHEDULE_SHIFTED] and "waited to arm" in s.delays[-1]


def test_the_arm_settle_does_not_hold_a_vehicle_without_sys_status_or_forever() -> None:
    silent = CommandScheduler([cmd(1.0, "arm")], arm_settle_ms=10_000)
    assert silent.update(1000, 0.0, armed=False) == [arm_command()]  # no SYS_STATUS: armed when due
    never = CommandScheduler([cmd(1.0, "arm")], arm_settle_ms=10_000, arm_give_up_ms=5000)
    never.on_sys_status(False, 0)
    assert never.update(1000, 0.0, armed=False) == []
    assert never.update(5000, 0.0, armed=False) == []
    assert never.update(6000, 0.0, armed=False) == [arm_command()]  # the vehicle decides now
    assert never.error is None


def test_without_an_arm_settle_sys_status_changes_nothing() -> None:
    s = CommandScheduler([cmd(1.0, "arm")])
    s.on_sys_status(False, 0)
    assert s.update(1000, 0.0, armed=False) == [arm_command()]


def test_a_schedule_the_vehicle_was_not_ready_for_shifts_and_keeps_its_spacing() -> None:
    """PX4 SITL answers ~35 s after boot: commands written from boot run late, the rest follows."""
    from uavtest.runner.commands import SCHEDULE_SHIFTED, CommandScheduler

    cmds = [
        Command(at=12, action="arm"),
        Command(at=14, action="mode", mode="takeoff"),
        Command(at=30, action="mode", mode="land"),
    ]
    sched = CommandScheduler(cmds)
    sent: list[tuple[int, int]] = []
    for now in range(46_000, 80_000, 100):  # the flight stage starts at 46 s
        for msg in sched.update(now, now / 1000, armed=now > 46_000):
            sent.append((now, msg.command))
        if sched._current is not None:
            sched.handle_ack(CommandAck(sched._current.command.command, 0), now, now / 1000)
    times = [t for t, _ in sent]
    assert times[0] == 46_000, "the first overdue command runs at once"
    assert times[-1] - times[0] == 18_000, "the land keeps its 18 s after the arm"
    assert sched.warnings == [SCHEDULE_SHIFTED] and "34.0 s late" in sched.delays[0]


def test_a_command_less_than_a_second_late_does_not_shift_the_schedule() -> None:
    from uavtest.runner.commands import CommandScheduler

    sched = CommandScheduler([Command(at=1, action="arm"), Command(at=3, action="mode", mode="land")])
    sent = []
    for now in range(1_500, 5_000, 100):  # the built-in simulator is ready at 1.5 s
        for _msg in sched.update(now, now / 1000, armed=now > 1_500):
            sent.append(now)
        if sched._current is not None:
            sched.handle_ack(CommandAck(sched._current.command.command, 0), now, now / 1000)
    assert sent == [1_500, 3_000] and sched.warnings == []


def test_unsupported_by_px4_itself_does_not_send_the_user_to_px4() -> None:
    reason = unsupported_reason("MAV_CMD_CONDITION_YAW", "builtin")
    assert "not supported by PX4 v1.15 either" in reason and "fly this test with simulator: px4" not in reason


def test_mode_mission_refused_while_px4_checks_the_new_mission_is_sent_again() -> None:
    """PX4 v1.15 answers mode mission TEMPORARILY_REJECTED until its navigator has checked the
    mission just uploaded and the commander's next health check (every 100 ms) has seen it: a runner
    that connects late arms and switches within milliseconds of the upload. Sent again, not recorded."""
    s = CommandScheduler([cmd(1.0, "mode", mode="mission")])
    s.mission_accepted_ms = 900
    assert s.update(1000, 0.0, armed=True) == [mode_command(FlightMode.MISSION)]
    s.handle_ack(CommandAck(MODE, AckResult.TEMPORARILY_REJECTED), 1010, 0.0)
    assert s.refusals == [] and s.notes == [] and not s.idle
    assert s.update(1010 + MISSION_RECHECK_MS - 1, 5.0, armed=True) == []  # vehicle time, not wall time
    assert s.update(1010 + MISSION_RECHECK_MS, 5.0, armed=True) == [mode_command(FlightMode.MISSION)]
    assert s.handle_ack(CommandAck(MODE, AckResult.ACCEPTED), 1220, 5.0) is not None
    assert s.idle and s.refusals == [] and s.error is None


def test_mode_mission_refused_long_after_the_upload_or_denied_is_a_refusal() -> None:
    late = CommandScheduler([cmd(5.0, "mode", mode="mission")])
    late.mission_accepted_ms = 900
    late.update(5000, 0.0, armed=True)
    late.handle_ack(CommandAck(MODE, AckResult.TEMPORARILY_REJECTED), 5010, 0.0)
    assert late.idle and late.refusals == [Refusal("mode mission", "TEMPORARILY_REJECTED", 5000, 5010)]
    # refused again and again while checked: recorded once the check has had its time
    s = CommandScheduler([cmd(1.0, "mode", mode="mission")])
    s.mission_accepted_ms = 1000
    t = 1000
    s.update(t, 0.0, armed=True)
    while not s.idle:
        s.handle_ack(CommandAck(MODE, AckResult.TEMPORARILY_REJECTED), t, 0.0)
        t += MISSION_RECHECK_MS
        s.update(t, 0.0, armed=True)
    (refusal,) = s.refusals
    assert refusal.result == "TEMPORARILY_REJECTED" and refusal.sent_ms == 1000  # its first send
    assert refusal.ack_ms - 1000 >= MISSION_CHECK_MS
    assert [label for _, label in s.sent] == ["mode mission"]  # one step, sent again
    denied = CommandScheduler([cmd(1.0, "mode", mode="mission")])
    denied.mission_accepted_ms = 990
    denied.update(1000, 0.0, armed=True)
    denied.handle_ack(CommandAck(MODE, AckResult.DENIED), 1000, 0.0)
    assert denied.idle and [r.result for r in denied.refusals] == ["DENIED"]
    # without an upload (a test with no mission) the refusal is the vehicle's answer at once
    none = CommandScheduler([cmd(1.0, "mode", mode="mission")])
    none.update(1000, 0.0, armed=True)
    none.handle_ack(CommandAck(MODE, AckResult.TEMPORARILY_REJECTED), 1000, 0.0)
    assert none.idle and len(none.refusals) == 1
