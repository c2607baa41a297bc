"""The runner core: stages, lockstep grants, settling the verdict — fed scripted messages."""

from __future__ import annotations

from uavtest.runner.core import CoreConfig, Ending, ReplicaCore, Stage
from uavtest.runner.events import (
    CommandAck,
    CommandLong,
    GcsHeartbeat,
    Incoming,
    LocalPosition,
    LockstepAnnounce,
    LockstepGrant,
    MissionItemInt,
    Outgoing,
    ParamRequestRead,
)
from uavtest.runner.mission import FRAME_GLOBAL_RELATIVE_ALT_INT
from uavtest.runner.px4 import AckResult, Cmd, ParamType
from uavtest.spec.models import Command, Obstacle

from .vehicle import ScriptedVehicle, boot, exchange, heartbeat

MISSION = [
    MissionItemInt(0, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_TAKEOFF, z=10),
    MissionItemInt(1, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_WAYPOINT, x=473979000, y=85455940, z=10),
]
START_MISSION = [Command(at=0, action="mode", mode="mission")]


def config(**kw: object) -> CoreConfig:
    base: dict[str, object] = {
        "params": {"NAV_ACC_RAD": 2.0, "COM_DISARM_LAND": 1},
        "mission": MISSION,
        "commands": START_MISSION,
    }
    base.update(kw)
    return CoreConfig(**base)  # type: ignore[arg-type]


def fly_lockstep(
    core: ReplicaCore, vehicle: ScriptedVehicle, path: list[tuple[float, float, float]], *, land_after: int
) -> None:
    """Answer each grant with a position from ``path`` and an announce; disarm after ``land_after`` grants."""
    step = 0
    while not core.done and vehicle.grants and step < 10_000:
        grant = vehicle.grants[-1]
        t = grant.until_ms
        x, y, z = path[min(step, len(path) - 1)]
        msgs = [LocalPosition(t, x, y, z)]
        if t % 1000 == 0:  # a real vehicle's heartbeat: once a second
            msgs.append(heartbeat(armed=vehicle.armed))
        if step == land_after:
            vehicle.armed = False
            msgs.append(heartbeat(armed=False))
        msgs.append(LockstepAnnounce(t))
        before = len(vehicle.grants)
        exchange(core, vehicle, msgs, wall=1.0 + step * 0.001)
        step += 1
        if len(vehicle.grants) == before:
            break


def test_a_lockstep_flight_holds_the_clock_for_setup_then_grants_steps_until_landed() -> None:
    core = ReplicaCore(config())
    vehicle = ScriptedVehicle(param_types={"COM_DISARM_LAND": int(ParamType.INT32)})
    assert core.start(0.0) == []
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    # setup happened with the vehicle clock held at 0: params set and verified, mission uploaded
    assert vehicle.params["NAV_ACC_RAD"] == 2.0
    assert len(vehicle.mission) == 2
    assert core.stage is Stage.FLIGHT and core.lockstep
    # the flight's first work happened at T=0 before the first grant: arm (Aerialist), heartbeat
    assert vehicle.grants == [LockstepGrant(0, 50)]
    assert vehicle.commands[0].command == Cmd.COMPONENT_ARM_DISARM
    climb = [(0.0, 0.0, -0.1 * i) for i in range(100)]
    fly_lockstep(core, vehicle, climb, land_after=60)
    assert core.done
    rep = core.report
    assert rep.ending is Ending.LANDED and rep.error is None
    assert rep.armed_ever and rep.start_ms == 0
    # the mode switch came one step after the arm ACK, on the vehicle clock
    assert [c.command for c in vehicle.commands[:2]] == [Cmd.COMPONENT_ARM_DISARM, Cmd.DO_SET_MODE]
    assert all(b.seen_ms == a.until_ms for a, b in zip(vehicle.grants, vehicle.grants[1:], strict=False))
    assert rep.end_ms == vehicle.grants[-2].until_ms
    assert rep.sim_time == rep.end_ms / 1000  # type: ignore[operator]


def test_gcs_heartbeats_go_out_once_per_vehicle_second_in_lockstep() -> None:
    core = ReplicaCore(config(timeout_s=5.0))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    vehicle.sent.clear()
    fly_lockstep(core, vehicle, [(0.0, 0.0, -5.0)], land_after=10**6)
    beats = [m for m in vehicle.sent if isinstance(m, GcsHeartbeat)]
    assert core.report.ending is Ending.TIMEOUT
    assert len(beats) == 5  # 5 s of vehicle time, whatever the wall clock did


