"""Where artifacts live in a store: one layout for the local engine and the cluster.

``<namespace>/<test>/<run-id>/replica-<i>/{flight.ulg,trajectory.csv,result.json}`` and
``<namespace>/<test>/<run-id>/aggregate/{summary.json,junit.xml,average.csv,trajectories.png}``.
Local runs use namespace ``local``.
"""

from __future__ import annotations

import re

from uavtest.errors import BadInput

__all__ = [
    "AVERAGE",
    "FLIGHT_LOG",
    "JUNIT",
    "LOCAL_NAMESPACE",
    "PLOT",
    "REPLICA_ARTIFACTS",
    "RESULT",
    "SUMMARY",
    "TRAJECTORY",
    "aggregate_key",
    "replica_key",
    "replica_prefix",
    "run_prefix",
]

LOCAL_NAMESPACE = "local"

FLIGHT_LOG = "flight.ulg"
TRAJECTORY = "trajectory.csv"
RESULT = "result.json"
REPLICA_ARTIFACTS = (FLIGHT_LOG, TRAJECTORY, RESULT)

SUMMARY = "summary.json"
AVERAGE = "average.csv"
PLOT = "trajectories.png"
JUNIT = "junit.xml"  # the run as JUnit XML, for CI systems

_SEGMENT = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


def _segment(field: str, value: str) -> str:
    if not isinstance(value, str) or not _SEGMENT.match(value) or value in {".", ".."}:
        raise BadInput(
            "not usable as a store key segment",
            field=field,
            value=value,
            allowed="letters, digits, '.', '_', '-', starting with a letter or digit; no '/'",
        )
    return value


def run_prefix(namespace: str, test: str, run_id: str) -> str:
    """``<namespace>/<test>/<run-id>/``: everything one run wrote."""
    return f"{_segment('namespace', namespace)}/{_segment('test', test)}/{_segment('run_id', run_id)}/"


def replica_prefix(namespace: str, test: str, run_id: str, index: int) -> str:
    """``<namespace>/<test>/<run-id>/replica-<i>/``."""
    if not isinstance(index, int) or isinstance(index, bool) or index < 0:
        raise BadInput("replica index must be a whole number >= 0", field="index", value=index)
    return f"{run_prefix(namespace, test, run_id)}replica-{index}/"


def replica_key(namespace: str, test: str, run_id: str, index: int, name: str) -> str:
    """``<namespace>/<test>/<run-id>/replica-<i>/<name>``, e.g. name ``result.json``."""
    return replica_prefix(namespace, test, run_id, index) + _segment("name", name)


def aggregate_key(namespace: str, test: str, run_id: str, name: str) -> str:
    """``<namespace>/<test>/<run-id>/aggregate/<name>``, e.g. name ``summary.json``."""
    return f"{run_prefix(namespace, test, run_id)}aggregate/{_segment('name', name)}"
