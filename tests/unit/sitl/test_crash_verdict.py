"""A crash into a box is judged a collision, whatever the noisy estimate says."""

from __future__ import annotations

import io

from pyulog import ULog

from uavtest.analysis.models import Verdict
from uavtest.analysis.ulog import crash_reported, mission_progress_from_ulog, trajectory_from_ulog
from uavtest.analysis.verdict import judge
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mission import from_spec
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig
from uavtest.spec.mission import mission_items
from uavtest.spec.models import UavTestSpec


def _spec(box_x: float) -> UavTestSpec:
    return UavTestSpec.model_validate(
        {
            "mission": {"waypoints": [{"x": 30, "y": 0, "z": -5}], "takeoffAltitude": 5},
            "world": {"obstacles": [{"size": {"l": 4, "w": 10, "h": 20}, "position": {"x": box_x, "y": 0}}]},
        }
    )


def _fly(spec: UavTestSpec) -> ULog:
    sink = MemorySink()
    fly_mission(SimConfig.from_spec(spec, 1), from_spec(mission_items(spec)), sink=sink, limit_s=120)
    return ULog(io.BytesIO(sink.logs[0]))


def test_flying_into_a_box_fails_no_collision():
    spec = _spec(15.0)
    ulog = _fly(spec)
    crash = crash_reported(ulog)
    assert crash is not None and "obstacle 0" in crash
    metrics, assertions, verdict, reason = judge(
        trajectory_from_ulog(ulog), spec, mission=mission_progress_from_ulog(ulog), crash=crash
    )
    assert verdict is Verdict.FAIL
    assert metrics.collision is True
    failed = {a.name for a in assertions if not a.passed}
    assert "noCollision" in failed
    assert "collision" in reason


def test_a_clean_flight_reports_no_crash():
    spec = _spec(-50.0)  # the box is behind home, far from the path
    ulog = _fly(spec)
    assert crash_reported(ulog) is None
    metrics, _, verdict, _ = judge(trajectory_from_ulog(ulog), spec, mission=mission_progress_from_ulog(ulog))
    assert metrics.collision is False
    assert verdict is Verdict.PASS