def test_the_connect_stage_grants_time_until_the_vehicle_has_a_position() -> None:
    core = ReplicaCore(config())
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [heartbeat(), LockstepAnnounce(0)], wall=0.1)
    assert vehicle.grants == [LockstepGrant(0, 50)]
    exchange(core, vehicle, [LockstepAnnounce(50)], wall=0.2)
    assert vehicle.grants[-1] == LockstepGrant(50, 100)
    exchange(core, vehicle, boot(100)[1:], wall=0.3)
    # positions arrived while the vehicle simulates up to 100: setup runs, no grant is due yet
    assert core.stage is Stage.FLIGHT
    assert any(isinstance(m, ParamRequestRead) for m in vehicle.sent)
    assert len(vehicle.grants) == 2
    exchange(core, vehicle, [LockstepAnnounce(100)], wall=0.4)
    assert vehicle.grants[-1] == LockstepGrant(100, 150)


def test_a_grant_stops_exactly_at_the_next_command_time() -> None:
    core = ReplicaCore(config(commands=[*START_MISSION, Command(at=1.02, action="speed", speed=3)]))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    for t in range(50, 1001, 50):
        exchange(core, vehicle, [LocalPosition(t, 0, 0, -1), LockstepAnnounce(t)], wall=0.2)
    assert vehicle.grants[-1] == LockstepGrant(1000, 1020)
    exchange(core, vehicle, [LockstepAnnounce(1020)], wall=0.3)
    assert vehicle.commands[-1].command == Cmd.DO_CHANGE_SPEED


def test_a_collision_settles_early_force_disarms_and_grants_once_more_for_the_log() -> None:
    box = Obstacle.model_validate({"size": {"l": 2, "w": 2, "h": 20}, "position": {"x": 5, "y": 0}})
    core = ReplicaCore(config(obstacles=[box]))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    path = [(0.25 * i, 0.0, -5.0) for i in range(40)]
    fly_lockstep(core, vehicle, path, land_after=10**6)
    rep = core.report
    assert core.done and rep.ending is Ending.COLLISION
    assert rep.collision is not None and rep.collision.x >= 4.0
    assert rep.min_distance == 0.0
    disarm = [c for c in vehicle.commands if c.command == Cmd.COMPONENT_ARM_DISARM and c.params[0] == 0]
    assert disarm and disarm[-1].params[1] == 21196.0
    assert any("collision at t=" in n for n in rep.notes)
    assert vehicle.grants[-1].seen_ms == rep.end_ms  # the extra step after the disarm


def test_a_vehicle_that_never_arms_is_a_bench_error_at_the_timeout() -> None:
    core = ReplicaCore(config(commands=[], mission=[], timeout_s=2.0))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    fly_lockstep(core, vehicle, [(0.0, 0.0, 0.0)], land_after=10**6)
    assert core.done and core.report.ending is Ending.ERROR
    assert core.report.error == "timeout: the vehicle never armed in 2 s of vehicle time"


def test_a_refused_arm_for_too_long_ends_the_flight_as_refused_not_a_bench_error() -> None:
    core = ReplicaCore(config())
    core.scheduler.arm_give_up_ms = 2000
    vehicle = ScriptedVehicle(refuse_arm=True)
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    fly_lockstep(core, vehicle, [(0.0, 0.0, 0.0)], land_after=10**6)
    rep = core.report
    assert core.done and rep.ending is Ending.REFUSED and rep.error is None
    assert [(r.label, r.result, r.final) for r in rep.refusals] == [
        ("arm (for mode mission)", "DENIED", True)
    ]
    assert any("vehicle refused arm (for mode mission) for 2 s (COMMAND_ACK DENIED)" in n for n in rep.notes)


def test_a_refused_arm_at_the_timeout_is_refused_not_a_bench_error() -> None:
    core = ReplicaCore(config(timeout_s=3.0))  # the test's timeout comes before the arm give-up
    vehicle = ScriptedVehicle(refuse_arm=True)
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    fly_lockstep(core, vehicle, [(0.0, 0.0, 0.0)], land_after=10**6)
    assert core.done and core.report.ending is Ending.REFUSED and core.report.error is None
    assert core.report.refusals and core.report.refusals[0].result == "DENIED"


def test_without_announces_the_core_follows_the_vehicle_clock_and_never_grants() -> None:
    core = ReplicaCore(config(commands=[Command(at=40.0, action="mode", mode="mission")]))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, boot(35_000), wall=0.1)  # PX4 boots for ~35 s
    assert core.stage is Stage.FLIGHT and not core.lockstep
    exchange(core, vehicle, [LocalPosition(39_990, 0, 0, 0)], wall=5.0)
    assert vehicle.commands == []
    exchange(core, vehicle, [LocalPosition(40_010, 0, 0, 0)], wall=5.1)
    assert [c.command for c in vehicle.commands] == [Cmd.COMPONENT_ARM_DISARM, Cmd.DO_SET_MODE]
    assert vehicle.grants == []


