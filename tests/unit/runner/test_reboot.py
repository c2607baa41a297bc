"""A vehicle that reboots under the runner (a restarted simulator) ends the replica as a bench error,
never as a landing judged on half a flight; a vehicle whose clock only jitters flies on."""

from __future__ import annotations

import pytest

from uavtest.runner.core import CoreConfig, Ending, ReplicaCore, Stage
from uavtest.runner.events import GlobalPosition, LocalPosition, LockstepAnnounce, VehicleTime
from uavtest.runner.reboot import JITTER_MS, clock_went_back, reboot_reason
from uavtest.spec.models import Command

from .vehicle import ScriptedVehicle, boot, exchange, heartbeat


@pytest.mark.parametrize(
    ("latest", "seen", "jitter", "rebooted"),
    [
        (41_200, 800, JITTER_MS, True),  # a new boot
        (41_200, 41_180, JITTER_MS, False),  # one stream's stamp lags another's
        (41_200, 40_200, JITTER_MS, False),  # exactly the jitter: still the same boot
        (41_200, 40_199, JITTER_MS, True),
        (41_200, 41_300, JITTER_MS, False),  # forward is time passing
        (350, 0, 0, True),  # a lockstep announce is exact: any step back
        (350, 350, 0, False),  # an announce repeated (lost grant) is not a step back
    ],
)
def test_clock_went_back(latest: int, seen: int, jitter: int, rebooted: bool) -> None:
    assert clock_went_back(latest, seen, jitter_ms=jitter) is rebooted


def test_the_reason_says_when_and_the_times() -> None:
    assert reboot_reason("flight", 41_200, 800) == (
        "the vehicle rebooted mid-flight (time since boot went from 41.2 s to 0.8 s): "
        "simulator restarted; no verdict on a half flight"
    )
    assert "while the runner set its parameters" in reboot_reason("params", 5_000, 100)


ARM_AND_HOLD = [Command(at=0, action="arm")]


def flying_without_lockstep(**kw: object) -> tuple[ReplicaCore, ScriptedVehicle]:
    """A PX4-like vehicle (no lockstep), booted 20 s ago, armed and climbing."""
    core = ReplicaCore(CoreConfig(commands=ARM_AND_HOLD, **kw))  # type: ignore[arg-type]
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, boot(20_000), wall=0.1)
    assert core.stage is Stage.FLIGHT
    for i in range(1, 200):
        exchange(core, vehicle, [LocalPosition(20_000 + 100 * i, 0, 0, -0.05 * i)], wall=0.1 + 0.01 * i)
    assert core.armed and core.stage is Stage.FLIGHT
    return core, vehicle


def test_a_restarted_vehicle_mid_flight_is_an_error_not_a_landing() -> None:
    core, vehicle = flying_without_lockstep()
    # the simulator restarts: the new boot says hello disarmed, the wall clock ticks on...
    exchange(core, vehicle, [heartbeat(armed=False)], wall=3.0)
    core.tick(3.1)
    assert core.stage is Stage.FLIGHT  # a disarm is not a landing until the clock moves on
    # ...then its clock, from zero
    exchange(core, vehicle, [LocalPosition(800, 0, 0, 0)], wall=3.2)
    core.tick(3.3)
    rep = core.report
    assert core.done and rep.ending is Ending.ERROR
    assert rep.error == (
        "the vehicle rebooted mid-flight (time since boot went from 39.9 s to 0.8 s): "
        "simulator restarted; no verdict on a half flight"
    )
    assert rep.end_ms == 39_900 and rep.sim_time == pytest.approx(19.9)


@pytest.mark.parametrize("stamp", [GlobalPosition(500, 0, 0, 0), VehicleTime(500)])
def test_any_stamped_message_shows_the_new_boot(stamp: GlobalPosition | VehicleTime) -> None:
    core, vehicle = flying_without_lockstep()
    exchange(core, vehicle, [stamp], wall=3.0)
    assert core.report.ending is Ending.ERROR and "rebooted mid-flight" in (core.report.error or "")


def test_a_landing_without_lockstep_still_ends_as_landed() -> None:
    core, vehicle = flying_without_lockstep()
    exchange(core, vehicle, [heartbeat(armed=False)], wall=3.0)
    exchange(core, vehicle, [LocalPosition(39_950, 0, 0, 0)], wall=3.1)  # the clock moves on
    core.tick(3.2)
    assert core.report.ending is Ending.LANDED and core.report.error is None


def test_telemetry_jitter_is_not_a_reboot() -> None:
    core, vehicle = flying_without_lockstep(timeout_s=25)
    exchange(core, vehicle, [GlobalPosition(39_900 - JITTER_MS, 0, 0, -5_000)], wall=3.0)
    exchange(core, vehicle, [LocalPosition(45_100, 0, 0, -5)], wall=3.1)
    assert core.report.ending is Ending.TIMEOUT and core.report.error is None


def test_a_lockstep_simulator_restarted_early_in_the_flight_is_caught_by_its_announce() -> None:
    core = ReplicaCore(CoreConfig(commands=ARM_AND_HOLD, step_ms=50))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [*boot(0), LockstepAnnounce(0)], wall=0.1)
    for _ in range(6):  # 300 ms of flight: far less than the telemetry jitter allowance
        t = vehicle.grants[-1].until_ms
        exchange(core, vehicle, [LocalPosition(t, 0, 0, -0.1), LockstepAnnounce(t)], wall=0.2)
    assert core.armed and core.now_ms == 300
    # the new simulator: disarmed, on the ground, at T=0, waiting for its first grant
    grants = len(vehicle.grants)
    exchange(core, vehicle, [heartbeat(), LocalPosition(0, 0, 0, 0), LockstepAnnounce(0)], wall=0.3)
    assert core.report.ending is Ending.ERROR
    assert core.report.error == (
        "the vehicle rebooted mid-flight (time since boot went from 0.3 s to 0.0 s): "
        "simulator restarted; no verdict on a half flight"
    )
    assert len(vehicle.grants) == grants  # no time granted to the new boot


def test_a_reboot_while_parameters_are_set_is_an_error_before_the_flight() -> None:
    class Rebooting(ScriptedVehicle):
        def answer(self, out: list) -> list:  # type: ignore[override,type-arg]
            replies = super().answer(out)
            return (
                [LocalPosition(100, 0, 0, 0), *replies]
                if any(r.__class__.__name__ == "ParamValue" for r in replies)
                else replies
            )

    core = ReplicaCore(CoreConfig(params={"NAV_ACC_RAD": 2.0}, commands=ARM_AND_HOLD))
    core.start(0.0)
    exchange(core, Rebooting(), boot(20_000), wall=0.1)
    assert core.done and core.report.ending is Ending.ERROR and core.report.start_ms is None
    assert (core.report.error or "").startswith("the vehicle rebooted while the runner set its parameters")
