"""From a test spec to the core's configuration."""

from __future__ import annotations

from pathlib import Path

from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.runner.main import exit_code
from uavtest.runner.plan import PX4_ARM_SETTLE_S, flight_commands, plan_flight
from uavtest.spec.loaders import load_test
from uavtest.spec.models import CommandAction, FlightMode, UavTestSpec

WAYPOINTS = {"mission": {"takeoffAltitude": 5, "waypoints": [{"x": 10, "y": 0, "z": -5}]}}


def test_a_mission_without_commands_is_started_at_once() -> None:
    commands = flight_commands(UavTestSpec.model_validate(WAYPOINTS))
    assert [(c.at, c.action, c.mode) for c in commands] == [(0.0, CommandAction.MODE, FlightMode.MISSION)]


def test_given_commands_are_flown_as_written() -> None:
    spec = UavTestSpec.model_validate({**WAYPOINTS, "commands": [{"at": 5, "action": "arm"}]})
    assert [c.action for c in flight_commands(spec)] == [CommandAction.ARM]


def test_the_plan_carries_params_mission_obstacles_and_timeout() -> None:
    spec = UavTestSpec.model_validate(
        {
            **WAYPOINTS,
            "timeout": 90,
            "vehicle": {"params": {"NAV_ACC_RAD": 1.5}},
            "world": {"obstacles": [{"size": {"l": 1, "w": 1, "h": 1}, "position": {"x": 3, "y": 3}}]},
        }
    )
    cfg = plan_flight(spec, endpoint="udpin:127.0.0.1:20000", step_ms=20)
    assert cfg.params == {"NAV_ACC_RAD": 1.5}
    assert [i.command for i in cfg.mission] == [22, 16, 21]  # takeoff, waypoint, land
    assert len(cfg.obstacles) == 1 and cfg.timeout_s == 90 and cfg.step_ms == 20
    assert plan_flight(spec, endpoint="udpin:127.0.0.1:1", timeout_s=10).timeout_s == 10


def test_px4_is_armed_only_once_it_has_been_ready_a_while_and_the_builtin_sim_at_once() -> None:
    builtin = UavTestSpec.model_validate(WAYPOINTS)
    px4 = UavTestSpec.model_validate({**WAYPOINTS, "vehicle": {"simulator": "px4"}})
    assert plan_flight(builtin, endpoint="udpin:127.0.0.1:1").arm_settle_s == 0
    assert plan_flight(px4, endpoint="udpin:127.0.0.1:1").arm_settle_s == PX4_ARM_SETTLE_S > 0
    assert plan_flight(px4, endpoint="udpin:127.0.0.1:1", arm_settle_s=2.5).arm_settle_s == 2.5


def test_the_competition_mission_plans_into_wire_items(shared_data: Path) -> None:
    test = load_test(shared_data / "competition/snippets/case_studies/mission2.yaml")
    cfg = plan_flight(test.spec, endpoint="udpin:127.0.0.1:14540")
    assert cfg.mission[0].command == 22  # takeoff first; QGC's SET_CAMERA_MODE is dropped
    assert all(i.seq == n for n, i in enumerate(cfg.mission))
    assert "NAV_ACC_RAD" in cfg.params
    assert cfg.commands and cfg.commands[0].mode is FlightMode.MISSION  # the commands CSV


def test_exit_codes_follow_the_verdict() -> None:
    def code(v: Verdict) -> int:
        return int(exit_code(ReplicaResult(index=0, seed=0, verdict=v)))

    assert (code(Verdict.PASS), code(Verdict.FAIL), code(Verdict.ERROR)) == (0, 1, 3)
