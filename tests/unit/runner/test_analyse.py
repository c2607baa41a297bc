"""Stage 7 on real PX4 logs: bench faults are errors, the drone's are judged from the log."""

from __future__ import annotations

import math
from pathlib import Path

from uavtest.analysis.models import Verdict
from uavtest.runner.analyse import analyse, collision_seen, vehicle_reason
from uavtest.runner.commands import Refusal
from uavtest.runner.core import Ending, FlightReport
from uavtest.runner.events import LocalPosition
from uavtest.spec.models import UavTestSpec

# square-mission.ulg: PX4 v1.15 SIH, takeoff to 10 m, 30 m north, 30 m east, land there
SQUARE = {
    "mission": {
        "takeoffAltitude": 10,
        "waypoints": [{"x": 30, "y": 0, "z": -10}, {"x": 30, "y": 30, "z": -10}],
    },
}


def flown() -> FlightReport:
    return FlightReport(ending=Ending.LANDED, start_ms=100_000, end_ms=180_000, armed_ever=True)


def test_a_real_px4_flight_of_its_mission_passes(shared_data: Path) -> None:
    spec = UavTestSpec.model_validate(SQUARE)
    a = analyse(flown(), shared_data / "px4-sih/square-mission.ulg", spec, index=1, seed=8, wall_time=2.5)
    assert a.result.verdict is Verdict.PASS, a.result.reason
    assert a.result.reason == "" and a.result.sim_time == 80.0 and a.result.wall_time == 2.5
    assert a.trajectory is not None and 30 < a.trajectory.duration < 60
    assert a.result.metrics is not None and 9 < (a.result.metrics.max_altitude or 0) < 12


def test_an_obstacle_on_the_path_fails_the_same_flight_saying_by_how_much(shared_data: Path) -> None:
    box = {"size": {"l": 4, "w": 4, "h": 20}, "position": {"x": 15, "y": 0}}
    spec = UavTestSpec.model_validate({**SQUARE, "world": {"obstacles": [box]}})
    a = analyse(flown(), shared_data / "px4-sih/square-mission.ulg", spec, index=0, seed=0)
    assert a.result.verdict is Verdict.FAIL
    assert "collision" in a.result.reason.lower() or "noCollision" in a.result.reason
    failed = [r.name for r in a.result.assertions if not r.passed]
    assert "noCollision" in failed


def test_a_bench_error_is_never_judged_even_with_a_log(shared_data: Path) -> None:
    report = flown()
    report.ending, report.error = Ending.ERROR, "no COMMAND_ACK for mode mission after 5 tries"
    spec = UavTestSpec.model_validate(SQUARE)
    a = analyse(report, shared_data / "px4-sih/square-mission.ulg", spec, index=0, seed=0)
    assert a.result.verdict is Verdict.ERROR
    assert a.result.reason == "no COMMAND_ACK for mode mission after 5 tries"
    assert a.result.assertions == []
    assert a.trajectory is not None  # still stored, for whoever debugs the bench


def test_a_missing_log_is_an_error_with_the_reason() -> None:
    spec = UavTestSpec.model_validate(SQUARE)
    a = analyse(flown(), None, spec, index=0, seed=0, log_error="log missing: no .ulg in /x after 15 s")
    assert a.result.verdict is Verdict.ERROR and a.result.reason.startswith("log missing")
    assert a.trajectory is None


def test_an_unreadable_log_is_an_error(tmp_path: Path) -> None:
    bad = tmp_path / "flight.ulg"
    bad.write_bytes(b"not a ulog at all")
    spec = UavTestSpec.model_validate(SQUARE)
    report = flown()
    report.min_distance = math.inf
    a = analyse(report, bad, spec, index=0, seed=0)
    assert a.result.verdict is Verdict.ERROR and a.result.reason.startswith("log unreadable")


# --------------------------------------------------------------------------- no silent pass

OFFBOARD = {
    "commands": [{"at": 1, "action": "arm"}, {"at": 2, "action": "mode", "mode": "offboard"}],
    "world": {"obstacles": [{"size": {"l": 2, "w": 2, "h": 10}, "position": {"x": 20, "y": 0}}]},
}


def refused_report(label: str, result: str, texts: list[tuple[int, int, str]], **kw: object) -> FlightReport:
    rep = FlightReport(ending=Ending.LANDED, start_ms=1_000, end_ms=12_000, armed_ever=True)
    rep.refusals = [Refusal(label, result, sent_ms=2_000, ack_ms=2_000)]
    rep.status_log = texts
    for k, v in kw.items():
        setattr(rep, k, v)
    return rep


def test_vehicle_reason_quotes_the_statustexts_of_the_refusal() -> None:
    texts = [
        (1_450, 6, "Ready for takeoff!"),
        (2_000, 2, "Arming denied: no valid mission"),
        (9_000, 2, "late"),
    ]
    rep = refused_report("arm", "DENIED", texts)
    assert (
        vehicle_reason(rep) == 'vehicle refused arm (COMMAND_ACK DENIED): "Arming denied: no valid mission"'
    )
    rep.status_log = []
    assert vehicle_reason(rep) == "vehicle refused arm (COMMAND_ACK DENIED)"


