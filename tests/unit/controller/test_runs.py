"""A UavTest and its runs: which runs to create (spec change, re-run, schedule), history, summary."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

import pytest
from pydantic import ValidationError

from uavtest.controller.runs import (
    build_run,
    due_schedule_time,
    planned_runs,
    runs_to_delete,
    spec_hash,
    test_status_from,
)
from uavtest.controller.views import RunView, run_view, test_view
from uavtest.spec.models import UavTestSpec

from .controller_bodies import test_body, uavtest_body

NOW = datetime(2026, 3, 1, 12, 7, 30, tzinfo=UTC)


def done(phase: str, *, flaky: bool = False) -> dict[str, Any]:
    return {
        "phase": phase,
        "passed": 2,
        "failed": 1 if flaky else 0,
        "flakiness": 1 / 3 if flaky else 0.0,
        "flaky": flaky,
        "conditions": [
            {
                "type": "Complete",
                "status": "True",
                "reason": "Aggregated",
                "lastTransitionTime": "2026-03-01T10:00:00Z",
            }
        ],
    }


def run(name: str, created: str, status: dict[str, Any] | None = None) -> RunView:
    body = uavtest_body(status=status or {})
    body["metadata"]["name"] = name
    body["metadata"]["creationTimestamp"] = created
    return run_view(body)


def test_a_new_test_gets_its_first_run_named_after_its_generation() -> None:
    body = test_body()
    [plan] = planned_runs(test_view(body), body["spec"], now=NOW)
    assert (plan.name, plan.trigger.value) == ("hover-g1", "create")
    assert plan.status_patch == {"specHash": spec_hash(body["spec"]), "observedGeneration": 1}
    manifest = build_run(body, plan)
    assert manifest["kind"] == "UavTestRun" and manifest["metadata"]["name"] == "hover-g1"
    assert manifest["spec"]["testSpec"] == body["spec"]  # the frozen copy it flies
    assert manifest["spec"]["testGeneration"] == 1
    [owner] = manifest["metadata"]["ownerReferences"]
    assert (owner["kind"], owner["name"], owner["controller"]) == ("UavTest", "hover", True)


def test_a_spec_change_starts_a_new_run_and_an_unchanged_spec_none() -> None:
    first = test_body()
    seen = {"specHash": spec_hash(first["spec"]), "observedGeneration": 1}
    assert planned_runs(test_view(test_body(status=seen)), first["spec"], now=NOW) == []
    changed = test_body(generation=2, status=seen, replicas=7)
    [plan] = planned_runs(test_view(changed), changed["spec"], now=NOW)
    assert (plan.name, plan.trigger.value) == ("hover-g2", "spec-change")


def test_a_new_schedule_or_history_limit_alone_starts_no_run() -> None:
    first = test_body()
    seen = {"specHash": spec_hash(first["spec"])}
    later = test_body(generation=2, status=seen, schedule="0 3 * * *", successfulRunsHistoryLimit=9)
    assert planned_runs(test_view(later), later["spec"], now=NOW) == []


def test_a_new_rerun_annotation_value_starts_one_run_named_by_it() -> None:
    base = test_body()
    seen = {"specHash": spec_hash(base["spec"])}
    body = test_body(status=seen, annotations={"uavtest.io/rerun": "firmware-1.15.2"})
    [plan] = planned_runs(test_view(body), body["spec"], now=NOW)
    assert plan.trigger.value == "rerun" and plan.name.startswith("hover-r")
    assert plan.status_patch == {"lastRerun": "firmware-1.15.2"}
    again = test_body(
        status={**seen, "lastRerun": "firmware-1.15.2"}, annotations={"uavtest.io/rerun": "firmware-1.15.2"}
    )
    assert planned_runs(test_view(again), again["spec"], now=NOW) == []
    other = test_body(status={**seen, "lastRerun": "firmware-1.15.2"}, annotations={"uavtest.io/rerun": "2"})
    assert planned_runs(test_view(other), other["spec"], now=NOW)[0].name != plan.name


def test_the_schedule_starts_one_run_per_due_time_and_never_twice() -> None:
    base = test_body(schedule="*/5 * * * *", created="2026-03-01T11:00:00Z")
    seen = {"specHash": spec_hash(base["spec"])}
    body = test_body(schedule="*/5 * * * *", created="2026-03-01T11:00:00Z", status=seen)
    [plan] = planned_runs(test_view(body), body["spec"], now=NOW, schedule=True)
    due = datetime(2026, 3, 1, 12, 5, tzinfo=UTC)
    assert plan.scheduled == due and plan.name == f"hover-s{int(due.timestamp()) // 60}"
    assert plan.status_patch == {"lastScheduleTime": "2026-03-01T12:05:00Z"}
    # acted on (an operator restarted after this): nothing until the next time comes
    acted = test_body(
        schedule="*/5 * * * *", created="2026-03-01T11:00:00Z", status={**seen, **plan.status_patch}
    )
    assert planned_runs(test_view(acted), acted["spec"], now=NOW, schedule=True) == []
    later = datetime(2026, 3, 1, 12, 10, 1, tzinfo=UTC)
    [nxt] = planned_runs(test_view(acted), acted["spec"], now=later, schedule=True)
    assert nxt.scheduled == datetime(2026, 3, 1, 12, 10, tzinfo=UTC)
    # restarted before the status was written: the same name again (the API server answers 409)
    assert planned_runs(test_view(body), body["spec"], now=NOW, schedule=True)[0].name == plan.name


def test_missed_windows_collapse_into_the_newest_and_none_before_creation() -> None:
    since = datetime(2026, 3, 1, 9, 0, tzinfo=UTC)
    assert due_schedule_time("0 * * * *", since, NOW) == datetime(2026, 3, 1, 12, 0, tzinfo=UTC)
    assert due_schedule_time("0 * * * *", NOW, NOW) is None


def test_an_invalid_schedule_names_the_field() -> None:
    spec = test_body()["spec"]
    with pytest.raises(ValidationError, match="schedule"):
        UavTestSpec.model_validate({**spec, "schedule": "every minute"})


def test_history_keeps_the_newest_finished_runs_per_kind_and_every_running_one() -> None:
    body = test_body(successfulRunsHistoryLimit=2, failedRunsHistoryLimit=1)
    runs = [
        run("hover-g1", "2026-03-01T10:00:00Z", done("Succeeded")),
        run("hover-s1", "2026-03-01T10:05:00Z", done("Failed")),
        run("hover-s2", "2026-03-01T10:10:00Z", done("Succeeded")),
        run("hover-s3", "2026-03-01T10:15:00Z", done("Error")),
        run("hover-s4", "2026-03-01T10:20:00Z", done("Succeeded")),
        run("hover-s5", "2026-03-01T10:25:00Z", {"phase": "Running"}),
    ]
    assert sorted(runs_to_delete(test_view(body), runs)) == ["hover-g1", "hover-s1"]


def test_the_test_summarises_its_runs_and_reads_like_kstatus() -> None:
    body = test_body(status={"observedGeneration": 1, "specHash": "x"})
    runs = [
        run("hover-g1", "2026-03-01T10:00:00Z", done("Succeeded")),
        run("hover-s1", "2026-03-01T10:05:00Z", done("Failed", flaky=True)),
        run("hover-s2", "2026-03-01T10:10:00Z", done("Succeeded", flaky=True)),
    ]
    st = test_status_from(test_view(body), runs, now=NOW)
    assert st.last_run is not None and st.last_run.name == "hover-s2"
    assert (st.runs, st.succeeded, st.failed, st.flaky_runs, st.active) == (3, 2, 1, 2, 0)
    assert st.flaky_rate == pytest.approx(2 / 3)
    assert st.spec_hash == "x" and st.observed_generation == 1  # the scheduler's fields are kept
    conds = {c.type: c.status.value for c in st.conditions}
    assert (conds["Ready"], conds["Reconciling"], conds["Stalled"]) == ("True", "False", "False")
    # a run in progress: Reconciling (kstatus InProgress)
    running = [*runs, run("hover-s3", "2026-03-01T10:15:00Z", {"phase": "Running"})]
    st = test_status_from(test_view(body), running, now=NOW)
    conds = {c.type: c.status.value for c in st.conditions}
    assert (conds["Ready"], conds["Reconciling"], conds["Stalled"]) == ("False", "True", "False")
    assert st.active == 1 and st.flaky_rate == pytest.approx(2 / 3)  # over finished runs only
    # the newest run failed: Stalled (kstatus Failed)
    failed = [*runs, run("hover-s3", "2026-03-01T10:15:00Z", done("Failed"))]
    st = test_status_from(test_view(body), failed, now=NOW)
    conds = {c.type: c.status.value for c in st.conditions}
    assert (conds["Ready"], conds["Reconciling"], conds["Stalled"]) == ("False", "False", "True")
    assert st.phase.value == "Failed"


def test_the_spec_hash_reads_120_and_120_0_as_the_same_spec() -> None:
    """The API server hands back 120.0 as 120: a re-applied unchanged test is not a new spec."""
    assert spec_hash({"timeout": 120.0, "world": {"wind": [1.0, 2.5]}}) == spec_hash(
        {"timeout": 120, "world": {"wind": [1, 2.5]}}
    )
    assert spec_hash({"timeout": 120}) != spec_hash({"timeout": 121})


def test_failed_runs_in_a_row_survive_history_trimming_and_a_pass_resets_them() -> None:
    """The count behind the "failing N runs in a row" alert: kept runs alone cannot give it
    (failedRunsHistoryLimit 1 keeps one failed run), so the status carries it forward."""

    def ended(phase: str, minute: int) -> dict[str, Any]:
        return {**done(phase), "completionTime": f"2026-03-01T11:{minute:02d}:00Z"}

    body = test_body(failedRunsHistoryLimit=1)
    status: dict[str, Any] = {}
    for i, phase in enumerate(["Succeeded", "Failed", "Error", "Failed", "Failed"]):
        # history has trimmed every older failed run: only the newest one and this one are kept
        kept = [run(f"hover-s{i}", f"2026-03-01T10:{i:02d}:00Z", ended(phase, i))]
        body = test_body(failedRunsHistoryLimit=1, status=status)
        st = test_status_from(test_view(body), kept, now=NOW)
        status = st.model_dump(by_alias=True, exclude_none=True, mode="json")
        # the same runs seen again (every reconcile recomputes the status) count nothing twice
        again = test_status_from(test_view(test_body(status=status)), kept, now=NOW)
        assert again.failed_in_a_row == st.failed_in_a_row
    assert st.failed_in_a_row == 3  # Failed, (Error: not judged), Failed, Failed
    passed = [run("hover-s9", "2026-03-01T10:09:00Z", ended("Succeeded", 9))]
    st = test_status_from(test_view(test_body(status=status)), passed, now=NOW)
    assert st.failed_in_a_row == 0
