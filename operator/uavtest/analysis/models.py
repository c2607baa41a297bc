"""Result models: one replica's verdict (``result.json``) and a run's summary (``summary.json``).

Words as in DESIGN.md: a replica's verdict is ``pass``, ``fail`` (an assertion did not hold —
the drone's fault) or ``error`` (the bench's fault). Errors are never counted as failures.
"""

from __future__ import annotations

from enum import StrEnum

from pydantic import BaseModel, ConfigDict, Field

__all__ = [
    "AssertionResult",
    "CompetitionScore",
    "FlightMetrics",
    "InjectedFault",
    "MissionProgress",
    "ReplicaResult",
    "RunSummary",
    "Stats",
    "Verdict",
]


class Verdict(StrEnum):
    """The verdict of a replica (or of a run)."""

    PASS = "pass"
    FAIL = "fail"
    ERROR = "error"


class _Result(BaseModel):
    model_config = ConfigDict(extra="forbid")


class AssertionResult(_Result):
    """One assertion checked against one flight."""

    name: str = Field(
        description="noCollision, minObstacleDistance, missionCompleted, maxFlightTime, geofence, similarity"
    )
    passed: bool
    value: float | None = Field(None, description="what was measured (metres, seconds, ...)")
    limit: float | None = Field(None, description="the limit it was compared with")
    message: str = Field("", description="e.g. 'min distance 0.82 m < 1.5 m (short by 0.68 m)'")


class MissionProgress(_Result):
    """How far a mission got: from PX4's ``mission_result`` or from waypoints reached in order."""

    reached: int = Field(ge=0, description="mission items / waypoints reached")
    total: int = Field(ge=0, description="mission items / waypoints in the mission")
    finished: bool = Field(description="the whole mission was flown")
    source: str = Field(description="'mission_result' (PX4 topic) or 'waypoints' (from the path)")


class FlightMetrics(_Result):
    """What was measured on one flight (takeoff to landing, or to the end of the log)."""

    flight_time: float | None = Field(None, description="seconds, takeoff to landing / end of log")
    min_obstacle_distance: float | None = Field(None, description="metres, 3-D; None without obstacles")
    min_obstacle_distance_2d: float | None = Field(
        None,
        description="metres in the (x, y) plane, as the UAV Testing Competition and Aerialist measure it "
        "(flying over a box is 0); None without obstacles",
    )
    competition_points: int | None = Field(
        None,
        description="the competition's points from the 2-D distance: 5 (< 0.25 m), 2 (< 1 m), 1 (< 1.5 m), 0",
    )
    collision: bool = False
    mission_completed: bool | None = None
    waypoints_reached: int | None = None
    waypoints_total: int | None = None
    similarity: float | None = Field(None, description="distance to the reference, metres")
    similarity_metric: str | None = Field(None, description="dtw (mean per step) or frechet")
    max_altitude: float | None = Field(None, description="metres above home (-z)")
    geofence_violation: float | None = Field(
        None, description="metres the vehicle went furthest outside the geofence (0 inside)"
    )


class InjectedFault(_Result):
    """A fault the runner injected (MAV_CMD_INJECT_FAILURE) and how the vehicle answered."""

    unit: str = Field(description="gps, motor, battery, ... (the test's faults[].unit)")
    type: str = Field(description="off, stuck, garbage, wrong, slow, delayed, intermittent, ok")
    instance: int = Field(0, ge=0)
    at: float = Field(description="seconds on the vehicle clock the test asked for")
    sent_ms: int | None = Field(None, description="vehicle ms it was sent; None: the flight ended before")
    ack_ms: int | None = Field(None, description="vehicle ms of the COMMAND_ACK")
    result: str | None = Field(None, description="MAV_RESULT of the ACK (ACCEPTED, DENIED, ...); None: none")


class ReplicaResult(_Result):
    """One replica's outcome: ``result.json``."""

    index: int = Field(ge=0)
    seed: int
    verdict: Verdict
    reason: str = Field("", description="why fail / error; empty on pass")
    assertions: list[AssertionResult] = Field(default_factory=list)
    metrics: FlightMetrics | None = None
    sim_time: float | None = Field(None, description="vehicle seconds flown")
    wall_time: float | None = Field(None, description="wall-clock seconds the replica took")
    attempts: int = Field(1, ge=1, description="1 + retries after bench errors")
    unmodelled_params: list[str] = Field(
        default_factory=list,
        description="PX4 parameters the test sets that have no effect in the built-in simulator",
    )
    warnings: list[str] = Field(
        default_factory=list,
        description="what the simulator could not simulate (e.g. PX4 SIH: obstacles, wind)",
    )
    faults: list[InjectedFault] = Field(
        default_factory=list, description="the test's faults as injected, with the vehicle's answers"
    )


class Stats(_Result):
    """min / mean / max of one metric over the valid replicas that have it."""

    min: float
    mean: float
    max: float
    count: int = Field(ge=1)


class CompetitionScore(_Result):
    """The UAV Testing Competition's view of a run: its points over the valid replicas that have them."""

    total: int = Field(ge=0, description="points summed over the replicas")
    mean: float = Field(ge=0, description="points per replica (the competition scores a test by this mean)")
    count: int = Field(ge=1, description="replicas scored (valid, with obstacles and a flight)")
    hard_fails: int = Field(ge=0, description="scored replicas that collided with an obstacle")
    soft_fails: int = Field(ge=0, description="scored replicas without collision, 2-D distance < 1.5 m")


class RunSummary(_Result):
    """A run's outcome over its replicas: ``aggregate/summary.json``."""

    test: str
    namespace: str
    run_id: str
    replicas: int = Field(ge=0)
    passed: int = Field(ge=0)
    failed: int = Field(ge=0)
    errors: int = Field(ge=0)
    flakiness: float | None = Field(None, description="failed / valid replicas; None when none is valid")
    flaky: bool = Field(description="valid replicas both passed and failed (0 < flakiness < 1)")
    verdict: Verdict = Field(description="pass: all valid passed; fail: any failed; error: only errors")
    min_obstacle_distance: Stats | None = None
    min_obstacle_distance_2d: Stats | None = Field(None, description="the competition's 2-D distance, metres")
    competition_points: CompetitionScore | None = None
    flight_time: Stats | None = None
    warnings: list[str] = Field(default_factory=list, description="the replicas' warnings, each once")
    results: list[ReplicaResult] = Field(default_factory=list)
    unmodelled_params: list[str] = Field(
        default_factory=list,
        description="PX4 parameters the test sets that have no effect in the built-in simulator",
    )
