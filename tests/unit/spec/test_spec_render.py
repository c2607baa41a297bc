"""``uavtest render``: self-contained manifests that load back to the same test."""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from uavtest.analysis.ulog import read_ulog, trajectory_from_ulog
from uavtest.spec.commands import resolved_commands
from uavtest.spec.loaders import load_test, load_test_text
from uavtest.spec.mission import mission_items
from uavtest.spec.render import MAX_REFERENCE_POINTS, render
from uavtest.spec.yaml_io import dump_yaml

FILE_FIELDS = ("planFile", "paramsFile", "commandsFile", "logFile")


def _keys(node: Any) -> set[str]:
    if isinstance(node, dict):
        return set(node) | {k for v in node.values() for k in _keys(v)}
    if isinstance(node, list):
        return {k for v in node for k in _keys(v)}
    return set()


def test_render_round_trip_of_a_native_test(
    write: Callable[..., Path],
    native: Callable[..., dict[str, Any]],
    square_plan: dict[str, Any],
    tmp_path: Path,
) -> None:
    write("f/square.plan", json.dumps(square_plan))
    write("f/p.csv", "MPC_XY_CRUISE, 8\n")
    write("f/c.csv", "timestamp,mode,x,y,z,r\n1000000,3,0,0,0.5,0\n")
    spec = {
        "replicas": 4,
        "seed": 7,
        "mission": {"planFile": "f/square.plan"},
        "vehicle": {"paramsFile": "f/p.csv"},
        "commandsFile": "f/c.csv",
        "world": {"obstacles": [{"size": {"l": 2, "w": 3, "h": 9}, "position": {"x": 20, "y": 1, "r": 15}}]},
    }
    original = load_test(write("t.yaml", native(spec)))
    manifest = render(original, namespace="ci")
    assert not _keys(manifest) & set(FILE_FIELDS)
    assert manifest["metadata"] == {"name": "hover", "namespace": "ci"}
    # written somewhere with none of the files around, it is the same test
    text = dump_yaml(manifest)
    again = load_test(write("elsewhere/rendered.yaml", text))
    assert again.spec == original.spec
    assert mission_items(again.spec) == mission_items(original.spec)
    assert resolved_commands(again.spec) == resolved_commands(original.spec)
    assert again.spec.vehicle.params == {"MPC_XY_CRUISE": 8}
    # rendering is stable
    assert dump_yaml(render(again, namespace="ci")) == text


@pytest.mark.parametrize(
    "relative",
    [
        "competition/snippets/case_studies/mission1.yaml",
        "competition/snippets/case_studies/mission2.yaml",
        "competition/snippets/case_studies/mission3.yaml",
        "aerialist/samples/tests/mission1-k8s.yaml",
    ],
)
def test_render_round_trip_of_upstream_tests(shared_data: Path, relative: str) -> None:
    original = load_test(shared_data / relative)
    manifest = render(original)
    again = load_test_text(dump_yaml(manifest), "rendered.yaml")
    assert again.metadata.name == original.metadata.name
    assert mission_items(again.spec) == mission_items(original.spec)
    assert again.spec.world == original.spec.world
    assert again.spec.vehicle == original.spec.vehicle
    assert again.spec.commands == original.spec.commands
    assert again.spec.replicas == original.spec.replicas


def test_reference_log_is_inlined_as_points(shared_data: Path) -> None:
    test = load_test(shared_data / "aerialist" / "samples" / "tests" / "mission1.yaml")
    similarity = render(test)["spec"]["assertions"]["similarity"]
    assert "logFile" not in similarity
    points = similarity["reference"]["points"]
    flight = trajectory_from_ulog(
        read_ulog(shared_data / "aerialist" / "samples" / "flights" / "mission1.ulg")
    )
    assert 2 <= len(points) <= MAX_REFERENCE_POINTS
    assert all(len(p) == 4 for p in points)
    assert all(a[0] < b[0] for a, b in itertools.pairwise(points))
    # the whole flight, first to last sample
    assert points[0] == pytest.approx([flight.t[0], flight.x[0], flight.y[0], flight.z[0]], abs=1e-3)
    assert points[-1] == pytest.approx([flight.t[-1], flight.x[-1], flight.y[-1], flight.z[-1]], abs=1e-3)
    assert min(p[3] for p in points) == pytest.approx(float(flight.z.min()), abs=0.2)


def test_render_command_prints_yaml_for_kubectl(shared_data: Path, uavtest) -> None:
    path = shared_data / "competition" / "snippets" / "case_studies" / "mission3.yaml"
    result = uavtest("render", path, "--name", "m3-run", "--namespace", "uav")
    assert result.returncode == 0, result.stderr
    doc = yaml.safe_load(result.stdout)
    assert doc["apiVersion"] == "uavtest.io/v1alpha1" and doc["kind"] == "UavTest"
    assert doc["metadata"] == {"name": "m3-run", "namespace": "uav"}
    assert [i["command"] for i in doc["spec"]["mission"]["plan"]["mission"]["items"]] == [22, 16, 16, 21]
    assert doc["spec"]["vehicle"]["params"]["NAV_ACC_RAD"] == 0.5


def test_rendered_yaml_is_safe_for_yaml_1_1_readers(shared_data: Path) -> None:
    # kubectl reads YAML 1.1, where a bare y is a boolean: obstacle positions must keep their "y"
    text = dump_yaml(render(load_test(shared_data / "aerialist" / "samples" / "tests" / "mission1.yaml")))
    assert "'y': 3.0" in text
    assert yaml.safe_load(text)["spec"]["world"]["obstacles"][0]["position"]["y"] == 3.0
