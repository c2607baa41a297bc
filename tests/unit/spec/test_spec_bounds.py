"""No silent pass: NaN, infinity, values outside their physical range, ill-formed boxes and
documents too deep or too large are bad input (exit 2, file, field, value, what is allowed),
for ``uavtest validate`` and ``uavtest run`` alike, before anything flies.

Plain regression tests for the inputs that once got through, then a property-based test that
breaks valid tests (the examples and one test using every section) at a random place.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import uavtest.spec.cli_support  # noqa: F401  (bound to the real load_test before any patching)
import uavtest.spec.loaders as loaders
from uavtest.spec.models import UavTest
from uavtest.spec.validation import _field_model
from uavtest.spec.yaml_io import dump_yaml

REPO = Path(__file__).resolve().parents[3]
HOVER = [{"at": 5, "action": "arm"}]


class WouldFly(Exception):
    """Raised instead of flying when ``uavtest run`` accepted a test the case says is bad."""


@pytest.fixture
def guarded_uavtest(uavtest, monkeypatch: pytest.MonkeyPatch) -> Callable[..., Any]:
    """``uavtest`` in-process, where a test file that loads fine stops ``run`` before it flies.

    The local engine imports ``load_test`` when it runs, so it sees the guard; ``validate``
    (imported above) keeps the real one.
    """
    real = loaders.load_test

    def load_or_stop(path: Path) -> UavTest:
        real(path)
        raise WouldFly(f"{path} was accepted")

    monkeypatch.setattr(loaders, "load_test", load_or_stop)
    return uavtest


def _native(spec: dict[str, Any]) -> dict[str, Any]:
    return {"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest", "metadata": {"name": "bad"}, "spec": spec}


def _check(result: Any, *expected: str) -> None:
    assert result.returncode == 2, (result.stdout, result.stderr)
    message = " ".join(result.stderr.split())
    assert message.startswith("error: "), message
    assert "Traceback" not in result.stderr
    for part in expected:
        assert part in message, f"{part!r} not in {message!r}"


DEEP_YAML = "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nspec: " + "[" * 5000 + "]" * 5000 + "\n"

# (id, files (the first is the test), parts of the message)
REGRESSIONS: list[tuple[str, dict[str, Any], list[str]]] = [
    (
        "waypoint-x-inf",
        {
            "t.yaml": "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: t}\nspec:\n"
            "  mission: {waypoints: [{x: .inf, 'y': 0, z: -5}]}\n"
        },
        [
            "field 'spec.mission.waypoints[0].x'",
            "not a finite number",
            "(got inf)",
            "allowed: a number >= -100000 and <= 100000",
        ],
    ),
    (
        "waypoint-x-nan",
        {
            "t.yaml": "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: t}\nspec:\n"
            "  mission: {waypoints: [{x: .nan, 'y': 0, z: -5}]}\n"
        },
        ["field 'spec.mission.waypoints[0].x'", "not a finite number", "(got nan)"],
    ),
    (
        "param-nan",
        {
            "t.yaml": "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: t}\nspec:\n"
            "  commands: [{at: 1, action: arm}]\n  vehicle: {params: {MPC_XY_CRUISE: .nan}}\n"
        },
        [
            "field 'spec.vehicle.params.MPC_XY_CRUISE'",
            "not a finite number",
            "(got nan)",
            "PX4 INT32",
            "PX4 FLOAT",
        ],
    ),
    (
        "wind-1e9",
        {"t.yaml": _native({"commands": HOVER, "world": {"wind": {"meanSpeed": 1e9}}})},
        [
            "field 'spec.world.wind.meanSpeed'",
            "value out of range",
            "(got 1000000000.0)",
            "allowed: a number >= 0 and <= 50",
        ],
    ),
    (
        "geofence-min-above-max",
        {"t.yaml": _native({"commands": HOVER, "assertions": {"geofence": {"minX": 10, "maxX": -10}}})},
        ["field 'spec.assertions.geofence'", "minX 10 is not below maxX -10"],
    ),
    (
        "deeply-nested-yaml",
        {"t.yaml": DEEP_YAML},
        ["t.yaml: the document is nested too deeply (at line 3", "allowed: at most 64 levels"],
    ),
    # the same kinds of numbers in the other formats
    (
        "plan-nan-literal",
        {
            "t.yaml": _native({"mission": {"planFile": "m.plan"}}),
            "m.plan": '{"fileType": "Plan", "mission": {"items": [{"command": 22, "params": [NaN]}]}}',
        },
        ["m.plan: NaN is not a JSON number", "allowed: finite numbers"],
    ),
    (
        "plan-infinity-literal",
        {
            "t.yaml": _native({"mission": {"planFile": "m.plan"}}),
            "m.plan": '{"fileType": "Plan", "mission": {"plannedHomePosition": [47, 8, -Infinity]}}',
        },
        ["m.plan: -Infinity is not a JSON number"],
    ),
    (
        "plan-deep",
        {"t.yaml": _native({"mission": {"planFile": "m.plan"}}), "m.plan": "[" * 100_000 + "]" * 100_000},
        ["m.plan: the plan is nested too deeply", "allowed: at most 64 levels"],
    ),
    (
        "plan-altitude-huge",
        {
            "t.yaml": _native({"mission": {"planFile": "m.plan"}}),
            "m.plan": json.dumps(
                {
                    "fileType": "Plan",
                    "mission": {
                        "items": [
                            {
                                "type": "SimpleItem",
                                "command": 22,
                                "frame": 3,
                                "params": [0, 0, 0, None, 47.4, 8.5, 1e9],
                            }
                        ]
                    },
                }
            ),
        },
        ["m.plan", "field 'mission.items[0].params[6]'", "altitude out of range", "<= 10000"],
    ),
    (
        "plan-home-altitude-huge",
        {
            "t.yaml": _native({"mission": {"planFile": "m.plan"}}),
            "m.plan": json.dumps(
                {"fileType": "Plan", "mission": {"plannedHomePosition": [47, 8, 1e7], "items": []}}
            ),
        },
        ["field 'mission.plannedHomePosition'", "home position out of range", "alt -500..10000"],
    ),
    (
        "params-csv-out-of-range",
        {"t.yaml": _native({"commands": HOVER, "vehicle": {"paramsFile": "p.csv"}}), "p.csv": "A_B, 1e39\n"},
        ["p.csv: line 1: value out of range", "(got '1e39')", "PX4 FLOAT"],
    ),
    (
        "params-csv-inf",
        {"t.yaml": _native({"commands": HOVER, "vehicle": {"paramsFile": "p.csv"}}), "p.csv": "A_B, inf\n"},
        ["p.csv: line 1: value is not finite", "(got 'inf')"],
    ),
    (
        "commands-csv-timestamp-huge",
        {"t.yaml": _native({"commandsFile": "c.csv"}), "c.csv": "timestamp,mode,x,y,z,r\n1e20,3,0,0,0,0\n"},
        ["c.csv: row 2: timestamp out of range", "(got '1e20')", "<= 86400000000"],
    ),
    (
        "commands-csv-timestamp-nan",
        {"t.yaml": _native({"commandsFile": "c.csv"}), "c.csv": "timestamp,mode,x,y,z,r\nnan,3,0,0,0,0\n"},
        ["c.csv: row 2, timestamp is not finite", "(got 'nan')"],
    ),
    (
        "aerialist-waypoint-inf",
        {"t.yaml": "mission:\n  waypoints: [{x: .inf, y: 0, z: 5}]\n"},
        ["field 'mission.waypoints[0]'", "a waypoint needs numbers x and y"],
    ),
    (
        "aerialist-waypoint-far",
        {"t.yaml": "mission:\n  waypoints: [{x: 1.0e+7, y: 0, z: 5}]\n"},
        ["field 'mission.waypoints[0].x'", "waypoint out of range", "<= 100000"],
    ),
    (
        "aerialist-param-nan",
        {"t.yaml": "robot:\n  params: {MPC_XY_CRUISE: .nan}\nmission:\n  waypoints: [{x: 1, y: 0, z: 5}]\n"},
        ["field 'robot.params.MPC_XY_CRUISE'", "PX4 FLOAT"],
    ),
    (
        "aerialist-timeout-huge",
        {"t.yaml": "simulation:\n  timeout: 1.0e+12\nmission:\n  waypoints: [{x: 1, y: 0, z: 5}]\n"},
        ["field 'simulation.timeout'", "<= 86400"],
    ),
    (
        "aerialist-wind-huge",
        {
            "t.yaml": "simulation:\n  wind: {velocity_mean: 1.0e+9}\n"
            "mission:\n  waypoints: [{x: 1, y: 0, z: 5}]\n"
        },
        ["field 'simulation.wind.meanSpeed'", "<= 50"],
    ),
    (
        "aerialist-speed-factor",
        {"t.yaml": "simulation:\n  speed: .inf\nmission:\n  waypoints: [{x: 1, y: 0, z: 5}]\n"},
        ["field 'simulation.speed'", "<= 1000"],
    ),
    (
        "yaml-alias-bomb",
        {
            "t.yaml": "a: &a [1,1,1,1,1,1,1,1,1,1]\n"
            + "".join(
                f"a{i}: &a{i} [{','.join([f'*a{i - 1}' if i > 1 else '*a'] * 10)}]\n" for i in range(1, 9)
            )
        },
        ["t.yaml: the document is too large once its aliases", "allowed: at most 1000000 values"],
    ),
]


def _write(tmp_path: Path, files: dict[str, Any]) -> Path:
    paths = []
    for name, content in files.items():
        path = tmp_path / name
        path.write_text(dump_yaml(content) if isinstance(content, dict) else content)
        paths.append(path)
    return paths[0]


@pytest.mark.parametrize("command", ["validate", "run"])
@pytest.mark.parametrize(("files", "expected"), [c[1:] for c in REGRESSIONS], ids=[c[0] for c in REGRESSIONS])
def test_once_accepted_input_is_now_bad_input(
    guarded_uavtest, tmp_path: Path, command: str, files: dict[str, Any], expected: list[str]
) -> None:
    test_file = _write(tmp_path, files)
    args = ["--out", str(tmp_path / "runs")] if command == "run" else []
    _check(guarded_uavtest(command, test_file, *args), *expected)
    assert not (tmp_path / "runs").exists(), "nothing was flown"


def test_a_file_too_large_is_refused_before_reading(guarded_uavtest, tmp_path: Path) -> None:
    test_file = tmp_path / "big.yaml"
    test_file.write_text("# padding\n" * 500_000)
    _check(guarded_uavtest("validate", test_file), "big.yaml: the file is too large", "at most 4 MiB")


def test_the_limits_leave_real_files_alone(uavtest) -> None:
    for example in sorted((REPO / "examples").glob("*.yaml")):
        result = uavtest("validate", example)
        assert result.returncode == 0, result.stderr


# --------------------------------------------------------------------------- property-based

#: one test using every section, so every model is broken somewhere
FULL: dict[str, Any] = _native(
    {
        "replicas": 2,
        "parallelism": 2,
        "seed": 3,
        "timeout": 120,
        "vehicle": {"simulator": "builtin", "params": {"MPC_XY_CRUISE": 5.0, "COM_RCL_EXCEPT": 4}},
        "world": {
            "home": {"lat": 47.397742, "lon": 8.545594, "alt": 488.0},
            "obstacles": [
                {"size": {"l": 4, "w": 4, "h": 15}, "position": {"x": 20, "y": 5, "z": 0, "r": 30}}
            ],
            "wind": {"meanSpeed": 2.0, "maxSpeed": 4.0, "direction": 90, "gusts": True},
        },
        "mission": {
            "waypoints": [{"x": 0, "y": 0, "z": -10, "hold": 1}, {"x": 40, "y": 0, "z": -10}],
            "takeoffAltitude": 10,
            "takeoffSpeed": 2,
            "land": True,
        },
        "commands": [
            {"at": 1, "action": "mode", "mode": "mission"},
            {"at": 30, "action": "sticks", "sticks": {"x": 0.1, "y": -0.1, "z": 0.5, "r": 0}},
            {"at": 40, "action": "speed", "speed": 3},
        ],
        "assertions": {
            "minObstacleDistance": 1.5,
            "maxFlightTime": 100,
            "geofence": {"minX": -50, "maxX": 50, "minY": -50, "maxY": 50, "minZ": -30, "maxZ": 5},
            "similarity": {
                "metric": "dtw",
                "threshold": 2,
                "reference": {"points": [[0, 0, 0, 0], [1, 1, 0, -1]]},
            },
        },
    }
)


def _bases() -> list[dict[str, Any]]:
    docs = [yaml.safe_load((p).read_text()) for p in sorted((REPO / "examples").glob("*.yaml"))]
    return [FULL, *docs]


BASES = _bases()
Path_ = tuple[int | str, ...]


def _leaves(node: Any, path: Path_ = ()) -> Iterator[tuple[Path_, Any]]:
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, (*path, i))
    else:
        yield path, node


def _keys(node: Any, path: Path_ = ()) -> Iterator[Path_]:
    if isinstance(node, dict):
        for k, v in node.items():
            yield (*path, k)
            yield from _keys(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _keys(v, (*path, i))


def _display(path: Path_) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path).lstrip(".")


def _set(doc: dict[str, Any], path: Path_, value: Any) -> None:
    node: Any = doc
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value


def _required(path: Path_) -> bool:
    """True when the model (or the loader, for apiVersion / kind / spec) needs the key at ``path``."""
    if path in (("apiVersion",), ("kind",), ("spec",)):
        return True
    if path[0] != "spec" or not isinstance(path[-1], str):
        return False
    owner = _field_model(UavTest, path[:-1])
    info = (
        next((f for n, f in owner.model_fields.items() if f.alias == path[-1] or n == path[-1]), None)
        if owner
        else None
    )
    return info is not None and info.is_required()


NOT_NUMBERS = [math.nan, math.inf, -math.inf, 1e39, -1e39]


@st.composite
def broken_tests(draw: st.DrawFn) -> tuple[dict[str, Any] | str, str]:
    """(a test made bad in one place, the text its message must contain)."""
    doc = copy.deepcopy(draw(st.sampled_from(BASES)))
    how = draw(st.sampled_from(["number", "number", "delete", "swap", "nest"]))
    if how == "number":
        numbers = [(p, v) for p, v in _leaves(doc) if isinstance(v, int | float) and not isinstance(v, bool)]
        path, _ = draw(st.sampled_from(numbers))
        _set(doc, path, draw(st.sampled_from(NOT_NUMBERS)))
        return doc, f"field '{_display(path)}'"
    if how == "delete":
        path = draw(st.sampled_from([p for p in _keys(doc) if _required(p)]))
        node: Any = doc
        for p in path[:-1]:
            node = node[p]
        del node[path[-1]]
        return doc, f"field '{_display(path)}'"
    leaves = [p for p, _ in _leaves(doc) if p[0] != "metadata" or p == ("metadata", "name")]
    path = draw(st.sampled_from(leaves))
    if how == "swap":
        _set(doc, path, draw(st.sampled_from([[1, 2], {"a": 1}, [None]])))
        return doc, f"field '{_display(path)}'"
    depth = draw(st.integers(min_value=65, max_value=400))
    nested: Any = 1
    for _ in range(depth):
        nested = [nested] if draw(st.booleans()) else {"a": nested}
    _set(doc, path, nested)
    return yaml.safe_dump(doc, sort_keys=False), "nested too deeply"


@pytest.mark.parametrize("command", ["validate", "run"])
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(case=broken_tests())
def test_broken_tests_are_bad_input_naming_the_field(
    guarded_uavtest, tmp_path: Path, command: str, case: tuple[dict[str, Any] | str, str]
) -> None:
    content, expected = case
    test_file = tmp_path / "broken.yaml"
    test_file.write_text(content if isinstance(content, str) else dump_yaml(content))
    args = ["--out", str(tmp_path / "runs")] if command == "run" else []
    result = guarded_uavtest(command, test_file, *args)
    _check(result, str(test_file), expected)
