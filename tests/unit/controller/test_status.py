"""A UavTest's status from its Job, pods and (at the end) the run's summary — pure."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from typing import Any

from uavtest.analysis.flakiness import summarize
from uavtest.analysis.models import FlightMetrics, ReplicaResult, RunSummary, Verdict
from uavtest.controller.status import awaiting_aggregation, is_final, status_from
from uavtest.controller.views import job_view, parse_indexes, pod_view, run_view
from uavtest.spec.status import UavTestStatus

from .controller_bodies import RUN, job_body, pod_body, uavtest_body

T0 = datetime(2025, 1, 1, 10, 0, tzinfo=UTC)
STORE = "s3://uavtest"


def status(
    job: dict[str, Any] | None,
    pods: list[dict[str, Any]],
    *,
    previous: dict[str, Any] | None = None,
    replicas: int = 4,
    now: datetime = T0,
    **kw: Any,
) -> UavTestStatus:
    test = run_view(uavtest_body(replicas=replicas, status=previous))
    views = [v for v in (pod_view(p) for p in pods) if v is not None]
    return status_from(test, job_view(job) if job else None, views, store_url=STORE, now=now, **kw)


def cond(st: UavTestStatus, type_: str) -> tuple[str, str]:
    c = next(c for c in st.conditions if c.type == type_)
    return c.status.value, c.reason


def result(index: int, verdict: Verdict, distance: float | None = 2.0, reason: str = "") -> ReplicaResult:
    metrics = (
        None if verdict == Verdict.ERROR else FlightMetrics(min_obstacle_distance=distance, flight_time=30.0)
    )
    return ReplicaResult(index=index, seed=10 + index, verdict=verdict, reason=reason, metrics=metrics)


def summary_of(*results: ReplicaResult) -> RunSummary:
    return summarize(list(results), test="hover", namespace="team-a", run_id=RUN)


def test_indexes_lists_parse_ranges() -> None:
    assert parse_indexes("1,3-5,7") == {1, 3, 4, 5, 7}
    assert parse_indexes("") == frozenset()
    assert parse_indexes(None) == frozenset()


def test_before_the_job_every_replica_is_pending() -> None:
    st = status(None, [])
    assert st.phase == "Pending"
    assert (st.replicas, st.pending, st.running, st.passed) == (4, 4, 0, 0)
    assert cond(st, "Complete") == ("False", "ReplicasPending")
    assert cond(st, "Succeeded") == ("Unknown", "ReplicasPending")
    assert st.run_id == RUN
    assert st.artifacts.store == f"{STORE}/team-a/hover/{RUN}/"
    assert st.observed_generation == 1


def test_counts_follow_the_pods_and_the_jobs_indexes() -> None:
    job = job_body(completed="2", active=2, ready=1)
    pods = [
        pod_body(0, "Running"),
        pod_body(1, "Pending"),
        pod_body(2, "Succeeded", exit_code=0),
    ]
    st = status(job, pods)
    assert st.phase == "Running"
    assert (st.pending, st.running, st.passed, st.failed, st.errors) == (2, 1, 1, 0, 0)
    assert cond(st, "Complete") == ("False", "ReplicasRunning")
    assert [(r.index, r.verdict.value) for r in st.results] == [(2, "pass")]
    assert st.start_time == datetime(2025, 1, 1, 10, 0, tzinfo=UTC)


def test_a_failed_index_is_a_fail_or_an_error_by_the_runners_exit_code() -> None:
    job = job_body(completed="0", failed="1,2", active=1)
    pods = [
        pod_body(0, "Succeeded", exit_code=0),
        pod_body(1, "Failed", exit_code=1),
        pod_body(2, "Failed", exit_code=3),
        pod_body(3, "Running"),
    ]
    st = status(job, pods)
    assert (st.passed, st.failed, st.errors, st.running) == (1, 1, 1, 1)
    assert st.flakiness == 0.5  # 1 failed of 2 valid so far
    error = next(r for r in st.results if r.index == 2)
    assert error.verdict == "error" and "runner exit 3" in error.reason
    assert [r.index for r in st.results] == [1, 2, 0]  # failures, then errors, then passes


def test_a_retried_replica_counts_once_as_its_newest_attempt() -> None:
    job = job_body(active=1)
    pods = [
        pod_body(0, "Failed", exit_code=3, created="2025-01-01T10:00:01Z", suffix="aaaaa"),
        pod_body(0, "Running", created="2025-01-01T10:02:00Z", suffix="bbbbb"),
    ]
    st = status(job, pods, replicas=1)
    assert (st.running, st.pending, st.errors, st.failed) == (1, 0, 0, 0)


def test_a_finished_job_awaits_aggregation() -> None:
    job = job_body(completed="0-2", failed="3", terminal=("Failed", "FailedIndexes"))
    pods = [pod_body(i, "Succeeded", exit_code=0) for i in range(3)] + [pod_body(3, "Failed", exit_code=1)]
    st = status(job, pods)
    assert cond(st, "Complete") == ("False", "Aggregating")
    assert awaiting_aggregation(st.dump())
    assert not is_final(st.dump())
    assert st.phase == "Running"


def test_deadline_ends_the_run_with_errors_for_unfinished_replicas() -> None:
    job = job_body(completed="0", terminal=("Failed", "DeadlineExceeded"))
    st = status(job, [pod_body(0, "Succeeded", exit_code=0), pod_body(1, "Running")])
    assert (st.passed, st.errors, st.running, st.pending) == (1, 3, 0, 0)
    assert cond(st, "Complete")[1] == "Aggregating"
    assert all("DeadlineExceeded" in r.reason for r in st.results if r.verdict == "error")


def test_a_deleted_job_ends_the_run() -> None:
    st = status(None, [], job_deleted=True)
    assert st.errors == 4
    assert awaiting_aggregation(st.dump())
    assert "deleted" in st.results[0].reason


def test_store_trouble_is_visible_and_retried() -> None:
    job = job_body(completed="0-3", terminal=("Complete", "CompletionsReached"))
    st = status(job, [], aggregation_error="store get x failed: connection refused")
    assert cond(st, "Complete") == ("False", "StoreUnavailable")
    assert "connection refused" in next(c for c in st.conditions if c.type == "Complete").message
    assert awaiting_aggregation(st.dump())


def test_final_status_comes_from_the_summary() -> None:
    job = job_body(completed="0,2", failed="1,3", terminal=("Failed", "FailedIndexes"))
    summary = summary_of(
        result(0, Verdict.PASS, 2.5),
        result(1, Verdict.FAIL, 0.8, "min distance 0.80 m < 1.5 m"),
        result(2, Verdict.PASS, 3.0),
        result(3, Verdict.ERROR, reason="artifacts missing: team-a/hover/x/replica-3/result.json"),
    )
    st = status(job, [], summary=summary, now=T0 + timedelta(minutes=5))
    assert st.phase == "Failed"
    assert (st.passed, st.failed, st.errors, st.pending, st.running) == (2, 1, 1, 0, 0)
    assert st.flakiness == 1 / 3 and st.flaky
    assert cond(st, "Complete") == ("True", "Aggregated")
    assert cond(st, "Failed") == ("True", "ReplicasFailed")
    assert cond(st, "Succeeded") == ("False", "ReplicasFailed")
    assert cond(st, "Flaky") == ("True", "FlakyReplicas")
    assert [r.index for r in st.results] == [1, 3, 0, 2]
    assert st.results[0].min_distance == 0.8
    assert "artifacts missing: team-a/hover/x/replica-3/result.json" in st.results[1].reason
    assert st.completion_time == T0 + timedelta(minutes=5)
    assert st.artifacts.summary == f"{STORE}/team-a/hover/{RUN}/aggregate/summary.json"
    assert st.artifacts.plot is not None
    assert is_final(st.dump())


def test_final_phase_matches_the_local_exit_codes() -> None:
    passed = status(None, [], summary=summary_of(result(0, Verdict.PASS), result(1, Verdict.PASS)))
    assert passed.phase == "Succeeded" and cond(passed, "Succeeded") == ("True", "AllReplicasPassed")
    assert cond(passed, "Flaky") == ("False", "StableReplicas")
    mixed = status(None, [], summary=summary_of(result(0, Verdict.PASS), result(1, Verdict.ERROR)))
    assert mixed.phase == "Error" and cond(mixed, "Failed") == ("True", "BenchErrors")
    errors = status(None, [], summary=summary_of(result(0, Verdict.ERROR), result(1, Verdict.ERROR)))
    assert errors.phase == "Error" and cond(errors, "Failed") == ("True", "OnlyBenchErrors")
    assert errors.flakiness is None and errors.artifacts.plot is None


def test_error_reason_keeps_why_the_replica_never_finished() -> None:
    job = job_body(completed="0", terminal=("Failed", "DeadlineExceeded"))
    summary = summary_of(
        result(0, Verdict.PASS),
        *(result(i, Verdict.ERROR, reason=f"artifacts missing: r{i}") for i in range(1, 4)),
    )
    st = status(job, [], summary=summary)
    r1 = next(r for r in st.results if r.index == 1)
    assert "DeadlineExceeded" in r1.reason and "artifacts missing: r1" in r1.reason


def test_transition_time_changes_only_when_a_condition_flips() -> None:
    job = job_body(active=1)
    first = status(job, [pod_body(0, "Running")], now=T0)
    later = status(job, [pod_body(0, "Running")], previous=first.dump(), now=T0 + timedelta(minutes=1))
    t = {c.type: c.last_transition_time for c in later.conditions}
    assert t["Complete"] == T0  # still False: reason may change, time does not
    assert later == first
    final = status(
        job,
        [],
        previous=later.dump(),
        summary=summary_of(result(0, Verdict.PASS)),
        now=T0 + timedelta(minutes=2),
    )
    t2 = {c.type: c.last_transition_time for c in final.conditions}
    assert t2["Complete"] == T0 + timedelta(minutes=2)  # False → True


def test_a_final_status_is_never_rewritten_by_late_events() -> None:
    final = status(None, [], summary=summary_of(result(0, Verdict.PASS), result(1, Verdict.FAIL, 0.5)))
    late = status(job_body(active=1), [pod_body(0, "Running")], previous=final.dump())
    assert late == final


def test_status_list_is_bounded_and_counts_the_rest() -> None:
    summary = summary_of(*(result(i, Verdict.PASS) for i in range(120)))
    st = status(None, [], replicas=120, summary=summary)
    assert len(st.results) == 50 and st.results_omitted == 70
    assert st.passed == 120


def test_status_wire_form_round_trips() -> None:
    st = status(
        job_body(completed="0", active=1), [pod_body(0, "Succeeded", exit_code=0), pod_body(1, "Running")]
    )
    wire = st.dump()
    assert "runId" in wire and "observedGeneration" in wire
    assert UavTestStatus.model_validate(wire) == st


def test_a_finished_pod_the_job_has_not_recorded_yet_is_still_running() -> None:
    # the job controller lags behind its pods under load: such a replica is neither pending nor done
    st = status(
        job_body(active=2), [pod_body(0, "Succeeded", exit_code=0), pod_body(1, "Failed", exit_code=1)]
    )
    assert (st.running, st.pending, st.passed, st.failed) == (2, 2, 0, 0)
    assert st.phase == "Running"
    retry = status(job_body(active=1), [pod_body(0, "Failed", exit_code=3)], replicas=1)
    assert (retry.running, retry.pending) == (0, 1)  # exit 3 is retried: a new pod will come


def test_what_the_run_could_not_simulate_is_in_the_status_and_an_event() -> None:
    from uavtest.controller.events import events_for
    from uavtest.spec.status import MAX_WARNINGS, Phase

    summary = summary_of(result(0, Verdict.PASS), result(1, Verdict.PASS)).model_copy(
        update={
            "warnings": ["PX4 SIH has no obstacles: they are judged against the trajectory only"],
            "unmodelled_params": ["SDLOG_PROFILE"],
        }
    )
    st = status(None, [], summary=summary)
    assert st.warnings[0].startswith("PX4 SIH has no obstacles")
    assert any("SDLOG_PROFILE" in w for w in st.warnings[1:])
    limits = [e for e in events_for(summary, Phase.SUCCEEDED) if e.reason == "SimulatorLimits"]
    assert len(limits) == 1 and limits[0].type == "Warning" and "SDLOG_PROFILE" in limits[0].message

    many = summary.model_copy(update={"warnings": [f"w{i} " + "x" * 900 for i in range(20)]})
    bounded = status(None, [], summary=many)
    assert len(bounded.warnings) == MAX_WARNINGS and all(len(w) <= 512 for w in bounded.warnings)

    quiet = status(None, [], summary=summary_of(result(0, Verdict.PASS)))
    assert quiet.warnings == []
    assert not [
        e
        for e in events_for(summary_of(result(0, Verdict.PASS)), Phase.SUCCEEDED)
        if e.reason == "SimulatorLimits"
    ]


def test_a_runs_conditions_follow_kstatus_running_passed_failed() -> None:
    """Reconciling while replicas fly (kstatus InProgress), Ready once passed (Current), Stalled
    once failed (Failed); the abnormal-true types are False, not absent, otherwise."""
    running = status(job_body(active=2), [pod_body(0, "Running")])
    assert cond(running, "Reconciling")[0] == "True" and cond(running, "Ready")[0] == "False"
    assert cond(running, "Stalled")[0] == "False"
    passed = status(None, [], summary=summary_of(result(0, Verdict.PASS), result(1, Verdict.PASS)))
    assert [cond(passed, t)[0] for t in ("Ready", "Reconciling", "Stalled")] == ["True", "False", "False"]
    failed = status(None, [], summary=summary_of(result(0, Verdict.PASS), result(1, Verdict.FAIL)))
    assert [cond(failed, t)[0] for t in ("Ready", "Reconciling", "Stalled")] == ["False", "False", "True"]
    assert passed.observed_generation == 1