def test_no_heartbeat_is_an_error_naming_the_endpoint_and_the_wait() -> None:
    core = ReplicaCore(config(endpoint="udpin:127.0.0.1:14540", connect_timeout_s=30))
    core.start(100.0)
    assert core.tick(129.9) == [] and not core.done
    core.tick(130.0)
    assert core.done and core.report.error == "no heartbeat from udpin:127.0.0.1:14540 within 30 s"


def test_a_vehicle_that_goes_silent_mid_flight_is_an_error() -> None:
    core = ReplicaCore(config(silence_s=10))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    core.tick(5.0)  # a lost grant or announce: the last grant goes out again
    core.tick(10.2)
    assert core.done and core.report.ending is Ending.ERROR
    assert core.report.error is not None and "went silent" in core.report.error


def test_a_lost_grant_is_sent_again() -> None:
    core = ReplicaCore(config())
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    assert not any(isinstance(m, LockstepGrant) for m in core.tick(0.5))
    assert LockstepGrant(0, 50) in core.tick(1.2)


def test_a_mission_the_vehicle_refuses_ends_before_the_flight() -> None:
    class Refusing(ScriptedVehicle):
        def answer(self, out: list) -> list:  # type: ignore[override,type-arg]
            from uavtest.runner.events import MissionAck, MissionCount

            if any(isinstance(m, MissionCount) for m in out):
                self.sent.extend(out)
                return [MissionAck(4)]  # NO_SPACE
            return super().answer(out)

    core = ReplicaCore(config())
    vehicle = Refusing()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    assert core.done and core.report.ending is Ending.ERROR
    assert core.report.error == "mission upload refused after 3 attempts: MISSION_ACK NO_SPACE"
    assert core.report.start_ms is None
    assert not any(isinstance(m, CommandLong) and m.command != Cmd.SET_MESSAGE_INTERVAL for m in vehicle.sent)


def test_an_accepted_arm_counts_before_the_next_heartbeat_shows_it() -> None:
    commands = [Command(at=0, action="arm"), Command(at=0.5, action="disarm")]
    core = ReplicaCore(config(commands=commands, mission=[]))
    vehicle = ScriptedVehicle(beat_on_ack=False)  # heartbeats only once a second
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    fly_lockstep(core, vehicle, [(0.0, 0.0, 0.0)], land_after=10**6)
    arm_disarm = [c.params[0] for c in vehicle.commands if c.command == Cmd.COMPONENT_ARM_DISARM]
    assert arm_disarm[:2] == [1.0, 0.0]  # the disarm at 0.5 s was sent, not skipped as "not armed"
    assert core.report.ending is Ending.LANDED and core.report.end_ms is not None
    assert core.report.end_ms <= 2000  # landed once the arming grace passed, not at the timeout


def test_a_stale_disarmed_heartbeat_right_after_arming_does_not_end_the_flight() -> None:
    core = ReplicaCore(config(commands=[Command(at=0, action="arm")], mission=[], timeout_s=5))
    vehicle = ScriptedVehicle(beat_on_ack=False)
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    exchange(
        core, vehicle, [heartbeat(armed=False), LocalPosition(50, 0, 0, 0), LockstepAnnounce(50)], wall=0.2
    )
    assert core.stage is Stage.FLIGHT  # sent before the arm took effect: not a landing
    fly_lockstep(core, vehicle, [(0.0, 0.0, -3.0)], land_after=10**6)
    assert core.report.ending is Ending.TIMEOUT and core.report.armed_ever


def test_a_refused_arm_downloads_no_log_the_vehicle_never_wrote() -> None:
    core = ReplicaCore(config(download_log=True))
    core.scheduler.arm_give_up_ms = 2000
    vehicle = ScriptedVehicle(refuse_arm=True)
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    fly_lockstep(core, vehicle, [(0.0, 0.0, 0.0)], land_after=10**6)
    assert core.done and core.report.ending is Ending.REFUSED
    assert core.report.error is None and core.report.log_data is None


