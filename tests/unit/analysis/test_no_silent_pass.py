"""No silent pass: whether a test flies (``flight_intent``), the verdict of a flight that did not
happen, and what PX4 SIH cannot simulate (``simulator_warnings``). All pure."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from uavtest.analysis.models import Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.verdict import NEVER_TOOK_OFF, flight_intent, judge, simulator_warnings
from uavtest.spec.models import UavTestSpec

BOX = {"size": {"l": 2, "w": 2, "h": 10}, "position": {"x": 20, "y": 0, "z": 0, "r": 0}}
EMPTY = Trajectory([], [], [], [])


def make(commands: list[dict[str, Any]] | None = None, **extra: Any) -> UavTestSpec:
    return UavTestSpec.model_validate({"commands": commands or [], **extra})


def c(at: float, action: str, **kw: Any) -> dict[str, Any]:
    return {"at": at, "action": action, **kw}


# ----------------------------------------------------------------------------- flight_intent


@pytest.mark.parametrize(
    ("spec", "why"),
    [
        (make(mission={"waypoints": [{"x": 0, "y": 0, "z": -5}]}), "the test has a mission"),
        (make([c(1, "mode", mode="mission")]), "mode mission at t=1 s"),  # arms first
        (make([c(1, "mode", mode="takeoff")]), "mode takeoff at t=1 s"),
        (make([c(1, "arm"), c(2, "mode", mode="offboard")]), "mode offboard at t=2 s"),
        (
            make([c(1, "arm"), c(2, "mode", mode="position"), c(3, "sticks", sticks={"z": 0.9})]),
            "sticks with thrust at t=3 s",
        ),
        (make([c(1, "sticks", sticks={"z": 1.0}), c(2, "arm")]), "sticks with thrust at t=1 s"),
    ],
)
def test_tests_that_fly(spec: UavTestSpec, why: str) -> None:
    assert flight_intent(spec) == why


@pytest.mark.parametrize(
    "spec",
    [
        make([c(1, "arm"), c(5, "disarm")]),  # ground only: arm and disarm
        make([c(1, "mode", mode="hold"), c(2, "speed", speed=3)]),  # no arming
        make([c(1, "mode", mode="offboard")]),  # offboard without arming: cannot fly
        make(
            [c(1, "arm"), c(2, "mode", mode="position"), c(3, "sticks", sticks={"z": 0.5})]
        ),  # hold altitude
        make([c(1, "sticks", sticks={"z": 1.0})]),  # thrust, never armed
    ],
)
def test_tests_that_do_not_fly_by_design(spec: UavTestSpec) -> None:
    assert flight_intent(spec) is None


def test_flight_intent_takes_the_resolved_commands() -> None:
    from uavtest.spec.models import Command

    spec = make([c(0, "mode", mode="hold")])
    assert (
        flight_intent(spec, [Command.model_validate(c(0, "mode", mode="mission"))]) == "mode mission at t=0 s"
    )


# ----------------------------------------------------------------------------- judge


def test_reproduction_offboard_never_took_off_is_not_a_pass() -> None:
    """The issue's case: arm, offboard (denied), obstacle with noCollision + minObstacleDistance."""
    spec = make([c(1, "arm"), c(2, "mode", mode="offboard")], world={"obstacles": [BOX]})
    refusal = "vehicle refused mode offboard (COMMAND_ACK DENIED)"
    metrics, results, verdict, reason = judge(EMPTY, spec, refusal=refusal)
    assert verdict is Verdict.FAIL
    assert reason.startswith(f"{NEVER_TOOK_OFF}: {refusal}; ")
    assert "noCollision not judged: the vehicle never took off" in reason
    assert "minObstacleDistance not judged: the vehicle never took off" in reason
    assert {r.name: r.passed for r in results} == {"noCollision": False, "minObstacleDistance": False}
    assert metrics.flight_time == 0.0 and metrics.min_obstacle_distance is None


def test_never_took_off_without_a_known_refusal_still_fails_saying_so() -> None:
    spec = make([c(1, "mode", mode="takeoff")])
    _m, results, verdict, reason = judge(EMPTY, spec)
    assert verdict is Verdict.FAIL and reason == NEVER_TOOK_OFF and results == []


def test_geofence_and_similarity_are_not_judged_without_a_flight() -> None:
    spec = make(
        [c(1, "mode", mode="takeoff")],
        assertions={
            "geofence": {"minX": -5, "maxX": 5},
            "similarity": {"threshold": 1.0, "reference": {"points": [[0, 0, 0, -5], [1, 0, 0, -5]]}},
        },
    )
    _m, results, verdict, reason = judge(EMPTY, spec)
    assert verdict is Verdict.FAIL
    assert {r.name: r.message for r in results} == {
        "geofence": "geofence not judged: the vehicle never took off",
        "similarity": "similarity not judged: the vehicle never took off",
    }
    assert reason.startswith(NEVER_TOOK_OFF + ";")


def test_a_mission_that_never_took_off_fails_first_for_that() -> None:
    spec = make(mission={"waypoints": [{"x": 40, "y": 0, "z": -5}]}, world={"obstacles": [BOX]})
    _m, _r, verdict, reason = judge(EMPTY, spec)
    assert verdict is Verdict.FAIL and reason.startswith(NEVER_TOOK_OFF + "; ")
    assert "mission not completed" in reason and "noCollision not judged" in reason


def test_a_ground_test_keeps_todays_behaviour() -> None:
    """By design no flight: obstacle assertions are judged on the (empty) flight as before: pass."""
    spec = make([c(1, "arm"), c(3, "disarm")], world={"obstacles": [BOX]})
    _m, results, verdict, reason = judge(EMPTY, spec)
    assert verdict is Verdict.PASS and reason == ""
    assert [(r.name, r.passed, r.message) for r in results] == [("noCollision", True, "no collision")]


def test_a_real_flight_is_judged_as_before() -> None:
    t = np.arange(0.0, 10.0, 0.1)
    flight = Trajectory(t, np.zeros_like(t), np.zeros_like(t), np.full_like(t, -5.0))
    spec = make([c(1, "arm"), c(2, "mode", mode="offboard")], world={"obstacles": [BOX]})
    _m, _r, verdict, reason = judge(flight, spec, refusal="ignored: it flew")
    assert verdict is Verdict.PASS and reason == ""


# ----------------------------------------------------------------------------- simulator warnings


def test_px4_warns_about_obstacles_and_wind() -> None:
    spec = make(
        [c(0, "mode", mode="takeoff")],
        vehicle={"simulator": "px4"},
        world={"obstacles": [BOX, BOX], "wind": {"meanSpeed": 4}},
    )
    assert simulator_warnings(spec) == [
        "PX4 SITL (SIH) has no obstacles: the 2 obstacle(s) are judged only geometrically against the "
        "trajectory; the vehicle cannot crash into them",
        "PX4 SITL (SIH, v1.15) has no wind model: the wind (4 m/s) is not simulated",
    ]


def test_px4_without_obstacles_or_wind_and_the_builtin_simulator_warn_nothing() -> None:
    hold = [c(0, "mode", mode="hold")]
    assert simulator_warnings(make(hold, vehicle={"simulator": "px4"})) == []
    assert simulator_warnings(make(hold, world={"obstacles": [BOX], "wind": {"meanSpeed": 4}})) == []
    gusts_only = make(hold, vehicle={"simulator": "px4"}, world={"wind": {"maxSpeed": 3}})
    assert len(simulator_warnings(gusts_only)) == 1
