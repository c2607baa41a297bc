"""Stage 7: the replica's verdict, from what the core saw and the flight log.

Bench faults (the core's error, a missing or unreadable log) are ``error`` with the reason and are
never judged; otherwise ``uavtest.analysis.judge`` decides ``pass`` or ``fail`` from the log. A
test that flies whose vehicle never took off is ``fail`` with the vehicle's reason
(``vehicle_reason``: the commands it refused, with its STATUSTEXTs); a vehicle that refused to
arm until the runner gave up is ``fail`` even in a test that does not fly.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

from uavtest.analysis.models import FlightMetrics, ReplicaResult, Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import (
    VERDICT_TOPICS,
    crash_reported,
    mission_progress_from_ulog,
    read_ulog,
    trajectory_from_ulog,
)
from uavtest.analysis.verdict import NEVER_TOOK_OFF, judge, simulator_warnings
from uavtest.errors import UavTestError
from uavtest.runner.core import Ending, FlightReport
from uavtest.runner.plan import flight_commands
from uavtest.spec.models import UavTestSpec

__all__ = ["Analysis", "analyse", "collision_seen", "online_metrics", "vehicle_reason"]

log = logging.getLogger(__name__)

STATUS_WINDOW_MS = 1000  # STATUSTEXTs up to this long after a refusing ACK belong to it
WARNING_SEVERITY = 4  # MAV_SEVERITY_WARNING: this and more severe explain a vehicle's refusal
CRITICAL_SEVERITY = 2  # MAV_SEVERITY_CRITICAL: how PX4 says why it refuses a mission


def _quoted(texts: list[str]) -> str:
    return "; ".join(f'"{t}"' for t in dict.fromkeys(texts))


def vehicle_reason(report: FlightReport) -> str | None:
    """Why the vehicle did not fly, in its own words, or None when it refused nothing and said
    nothing of warning severity. Pure.

    Each refused command (unique by label) with the STATUSTEXTs the vehicle sent between the
    command and ``STATUS_WINDOW_MS`` after its ACK, e.g. 'vehicle refused arm (COMMAND_ACK
    DENIED): "Arming denied: no valid mission"'. Without refusals: the vehicle's warnings
    (failsafes), e.g. 'vehicle says: "Failsafe: ..."'.
    """
    parts: list[str] = []
    seen: set[str] = set()
    for r in report.refusals:
        if r.label in seen:
            continue
        seen.add(r.label)
        texts = [t for ms, _sev, t in report.status_log if r.sent_ms <= ms <= r.ack_ms + STATUS_WINDOW_MS]
        part = f"vehicle refused {r.label} (COMMAND_ACK {r.result})"
        part = f"{part}: {_quoted(texts)}" if texts else part
        if "mission" in r.label:
            # PX4 says why a mission is not valid when it checks it (the upload, the arming:
            # "Mission rejected: ...", "Geofence violation for waypoint N"), not when refusing it
            earlier = [t for ms, sev, t in report.status_log if sev <= CRITICAL_SEVERITY and ms < r.sent_ms]
            if earlier:
                part += f"; it said before: {_quoted(earlier[-2:])}"
        parts.append(part)
    if parts:
        return "; ".join(parts)
    start = report.start_ms if report.start_ms is not None else 0
    warnings = [t for ms, sev, t in report.status_log if sev <= WARNING_SEVERITY and ms >= start]
    return f"vehicle says: {_quoted(warnings[-3:])}" if warnings else None


class Analysis:
    """The result and the trajectory (None when there is no readable log)."""

    def __init__(self, result: ReplicaResult, trajectory: Trajectory | None) -> None:
        self.result = result
        self.trajectory = trajectory


def online_metrics(report: FlightReport) -> FlightMetrics | None:
    """What the runner measured during the flight (for a replica that could not be judged)."""
    if report.start_ms is None:
        return None
    return FlightMetrics(
        flight_time=None,
        min_obstacle_distance=report.min_distance if math.isfinite(report.min_distance) else None,
        collision=report.collision is not None,
        geofence_violation=report.geofence_violation or None,
    )


def collision_seen(report: FlightReport) -> str | None:
    """Where the runner ended the flight because the vehicle reported its position inside a box
    (LOCAL_POSITION_NED), else None. Pure. The vehicle's log closes at the disarm that follows,
    so it may end a step short of that position; the verdict still counts the collision."""
    c = report.collision
    if report.ending is not Ending.COLLISION or c is None:
        return None
    return (
        f"the vehicle reported its position inside it at t={c.time_ms / 1000:.2f} s "
        f"(LOCAL_POSITION_NED {c.x:.2f}, {c.y:.2f}, {c.z:.2f}) and the runner ended the flight there"
    )


def _reference(spec: UavTestSpec) -> Trajectory | None:
    sim = spec.assertions.similarity
    if sim is None or sim.log_file is None:
        return None
    return trajectory_from_ulog(read_ulog(Path(sim.log_file), VERDICT_TOPICS), source=sim.log_file)


def analyse(
    report: FlightReport,
    log_path: Path | None,
    spec: UavTestSpec,
    *,
    index: int,
    seed: int,
    log_error: str | None = None,
    wall_time: float | None = None,
) -> Analysis:
    """Judge one replica. ``log_error`` says why there is no log when ``log_path`` is None."""

    def error(reason: str, trajectory: Trajectory | None = None) -> Analysis:
        result = ReplicaResult(
            index=index,
            seed=seed,
            verdict=Verdict.ERROR,
            reason=reason,
            metrics=online_metrics(report),
            sim_time=report.sim_time,
            wall_time=wall_time,
            warnings=warnings,
        )
        return Analysis(result, trajectory)

    warnings = simulator_warnings(spec) + report.delays + report.warnings
    for w in warnings:
        log.warning("%s", w)

    def refused() -> Analysis:
        """The vehicle refused to arm: no flight and (usually) no log — the vehicle's doing."""
        reason = NEVER_TOOK_OFF + ": " + (vehicle_reason(report) or "the vehicle refused to arm")
        log.info("verdict fail: %s", reason)
        result = ReplicaResult(
            index=index,
            seed=seed,
            verdict=Verdict.FAIL,
            reason=reason,
            metrics=FlightMetrics(flight_time=0.0),
            sim_time=report.sim_time,
            wall_time=wall_time,
            warnings=warnings,
        )
        return Analysis(result, trajectory)

    trajectory: Trajectory | None = None
    ulog = None
    read_error: str | None = None
    if log_path is not None:
        try:
            ulog = read_ulog(log_path, VERDICT_TOPICS)
            trajectory = trajectory_from_ulog(ulog, source=str(log_path))
        except UavTestError as e:
            read_error = f"log unreadable: {e}"
    if report.error:
        return error(report.error, trajectory)
    if report.ending is Ending.REFUSED and (ulog is None or trajectory is None or not len(trajectory)):
        return refused()
    if log_path is None:
        return error(log_error or "log missing")
    if ulog is None or trajectory is None:
        return error(read_error or "log unreadable")
    try:
        reference = _reference(spec)
    except UavTestError as e:
        return error(f"reference log for the similarity assertion: {e}", trajectory)
    metrics, assertions, verdict, reason = judge(
        trajectory,
        spec,
        mission=mission_progress_from_ulog(ulog),
        reference=reference,
        crash=crash_reported(ulog),
        commands=flight_commands(spec),
        refusal=vehicle_reason(report),
        collision_seen=collision_seen(report),
    )
    if report.ending is Ending.REFUSED and verdict is Verdict.PASS:
        return refused()
    if report.ending is Ending.BLOCKED:  # the runner ended the flight: no progress in the mission
        blocked = next((n for n in report.notes if n.startswith("blocked")), "blocked")
        verdict, reason = Verdict.FAIL, "; ".join(r for r in (blocked, reason) if r)
    log.info("verdict %s%s", verdict, f": {reason}" if reason else "")
    return Analysis(
        ReplicaResult(
            index=index,
            seed=seed,
            verdict=verdict,
            reason=reason,
            assertions=assertions,
            metrics=metrics,
            sim_time=report.sim_time,
            wall_time=wall_time,
            warnings=warnings,
        ),
        trajectory,
    )