def test_once_connected_the_runner_stops_the_streams_it_never_reads() -> None:
    """PX4's ONBOARD link streams ~300 messages/s; the runner keeps what it reads, slows the rest."""
    from uavtest.runner.streams import STREAM_INTERVALS_US

    core = ReplicaCore(config())
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    assert vehicle.intervals == STREAM_INTERVALS_US
    assert vehicle.intervals[30] == -1 and vehicle.intervals[105] == -1  # ATTITUDE, HIGHRES_IMU off
    assert 32 not in vehicle.intervals and 1 not in vehicle.intervals  # LOCAL_POSITION_NED, SYS_STATUS kept
    assert vehicle.intervals[33] == 200_000  # GLOBAL_POSITION_INT slowed to 5 Hz


def test_a_mission_flight_without_progress_ends_blocked_after_a_minute() -> None:
    """Airborne in mission mode, 17 m short of the waypoint and getting no closer (a wall the
    avoidance cannot get around): the runner ends the flight as blocked, long before the timeout."""
    mission_mode = (4 << 16) | (4 << 24)  # AUTO.MISSION
    core = ReplicaCore(config(timeout_s=600.0))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    step = 0
    while not core.done and vehicle.grants and step < 5000:
        t = vehicle.grants[-1].until_ms
        z = 0.0 if step < 3 else -10.0  # took off, then hovering, turning back and forth
        msgs = [LocalPosition(t, 0.3 * (step % 2), 0.0, z)]
        if t % 1000 == 0:
            msgs.append(heartbeat(armed=vehicle.armed, custom_mode=mission_mode))
        msgs.append(LockstepAnnounce(t))
        exchange(core, vehicle, msgs, wall=1.0 + step * 0.001)
        step += 1
    rep = core.report
    assert core.done and rep.ending is Ending.BLOCKED
    assert any(n.startswith("blocked: no progress toward mission item 1 for 60 s") for n in rep.notes)
    assert rep.end_ms is not None and 60_000 <= rep.end_ms < 70_000


def test_the_wait_for_the_vehicle_to_settle_does_not_count_against_the_timeout() -> None:
    """PX4 SITL: the runner holds the arm until the vehicle has been ready for arm_settle_s; that
    wait is the bench's, so a 5 s test still flies 5 s after it (the built-in vehicle needs none)."""
    from uavtest.runner.events import SysStatus

    READY = 0x10000000  # MAV_SYS_STATUS_PREARM_CHECK
    core = ReplicaCore(config(timeout_s=5.0, arm_settle_s=10.0))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    heard, *positions = boot(0)
    exchange(core, vehicle, [heard, SysStatus(READY), *positions], wall=0.1)  # ready from t=0
    for k in range(1, 200):
        t = k * 100
        msgs = [LocalPosition(t, 0.0, 0.0, -5.0 if vehicle.armed else 0.0)]
        if t % 1000 == 0:
            msgs += [heartbeat(armed=vehicle.armed), SysStatus(READY)]
        exchange(core, vehicle, msgs, wall=0.2 + k * 0.1)
        if core.done:
            break
    rep = core.report
    assert rep.ending is Ending.TIMEOUT and rep.armed_ever
    assert rep.end_ms == 15_000  # armed at 10 s (settled), then the test's 5 s
    assert any("and 10.0 s waiting for the vehicle to settle" in n for n in rep.notes)


def test_mode_mission_refused_right_after_the_upload_is_sent_again_and_flies() -> None:
    """The runner arms and switches to mission moments after PX4 accepted the upload; PX4 answers
    TEMPORARILY_REJECTED until it has checked the mission. The core tells the scheduler when the
    upload was accepted, so the switch is sent again instead of ending the flight as refused."""

    class ChecksTheMissionFirst(ScriptedVehicle):
        rejected: int = 0

        def answer(self, out: list[Outgoing]) -> list[Incoming]:
            replies = super().answer(out)
            for i, r in enumerate(replies):
                if isinstance(r, CommandAck) and r.command == Cmd.DO_SET_MODE and self.rejected == 0:
                    self.rejected += 1
                    replies[i] = CommandAck(r.command, AckResult.TEMPORARILY_REJECTED)
            return replies

    core = ReplicaCore(config())
    vehicle = ChecksTheMissionFirst(param_types={"COM_DISARM_LAND": int(ParamType.INT32)})
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    assert core.scheduler.mission_accepted_ms == 0
    fly_lockstep(core, vehicle, [(0.0, 0.0, -0.1 * i) for i in range(100)], land_after=60)
    rep = core.report
    assert vehicle.rejected == 1
    assert [c.command for c in vehicle.commands[:3]] == [
        Cmd.COMPONENT_ARM_DISARM,
        Cmd.DO_SET_MODE,
        Cmd.DO_SET_MODE,
    ]
    assert rep.ending is Ending.LANDED and rep.refusals == [] and rep.error is None