def test_a_refused_mission_gets_what_the_vehicle_said_when_it_checked_the_mission() -> None:
    """PX4 says why a mission is not valid when it checks it (the upload, the arming), not when
    it then refuses Mission mode: the reason carries those critical texts too."""
    texts = [
        (300, 2, "Mission rejected: takeoff not first waypoint item"),  # at the upload
        (1_450, 6, "Ready for takeoff!"),
        (2_000, 4, "Switching to Mission is currently not available"),
    ]
    rep = refused_report("mode mission", "TEMPORARILY_REJECTED", texts)
    assert vehicle_reason(rep) == (
        'vehicle refused mode mission (COMMAND_ACK TEMPORARILY_REJECTED): "Switching to Mission is '
        'currently not available"; it said before: "Mission rejected: takeoff not first waypoint item"'
    )
    rep = refused_report("arm", "DENIED", texts)  # not a mission: only its own texts
    assert "it said before" not in (vehicle_reason(rep) or "")


def test_vehicle_reason_without_refusals_is_the_vehicles_warnings_or_none() -> None:
    rep = FlightReport(start_ms=1_000)
    rep.status_log = [(500, 2, "before the flight"), (1_500, 6, "info"), (3_000, 1, "Failsafe: no RC")]
    assert vehicle_reason(rep) == 'vehicle says: "Failsafe: no RC"'
    assert vehicle_reason(FlightReport(start_ms=0)) is None


def test_a_refused_arm_is_fail_with_the_vehicles_reason_even_without_a_log() -> None:
    spec = UavTestSpec.model_validate(OFFBOARD)
    rep = refused_report("arm", "DENIED", [(2_000, 2, "Arming denied: no valid mission")], armed_ever=False)
    rep.ending = Ending.REFUSED
    a = analyse(rep, None, spec, index=0, seed=3, log_error="log missing: the vehicle never armed")
    assert a.result.verdict is Verdict.FAIL
    assert a.result.reason == (
        "the vehicle never took off: "
        'vehicle refused arm (COMMAND_ACK DENIED): "Arming denied: no valid mission"'
    )
    assert a.result.metrics is not None and a.result.metrics.flight_time == 0.0


def test_px4_limits_are_warnings_in_the_result() -> None:
    spec = UavTestSpec.model_validate({**OFFBOARD, "vehicle": {"simulator": "px4"}})
    a = analyse(flown(), None, spec, index=0, seed=0, log_error="log missing")
    assert a.result.warnings and "PX4 SITL (SIH) has no obstacles" in a.result.warnings[0]


def test_a_blocked_flight_fails_with_the_runners_reason_first(shared_data: Path) -> None:
    """The runner ended the flight as blocked: fail, whatever the log's own assertions say."""
    spec = UavTestSpec.model_validate({**SQUARE, "assertions": {"missionCompleted": False}})
    rep = flown()
    rep.ending = Ending.BLOCKED
    rep.notes.append("blocked: no progress toward mission item 2 for 60 s (12.0 m away)")
    a = analyse(rep, shared_data / "px4-sih/square-mission.ulg", spec, index=0, seed=0)
    assert a.result.verdict is Verdict.FAIL
    assert a.result.reason == "blocked: no progress toward mission item 2 for 60 s (12.0 m away)"


def test_a_collision_the_runner_ended_the_flight_at_fails_even_if_the_log_stops_short(
    shared_data: Path,
) -> None:
    """The runner stops a flight once the vehicle reports its position inside a box; the disarm
    closes the log, which may end a step before that position. The verdict still counts it: a
    box 0.3 m beside the square's first leg is never entered by the logged path, but the runner
    saw the vehicle inside it."""
    box = {"size": {"l": 4, "w": 1, "h": 20}, "position": {"x": 15, "y": 1.3}}
    spec = UavTestSpec.model_validate({**SQUARE, "world": {"obstacles": [box]}})
    clear = analyse(flown(), shared_data / "px4-sih/square-mission.ulg", spec, index=0, seed=0)
    assert clear.result.metrics is not None and clear.result.metrics.collision is False
    report = flown()
    report.ending = Ending.COLLISION
    report.collision = LocalPosition(time_ms=141_250, x=15.0, y=0.9, z=-10.0)
    a = analyse(report, shared_data / "px4-sih/square-mission.ulg", spec, index=0, seed=0)
    assert a.result.verdict is Verdict.FAIL
    assert a.result.metrics is not None and a.result.metrics.collision is True
    assert a.result.reason.startswith(
        "hard fail: collision with an obstacle: the vehicle reported its position inside it at t=141.25 s"
    ), a.result.reason
    assert "noCollision" in [r.name for r in a.result.assertions if not r.passed]


def test_a_position_inside_a_box_counts_only_when_the_runner_ended_the_flight_on_it() -> None:
    """``collision_seen`` is the runner's own ending: a flight that landed (or timed out, or was
    blocked) is judged from its log alone, whatever position the report holds."""
    inside = LocalPosition(time_ms=20_000, x=19.5, y=0.0, z=-10.0)
    for ending in (Ending.LANDED, Ending.TIMEOUT, Ending.BLOCKED, Ending.ERROR):
        report = flown()
        report.ending, report.collision = ending, inside
        assert collision_seen(report) is None, ending
    report = flown()
    report.ending = Ending.COLLISION
    assert collision_seen(report) is None, "no position: nothing to report"
    report.collision = inside
    assert collision_seen(report) is not None
