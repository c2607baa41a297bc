"""Stage 8: the three artifacts under the layout; nothing lost silently."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.analysis.trajectory import Trajectory
from uavtest.runner.artifacts import ReplicaPlace, store_artifacts
from uavtest.store import LocalStore

PLACE = ReplicaPlace("local", "hover", "run-1", 2)
TRAJ = Trajectory(
    np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.zeros(2), np.array([-1.0, -2.0]), np.zeros(2)
)


def result(verdict: Verdict = Verdict.PASS, reason: str = "") -> ReplicaResult:
    return ReplicaResult(index=2, seed=9, verdict=verdict, reason=reason)


def test_all_three_artifacts_land_under_the_layout(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    stored, ok = store_artifacts(store, PLACE, result(), log_bytes=b"ULog...", trajectory=TRAJ)
    assert ok and stored.verdict is Verdict.PASS
    assert store.list("local/hover/run-1/") == [
        "local/hover/run-1/replica-2/flight.ulg",
        "local/hover/run-1/replica-2/result.json",
        "local/hover/run-1/replica-2/trajectory.csv",
    ]
    assert Trajectory.from_csv(store.get(PLACE.key("trajectory.csv")).decode()).x.tolist() == [0.0, 1.0]
    assert ReplicaResult.model_validate_json(store.get(PLACE.key("result.json"))) == stored


def test_an_error_without_a_log_still_stores_result_json(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    _, ok = store_artifacts(
        store, PLACE, result(Verdict.ERROR, "no heartbeat"), log_bytes=None, trajectory=None
    )
    assert ok and store.list() == ["local/hover/run-1/replica-2/result.json"]
    assert json.loads(store.get(PLACE.key("result.json")))["reason"] == "no heartbeat"


def test_a_log_the_store_refuses_makes_the_replica_an_error_saying_so(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    (tmp_path / "local/hover/run-1/replica-2/flight.ulg").mkdir(parents=True)  # a directory in the way
    stored, ok = store_artifacts(
        store, PLACE, result(Verdict.FAIL, "collision"), log_bytes=b"ULog", trajectory=TRAJ
    )
    assert ok and stored.verdict is Verdict.ERROR
    assert stored.reason.startswith("store upload failed: flight.ulg")
    assert "judged fail: collision" in stored.reason
    assert ReplicaResult.model_validate_json(store.get(PLACE.key("result.json"))).verdict is Verdict.ERROR
