"""Bad input: exit code 2 and a message naming the file, the field, the value and what is allowed.

Every case runs the command line (``uavtest validate``, through ``uavtest.cli.main``) on files
written for it; a few also as a separate process, exactly as a user runs it.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

HOVER = [{"at": 5, "action": "arm"}]


def _native(spec: dict[str, Any], **top: Any) -> dict[str, Any]:
    doc = {"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest", "metadata": {"name": "bad"}, "spec": spec}
    doc.update(top)
    return doc


def _plan(*items: dict[str, Any]) -> str:
    return json.dumps({"fileType": "Plan", "version": 1, "mission": {"version": 2, "items": list(items)}})


TAKEOFF = {"type": "SimpleItem", "command": 22, "frame": 3, "params": [0, 0, 0, None, 47.3977, 8.5456, 10]}
WITH_PLAN = {"mission": {"planFile": "flights/m.plan"}}
WITH_CSV = {"commandsFile": "flights/c.csv"}

# (id, files to write (test.yaml is validated), substrings the message must contain)
CASES: list[tuple[str, dict[str, Any], list[str]]] = [
    (
        "negative-obstacle-size",
        {
            "test.yaml": _native(
                {
                    "commands": HOVER,
                    "world": {
                        "obstacles": [{"size": {"l": -5, "w": 2, "h": 3}, "position": {"x": 1, "y": 2}}]
                    },
                }
            )
        },
        ["field 'spec.world.obstacles[0].size.l'", "(got -5)", "allowed: a number > 0"],
    ),
    (
        "unknown-flight-mode",
        {"test.yaml": _native({"commands": [{"at": 1, "action": "mode", "mode": "acrobatic"}]})},
        ["field 'spec.commands[0].mode'", "(got 'acrobatic')", "allowed:", "'position'", "'offboard'"],
    ),
    (
        "bad-api-version",
        {"test.yaml": _native({"commands": HOVER}, apiVersion="uavtest.io/v1")},
        ["field 'apiVersion'", "(got 'uavtest.io/v1')", "allowed: uavtest.io/v1alpha1"],
    ),
    (
        "wrong-kind",
        {"test.yaml": _native({"commands": HOVER}, kind="Job")},
        ["field 'kind'", "(got 'Job')", "allowed: UavTest"],
    ),
    (
        "unknown-field",
        {"test.yaml": _native({"commands": HOVER, "replica": 3})},
        ["field 'spec.replica'", "unknown field 'replica'", "allowed: replicas, parallelism, seed"],
    ),
    (
        "unknown-nested-field",
        {"test.yaml": _native({"commands": HOVER, "world": {"wind": {"speed": 3}}})},
        ["field 'spec.world.wind.speed'", "allowed: meanSpeed, maxSpeed, direction, gusts"],
    ),
    (
        "no-mission-no-commands",
        {"test.yaml": _native({"replicas": 3})},
        ["field 'spec'", "a test needs a mission or commands"],
    ),
    (
        "wrong-type",
        {"test.yaml": _native({"commands": HOVER, "replicas": "three"})},
        ["field 'spec.replicas'", "(got 'three')", "allowed: an integer"],
    ),
    (
        "replicas-out-of-range",
        {"test.yaml": _native({"commands": HOVER, "replicas": 0})},
        ["field 'spec.replicas'", "(got 0)", "allowed: a number >= 1 and <= 1000"],
    ),
    (
        "sticks-out-of-range-inline",
        {"test.yaml": _native({"commands": [{"at": 1, "action": "sticks", "sticks": {"x": 1.5}}]})},
        ["field 'spec.commands[0].sticks.x'", "(got 1.5)", "allowed: a number >= -1 and <= 1"],
    ),
    (
        "wind-max-below-mean",
        {"test.yaml": _native({"commands": HOVER, "world": {"wind": {"meanSpeed": 5, "maxSpeed": 2}}})},
        ["field 'spec.world.wind'", "maxSpeed 2.0 is below meanSpeed 5.0"],
    ),
    (
        "bad-metadata-name",
        {"test.yaml": _native({"commands": HOVER}, metadata={"name": "My_Test"})},
        ["field 'metadata.name'", "(got 'My_Test')", "DNS-1123"],
    ),
    (
        "yaml-syntax-error",
        {"test.yaml": "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nspec:\n  commands: [\n    {at: 1\n"},
        ["YAML syntax error at line", "column"],
    ),
    (
        "duplicate-key",
        {"test.yaml": "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nkind: UavTest\nspec: {}\n"},
        ["line 3, column 1", "key 'kind' is given twice"],
    ),
    ("empty-file", {"test.yaml": "# nothing here\n"}, ["the file is empty", "allowed: a UavTest"]),
    ("not-a-mapping", {"test.yaml": "- 1\n- 2\n"}, ["a test file must be a mapping", "(got 'list')"]),
    (
        "missing-plan-file",
        {"test.yaml": _native(WITH_PLAN)},
        ["field 'spec.mission.planFile'", "file not found: flights/m.plan"],
    ),
    (
        "unsupported-plan-command",
        {
            "test.yaml": _native(WITH_PLAN),
            "flights/m.plan": _plan(TAKEOFF, {"type": "SimpleItem", "command": 84, "frame": 3, "params": []}),
        },
        [
            "m.plan",
            "field 'mission.items[1].command'",
            "command 84 is not supported",
            "(got 84)",
            "22 takeoff",
        ],
    ),
    (
        "complex-plan-item",
        {
            "test.yaml": _native(WITH_PLAN),
            "flights/m.plan": _plan(TAKEOFF, {"type": "ComplexItem", "complexItemType": "survey"}),
        },
        [
            "field 'mission.items[1].complexItemType'",
            "complex item 'survey' is not supported",
            "simple items",
        ],
    ),
    (
        "plan-not-json",
        {"test.yaml": _native(WITH_PLAN), "flights/m.plan": '{"fileType": "Plan",\n  "mission": }'},
        ["m.plan", "not valid JSON at line 2, column"],
    ),
    (
        "csv-mode-code-acro",
        {
            "test.yaml": _native(WITH_CSV),
            "flights/c.csv": "timestamp,mode,x,y,z,r\n1000,2,0,0,0.5,0\n2000,6,0,0,0.5,0\n",
        },
        [
            "c.csv",
            "row 3: mode code 6 (acro) is not supported",
            "(got '6')",
            "allowed: 0 manual",
            "100 sticks",
        ],
    ),
    (
        "csv-unknown-mode-code",
        {"test.yaml": _native(WITH_CSV), "flights/c.csv": "timestamp,mode,x,y,z,r\n1000,42,0,0,0.5,0\n"},
        ["row 2: unknown mode code 42", "allowed: 0 manual"],
    ),
    (
        "csv-sticks-out-of-range",
        {"test.yaml": _native(WITH_CSV), "flights/c.csv": "mode,timestamp,x,y,z,r\n100,1000,0,0,1.2,0\n"},
        ["c.csv", "row 2: stick z out of range", "(got '1.2')", "allowed: 0 to 1"],
    ),
    (
        "csv-missing-column",
        {"test.yaml": _native(WITH_CSV), "flights/c.csv": "timestamp,mode,x,y,z\n1000,3,0,0,0.5\n"},
        ["header: missing column(s) r", "allowed: a header naming timestamp, mode, x, y, z, r"],
    ),
    (
        "params-not-a-number",
        {
            "test.yaml": _native({"commands": HOVER, "vehicle": {"paramsFile": "p.csv"}}),
            "p.csv": "NAV_ACC_RAD, 0.5\nMPC_XY_CRUISE, fast\n",
        },
        ["p.csv", "line 2: value is not a number", "(got 'fast')", "allowed: a number"],
    ),
    (
        "aerialist-obstacle-flat-list",
        {
            "test.yaml": {
                "simulation": {"obstacles": [5, 5, 5, 1, 2, 0]},
                "mission": {"commands": [{"timestamp": 0, "mode": 3}]},
            }
        },
        ["field 'simulation.obstacles'", "7 numbers per box, found 6", "l, w, h, x, y, z, r"],
    ),
    (
        "aerialist-negative-obstacle",
        {
            "test.yaml": {
                "simulation": {
                    "obstacles": [
                        {"size": {"l": 5, "w": -1, "h": 5}, "position": {"x": 0, "y": 0, "z": 0, "r": 0}}
                    ]
                },
                "mission": {"commands": [{"timestamp": 0, "mode": 3}]},
            }
        },
        ["field 'simulation.obstacles[0].size.w'", "(got -1)", "allowed: a number > 0"],
    ),
    (
        "aerialist-nothing-to-fly",
        {"test.yaml": {"drone": {"port": "ros"}, "simulation": {"simulator": "ros"}}},
        ["field 'mission'", "a test needs a mission or commands", "allowed: drone.mission_file"],
    ),
    (
        "aerialist-unknown-section",
        {"test.yaml": {"drone": {}, "simulaton": {}}},
        ["field 'simulaton'", "unknown section", "allowed: robot, simulation, mission"],
    ),
]


@pytest.mark.parametrize(("files", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_exits_2_naming_field_value_and_allowed(
    write: Callable[..., Path], uavtest, files: dict[str, Any], expected: list[str]
) -> None:
    paths = [write(name, content) for name, content in files.items()]
    test_file = paths[0]
    result = uavtest("validate", test_file)
    assert result.returncode == 2, (result.stdout, result.stderr)
    message = " ".join(result.stderr.split())  # rich may wrap long lines
    assert message.startswith("error: ")
    assert "Traceback" not in result.stderr
    for part in expected:
        assert part in message, f"{part!r} not in {message!r}"
    named = {str(p) for p in paths}
    assert any(n in message for n in named), "the message names the file at fault"


@pytest.mark.parametrize("case", ["negative-obstacle-size", "csv-mode-code-acro", "yaml-syntax-error"])
def test_bad_input_in_a_real_process(write: Callable[..., Path], cli, case: str) -> None:
    files, expected = next(c[1:] for c in CASES if c[0] == case)
    paths = [write(name, content) for name, content in files.items()]
    result = cli("validate", paths[0])
    assert result.returncode == 2
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    assert expected[0] in " ".join(result.stderr.split())
