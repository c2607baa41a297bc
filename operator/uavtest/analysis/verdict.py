"""A flight's metrics and verdict against the test's assertions (pure).

``judge`` returns ``pass`` or ``fail``: an assertion that does not hold is the drone's fault.
Bench errors (``error``) are decided by the runner, which knows whether the bench failed.

A verdict is never given on a flight that did not happen. ``flight_intent`` decides from the spec
alone whether a test flies (a mission, or commands that arm and command flight). When a test that
flies has an empty trajectory (the vehicle never took off) the replica is ``fail``, the reason
saying so (with the vehicle's refusal when there was one), and the assertions that need a flight
— noCollision, minObstacleDistance, geofence, similarity — are reported "not judged" instead of
passing by default. A test that by design does not fly (ground commands only) is judged as before.

With obstacles, the metrics also carry the UAV Testing Competition's 2-D distance and points
(``uavtest.analysis.competition``; they never change the verdict), and a failed noCollision reads
"hard fail: ...", a failed minObstacleDistance "soft fail: ...", in the competition's words.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from uavtest.analysis.competition import HARD_FAIL, SOFT_FAIL, competition_distance, competition_points
from uavtest.analysis.geometry import distances_to_obstacles
from uavtest.analysis.mission import acceptance_radius, mission_targets, progress_from_waypoints
from uavtest.analysis.models import AssertionResult, FlightMetrics, MissionProgress, Verdict
from uavtest.analysis.similarity import similarity
from uavtest.analysis.trajectory import Trajectory
from uavtest.spec.models import (
    Assertions,
    Avoidance,
    Command,
    CommandAction,
    FlightMode,
    Geofence,
    Obstacle,
    ReferenceTrajectory,
    Simulator,
    UavTestSpec,
)

__all__ = [
    "NEVER_TOOK_OFF",
    "flight_intent",
    "geofence_violation",
    "judge",
    "judge_flight",
    "reference_from_points",
    "simulator_warnings",
]

NEVER_TOOK_OFF = "the vehicle never took off"

#: modes that fly the vehicle once armed (offboard flies the test's setpoints; without any PX4
#: refuses it, and a refused flight is a fail with the refusal, never a pass)
_FLYING_MODES = frozenset({FlightMode.MISSION, FlightMode.TAKEOFF, FlightMode.OFFBOARD})
#: commands that fly the armed vehicle to a place (PX4 switches to hold / orbit)
_FLYING_ACTIONS = frozenset({CommandAction.GOTO, CommandAction.ORBIT})
_CLIMB_THROTTLE = 0.5  # sticks z above this climbs (0.5 holds altitude in altitude / position mode)


def flight_intent(spec: UavTestSpec, commands: Sequence[Command] | None = None) -> str | None:
    """Why ``spec`` flies (e.g. "the test has a mission", "mode offboard at t=2 s"), or None
    when by design it does not (only ground commands, no mission, no arming). Pure.

    ``commands``: the test's timed commands (default ``spec.commands``; pass
    ``uavtest.spec.commands.resolved_commands(spec)`` to include a ``commandsFile``).

    A test flies when it has a mission, or when its commands arm the vehicle (``arm``, or
    ``mode mission`` / ``mode takeoff``, which arm first) and command flight: mode mission,
    takeoff or offboard (which flies the setpoints; PX4 refuses it without them, and the refusal
    then makes the replica fail), goto or orbit, or a climb on the sticks (throttle above 0.5) in
    manual, altitude or position mode (or in no mode command at all).
    """
    if spec.mission is not None:
        return "the test has a mission"
    cmds = sorted(spec.commands if commands is None else commands, key=lambda c: c.at)
    arming = (FlightMode.MISSION, FlightMode.TAKEOFF)  # Aerialist semantics: these arm first
    if not any(c.action is CommandAction.ARM or c.mode in arming for c in cmds):
        return None
    for c in cmds:
        if c.action is CommandAction.MODE and c.mode in _FLYING_MODES:
            assert c.mode is not None
            return f"mode {c.mode.value} at t={c.at:g} s"
        if c.action in _FLYING_ACTIONS:
            return f"{c.action.value} at t={c.at:g} s"
        if c.action is CommandAction.STICKS and c.sticks is not None and c.sticks.z > _CLIMB_THROTTLE:
            return f"sticks with thrust at t={c.at:g} s"
    return None


def simulator_warnings(spec: UavTestSpec) -> list[str]:
    """What the chosen simulator cannot simulate in ``spec``, to be said with the results
    (and what its Collision Prevention set-up will not do, ``collision_prevention_warnings``).

    PX4 SITL with SIH (the PX4 simulator uavtest runs) has no obstacles — the vehicle flies
    through them, so they are only judged geometrically against the trajectory — and, in PX4
    v1.15, no wind model (SIH's SIH_WIND_N/E parameters arrived after v1.15).
    """
    from uavtest.spec.collision_prevention import collision_prevention_warnings

    out = collision_prevention_warnings(spec)
    if spec.vehicle.simulator is not Simulator.PX4:
        return out
    if spec.world.obstacles:
        n = len(spec.world.obstacles)
        out.append(
            f"PX4 SITL (SIH) has no obstacles: the {n} obstacle(s) are judged only geometrically "
            "against the trajectory; the vehicle cannot crash into them"
        )
    if spec.vehicle.avoidance is Avoidance.LOCAL_PLANNER:
        out.append(
            "PX4 SITL runs without PX4-Avoidance: vehicle.avoidance local-planner is flown only by "
            "the built-in simulator (simulator: builtin); here the mission is flown as planned"
        )
    w = spec.world.wind
    if w.mean_speed > 0 or (w.max_speed or 0) > 0:
        out.append(
            f"PX4 SITL (SIH, v1.15) has no wind model: the wind ({w.mean_speed:g} m/s) is not simulated"
        )
    return out


def reference_from_points(reference: ReferenceTrajectory) -> Trajectory:
    """An inline reference (rows t, x, y, z) as a Trajectory."""
    rows = np.asarray(reference.points, dtype=np.float64)
    return Trajectory(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], np.zeros(len(rows)))


def geofence_violation(trajectory: Trajectory, fence: Geofence) -> float:
    """How far (metres, 3-D) the flight went furthest outside the fence box; 0 when always inside."""
    if len(trajectory) == 0:
        return 0.0
    pos = trajectory.positions()
    lo = np.array([fence.min_x, fence.min_y, fence.min_z])
    hi = np.array([fence.max_x, fence.max_y, fence.max_z])
    outside = np.maximum(lo - pos, 0.0) + np.maximum(pos - hi, 0.0)
    return float(np.sqrt((outside**2).sum(axis=1)).max())


def _fmt(v: float) -> str:
    return f"{v:.2f}"


def judge_flight(
    trajectory: Trajectory,
    assertions: Assertions,
    *,
    obstacles: Sequence[Obstacle] = (),
    mission: MissionProgress | None = None,
    mission_expected: bool = False,
    reference: Trajectory | None = None,
    vehicle_radius: float = 0.0,
    crash: str | None = None,
    expect_flight: bool = False,
    refusal: str | None = None,
    collision_seen: str | None = None,
) -> tuple[FlightMetrics, list[AssertionResult], Verdict, str]:
    """Measure the flight and check each assertion that applies.

    ``expect_flight``: the test flies (``flight_intent``). Then an empty ``trajectory`` is a
    ``fail`` whose reason starts "the vehicle never took off" (followed by ``refusal``, the
    vehicle's own reason when it refused a command), and the assertions that need a flight
    (noCollision, minObstacleDistance, geofence, similarity) are "not judged" (not passed).

    ``crash``: a crash the log itself reports (``uavtest.analysis.ulog.crash_reported``); it
    counts as a collision even when the logged estimate stops short of the box.
    ``collision_seen``: where the runner saw the vehicle's reported position inside a box and
    ended the flight (the log closes at the disarm and may stop short of that position); a
    collision likewise.

    ``mission_expected``: the test has a mission, so ``missionCompleted`` applies even when
    ``mission`` (the progress) is unknown — then it fails saying so. Without an expected mission,
    a known ``mission`` (e.g. from the log's ``mission_result``) is still checked.
    """
    flew = len(trajectory) > 0
    unjudged = expect_flight and not flew  # a flight was due and did not happen
    results: list[AssertionResult] = []

    def not_judged(name: str, limit: float | None = None) -> None:
        results.append(
            AssertionResult(
                name=name, passed=False, limit=limit, message=f"{name} not judged: {NEVER_TOOK_OFF}"
            )
        )

    metrics = FlightMetrics(
        flight_time=trajectory.duration if flew else 0.0,
        max_altitude=float(trajectory.altitude.max()) if flew else None,
    )

    # ----------------------------------------------------------------- obstacles
    if obstacles and flew:
        d = distances_to_obstacles(trajectory.x, trajectory.y, trajectory.z, obstacles, radius=vehicle_radius)
        metrics.min_obstacle_distance = float(d.min())
        metrics.collision = bool(d.min() <= 0.0)
        metrics.min_obstacle_distance_2d = competition_distance(trajectory, obstacles)
        metrics.competition_points = competition_points(metrics.min_obstacle_distance_2d)
    if crash is not None or collision_seen is not None:
        metrics.collision = True
    if obstacles and assertions.no_collision and unjudged and crash is None and collision_seen is None:
        not_judged("noCollision", 0.0)
    elif obstacles and assertions.no_collision:
        hit = metrics.collision
        where = ""
        if hit and flew and bool((d <= 0.0).any()):
            first = int(np.argmax(d <= 0.0))
            where = f" at t={trajectory.t[first]:.1f} s"
        elif crash is not None:
            where = f": the log reports '{crash}'"
        elif collision_seen is not None:
            where = f": {collision_seen}"
        results.append(
            AssertionResult(
                name="noCollision",
                passed=not hit,
                value=metrics.min_obstacle_distance,
                limit=0.0,
                message=f"{HARD_FAIL}: collision with an obstacle{where}" if hit else "no collision",
            )
        )
    if obstacles and assertions.min_obstacle_distance is not None and unjudged:
        not_judged("minObstacleDistance", assertions.min_obstacle_distance)
    if obstacles and assertions.min_obstacle_distance is not None and flew:
        limit = assertions.min_obstacle_distance
        dist = metrics.min_obstacle_distance
        assert dist is not None
        ok = dist >= limit
        short = (
            f"{SOFT_FAIL}: min distance {_fmt(dist)} m < {_fmt(limit)} m (short by {_fmt(limit - dist)} m)"
        )
        msg = f"min distance {_fmt(dist)} m >= {_fmt(limit)} m" if ok else short
        results.append(
            AssertionResult(name="minObstacleDistance", passed=ok, value=dist, limit=limit, message=msg)
        )

    # ----------------------------------------------------------------- mission
    if mission is not None:
        metrics.mission_completed = mission.finished
        metrics.waypoints_reached = mission.reached
        metrics.waypoints_total = mission.total
    if assertions.mission_completed and (mission_expected or mission is not None):
        if mission is None:
            results.append(
                AssertionResult(
                    name="missionCompleted",
                    passed=False,
                    message="mission progress unknown: no mission_result in the log, no waypoints to check",
                )
            )
        else:
            msg = f"mission {'completed' if mission.finished else 'not completed'}: "
            msg += f"{mission.reached}/{mission.total} items reached ({mission.source})"
            results.append(
                AssertionResult(
                    name="missionCompleted",
                    passed=mission.finished,
                    value=float(mission.reached),
                    limit=float(mission.total),
                    message=msg,
                )
            )

    # ----------------------------------------------------------------- flight time
    if assertions.max_flight_time is not None:
        ft = metrics.flight_time or 0.0
        limit = assertions.max_flight_time
        ok = ft <= limit
        results.append(
            AssertionResult(
                name="maxFlightTime",
                passed=ok,
                value=ft,
                limit=limit,
                message=f"flight time {ft:.1f} s {'<=' if ok else '>'} {limit:.1f} s",
            )
        )

    # ----------------------------------------------------------------- geofence
    if assertions.geofence is not None and unjudged:
        not_judged("geofence", 0.0)
    elif assertions.geofence is not None:
        out = geofence_violation(trajectory, assertions.geofence)
        metrics.geofence_violation = out
        results.append(
            AssertionResult(
                name="geofence",
                passed=out <= 0.0,
                value=out,
                limit=0.0,
                message="inside the geofence" if out <= 0.0 else f"left the geofence by {_fmt(out)} m",
            )
        )

    # ----------------------------------------------------------------- similarity
    sim = assertions.similarity
    if reference is None and sim is not None and sim.reference is not None:
        reference = reference_from_points(sim.reference)
    if reference is not None and len(reference) and flew:
        metric = sim.metric.value if sim is not None else "dtw"
        metrics.similarity = similarity(metric, trajectory, reference)
        metrics.similarity_metric = metric
    if sim is not None and unjudged:
        not_judged("similarity", sim.threshold)
    elif sim is not None:
        if metrics.similarity is None:
            why = "no reference trajectory" if reference is None or not len(reference) else "no flight"
            results.append(
                AssertionResult(
                    name="similarity", passed=False, limit=sim.threshold, message=f"cannot compare: {why}"
                )
            )
        else:
            v = metrics.similarity
            ok = v <= sim.threshold
            label = "DTW per step" if sim.metric.value == "dtw" else "Fréchet distance"
            cmp = "<=" if ok else ">"
            results.append(
                AssertionResult(
                    name="similarity",
                    passed=ok,
                    value=v,
                    limit=sim.threshold,
                    message=f"{label} to the reference {_fmt(v)} m {cmp} {_fmt(sim.threshold)} m",
                )
            )

    failed = [r for r in results if not r.passed]
    reasons = [r.message for r in failed]
    if unjudged:
        reasons.insert(0, NEVER_TOOK_OFF + (f": {refusal}" if refusal else ""))
    verdict = Verdict.FAIL if reasons else Verdict.PASS
    return metrics, results, verdict, "; ".join(reasons)


def judge(
    trajectory: Trajectory,
    spec: UavTestSpec,
    *,
    mission: MissionProgress | None = None,
    reference: Trajectory | None = None,
    vehicle_radius: float = 0.0,
    crash: str | None = None,
    commands: Sequence[Command] | None = None,
    refusal: str | None = None,
    collision_seen: str | None = None,
) -> tuple[FlightMetrics, list[AssertionResult], Verdict, str]:
    """Metrics, assertion results, verdict (pass / fail) and reason of one flight of ``spec``.

    Whether a flight was due is ``flight_intent(spec, commands)``; ``refusal`` is the vehicle's
    reason when it refused a command, ``crash`` and ``collision_seen`` collisions the log or the
    runner reports (see ``judge_flight``).

    ``mission``: progress from the log's ``mission_result``; when None and the test has a
    mission, it is worked out from the path (``uavtest.analysis.mission``). ``reference``: the
    reference trajectory for a ``similarity`` assertion (else its inline ``reference``).
    """
    if mission is None and spec.mission is not None:
        targets = mission_targets(spec)
        if targets:
            mission = progress_from_waypoints(trajectory, targets, acceptance_radius=acceptance_radius(spec))
    return judge_flight(
        trajectory,
        spec.assertions,
        obstacles=spec.world.obstacles,
        mission=mission,
        mission_expected=spec.mission is not None,
        reference=reference,
        vehicle_radius=vehicle_radius,
        crash=crash,
        expect_flight=flight_intent(spec, commands) is not None,
        refusal=refusal,
        collision_seen=collision_seen,
    )
