"""Lockstep grant sizes: large while the flight just goes on, short where the runner must act."""

from __future__ import annotations

from uavtest.runner.core import ReplicaCore
from uavtest.runner.events import LocalPosition, LockstepAnnounce, LockstepGrant, ManualControl
from uavtest.runner.grants import DEFAULT_STEP_MS, FINE_MS, NEAR_MS, STICKS_MS, grant_until
from uavtest.runner.px4 import Cmd
from uavtest.spec.models import Command, Obstacle

from .test_core import START_MISSION, config, fly_lockstep
from .vehicle import ScriptedVehicle, boot, exchange


def test_the_largest_grant_while_nothing_is_going_on() -> None:
    assert grant_until(2000, max_ms=1000) == 3000


def test_short_grants_while_commands_run_sticks_stream_or_an_obstacle_is_near() -> None:
    assert grant_until(2000, max_ms=1000, busy=True) == 2000 + FINE_MS
    assert grant_until(2000, max_ms=1000, sticks=True) == 2000 + STICKS_MS
    assert grant_until(2000, max_ms=1000, obstacle_distance=3.0) == 2000 + NEAR_MS
    assert grant_until(2000, max_ms=1000, obstacle_distance=30.0) == 3000


def test_a_grant_ends_exactly_at_the_next_event() -> None:
    assert grant_until(2000, max_ms=1000, next_event_ms=2345.2) == 2346
    assert grant_until(2000, max_ms=1000, next_event_ms=2000) == 3000  # due now: handled already
    assert grant_until(2000, max_ms=30, next_event_ms=2345) == 2030
    assert grant_until(2000, max_ms=0) == 2001  # never an empty grant


def _flight(core: ReplicaCore) -> ScriptedVehicle:
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    fly_lockstep(core, vehicle, [(0.0, 0.0, -5.0)], land_after=10**6)
    return vehicle


def test_a_quiet_minute_of_flight_takes_about_one_grant_per_second() -> None:
    core = ReplicaCore(config(timeout_s=60.0))
    vehicle = _flight(core)
    assert core.report.ending is not None
    assert core.cfg.step_ms == DEFAULT_STEP_MS
    # arm and mode switch one fine step apart, then whole seconds (GCS heartbeat times)
    assert vehicle.grants[:3] == [LockstepGrant(0, 50), LockstepGrant(50, 100), LockstepGrant(100, 1000)]
    assert all(g.until_ms - g.seen_ms == 1000 for g in vehicle.grants[3:-1])
    assert len(vehicle.grants) <= 64


def test_the_same_script_gives_the_same_grants() -> None:
    commands = [
        *START_MISSION,
        Command(at=7.3, action="speed", speed=3),
        Command.model_validate({"at": 12, "action": "sticks", "sticks": {"x": 0.5}}),
        Command(at=14, action="mode", mode="hold"),
    ]
    runs = []
    for _ in range(2):
        core = ReplicaCore(config(commands=commands, timeout_s=20.0))
        runs.append(_flight(core).grants)
    assert runs[0] == runs[1]
    grants = runs[0]
    ends = {g.until_ms for g in grants}
    assert {7300, 12000, 14000} <= ends  # commands land exactly on their times
    during_sticks = [g for g in grants if 12000 <= g.seen_ms < 14000]
    assert during_sticks and all(g.until_ms - g.seen_ms <= STICKS_MS for g in during_sticks)


def test_sticks_are_sent_at_least_ten_times_per_vehicle_second() -> None:
    commands = [*START_MISSION, Command.model_validate({"at": 2, "action": "sticks", "sticks": {"x": 0.5}})]
    core = ReplicaCore(config(commands=commands, timeout_s=5.0))
    vehicle = _flight(core)
    sticks = [m for m in vehicle.sent if isinstance(m, ManualControl)]
    assert len(sticks) >= 30  # 3 s of vehicle time at >= 10 Hz


def test_grants_shrink_near_an_obstacle() -> None:
    box = Obstacle.model_validate({"size": {"l": 2, "w": 2, "h": 20}, "position": {"x": 50, "y": 0}})
    core = ReplicaCore(config(obstacles=[box], timeout_s=30.0))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    x = 0.0
    while not core.done and len(vehicle.grants) < 1000:
        g = vehicle.grants[-1]
        exchange(core, vehicle, [LocalPosition(g.until_ms, x, 0, -5), LockstepAnnounce(g.until_ms)], wall=0.2)
        x += (g.until_ms - g.seen_ms) / 1000 * 4.0  # 4 m/s towards the box
    far = [g for g in vehicle.grants[3:] if g.until_ms < 8000]
    assert far and all(g.until_ms - g.seen_ms == 1000 for g in far)  # 40 m and more away
    assert core.report.collision is not None
    # the last grants before the collision were short: the force disarm came at once
    hit = core.report.collision.time_ms
    before = [g for g in vehicle.grants if hit - 1000 <= g.seen_ms < hit]
    assert before and all(g.until_ms - g.seen_ms <= NEAR_MS for g in before)
    disarm = [c for c in vehicle.commands if c.command == Cmd.COMPONENT_ARM_DISARM and c.params[0] == 0]
    assert disarm
