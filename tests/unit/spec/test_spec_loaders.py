"""Loading native and Aerialist files: references, parent folders, homes, obstacles, wind."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from uavtest.errors import BadInput, MissingFile
from uavtest.spec.aerialist import AERIALIST_SIMILARITY_THRESHOLD, dns_name
from uavtest.spec.commands import resolved_commands
from uavtest.spec.loaders import load_test, load_test_text
from uavtest.spec.mission import mission_items
from uavtest.spec.models import CommandAction, FlightMode, MissionItemKind

CSV = "timestamp,mode,x,y,z,r\n2000000,20,0,0,0.5,0\n1000000,2,0,0,0.5,0\n3000000,100,0.5,-0.25,0.75,1\n"


def test_native_references_are_inlined_relative_to_the_test_file(
    write: Callable[..., Path], native: Callable[..., dict[str, Any]], square_plan: dict[str, Any]
) -> None:
    write("flights/square.plan", json.dumps(square_plan))
    write("flights/p.csv", "MPC_XY_CRUISE, 8\nNAV_ACC_RAD, 0.5\n")
    write("flights/c.csv", CSV)
    spec = {
        "mission": {"planFile": "../flights/square.plan"},
        "vehicle": {"paramsFile": "../flights/p.csv", "params": {"NAV_ACC_RAD": 1.5}},
        "commandsFile": "../flights/c.csv",
        "commands": [{"at": 0.5, "action": "mode", "mode": "hold"}],
    }
    test = load_test(write("tests/t.yaml", native(spec)))
    s = test.spec
    assert s.mission is not None and s.mission.plan_file is None and s.mission.plan == square_plan
    assert s.vehicle.params_file is None and s.commands_file is None
    assert s.vehicle.params == {"MPC_XY_CRUISE": 8, "NAV_ACC_RAD": 1.5}  # inline wins over the file
    assert isinstance(s.vehicle.params["MPC_XY_CRUISE"], int)
    assert [(c.at, c.action) for c in s.commands] == [
        (0.5, CommandAction.MODE),
        (1.0, CommandAction.MODE),
        (2.0, CommandAction.ARM),
        (3.0, CommandAction.STICKS),
    ]
    sticks = s.commands[3].sticks
    assert sticks is not None and (sticks.x, sticks.y, sticks.z, sticks.r) == (0.5, -0.25, 0.75, 1.0)
    assert resolved_commands(s) == s.commands
    # the plan's home becomes world.home when the test gives none
    assert (s.world.home.lat, s.world.home.lon, s.world.home.alt) == (47.3977419, 8.5455938, 488.0)


def test_references_are_found_in_parent_folders(
    write: Callable[..., Path], native: Callable[..., dict[str, Any]], tmp_path: Path
) -> None:
    write("repo/samples/flights/c.csv", CSV)
    test_file = write("repo/samples/tests/deep/t.yaml", native({"commandsFile": "samples/flights/c.csv"}))
    assert len(load_test(test_file).spec.commands) == 3
    with pytest.raises(MissingFile) as e:
        load_test(write("elsewhere/t.yaml", native({"commandsFile": "samples/flights/c.csv"})))
    assert e.value.path == "samples/flights/c.csv"
    assert str(tmp_path / "elsewhere" / "t.yaml") in str(e.value)


def test_an_explicit_home_wins_over_the_plan(
    write: Callable[..., Path], native: Callable[..., dict[str, Any]], square_plan: dict[str, Any]
) -> None:
    home = {"lat": 46.0, "lon": 7.0, "alt": 500.0}
    spec = {"mission": {"plan": square_plan}, "world": {"home": home}}
    test = load_test(write("t.yaml", native(spec)))
    assert test.spec.world.home.dump() == home


def test_metadata_name_defaults_to_the_file_name(write: Callable[..., Path]) -> None:
    doc = {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "spec": {"commands": [{"at": 1, "action": "arm"}]},
    }
    assert load_test(write("My_Hover Test.yaml", doc)).metadata.name == "my-hover-test"


@pytest.mark.parametrize(
    ("stem", "name"),
    [
        ("mission1-k8s", "mission1-k8s"),
        ("Mission_2", "mission-2"),
        ("__x__", "x"),
        ("---", "test"),
        ("a" * 80, "a" * 63),
    ],
)
def test_dns_names(stem: str, name: str) -> None:
    assert dns_name(stem) == name


def test_load_test_text_without_a_file_needs_a_name() -> None:
    text = "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nspec:\n  commands: [{at: 1, action: arm}]\n"
    with pytest.raises(BadInput, match="metadata"):
        load_test_text(text, "stdin")
    test = load_test_text(text.replace("spec:", "metadata: {name: from-text}\nspec:"), "stdin")
    assert test.metadata.name == "from-text"


def test_a_manifest_with_status_loads(
    write: Callable[..., Path], native: Callable[..., dict[str, Any]]
) -> None:
    doc = native({"commands": [{"at": 1, "action": "arm"}]})
    doc["status"] = {"phase": "Succeeded"}
    assert load_test(write("t.yaml", doc)).spec.commands[0].action == CommandAction.ARM


# --------------------------------------------------------------------------- Aerialist


def test_old_and_new_aerialist_keys_give_the_same_test(write: Callable[..., Path]) -> None:
    write("samples/flights/c.csv", CSV)
    write("samples/flights/p.csv", "NAV_ACC_RAD, 1\n")
    new = {
        "robot": {"params_file": "samples/flights/p.csv"},
        "mission": {"commands_file": "samples/flights/c.csv"},
    }
    old = {"drone": new["robot"], "test": new["mission"]}
    a = load_test(write("samples/tests/new.yaml", new))
    b = load_test(write("samples/tests/old.yaml", old))
    assert a.spec == b.spec
    assert a.spec.vehicle.params == {"NAV_ACC_RAD": 1}


def test_aerialist_flat_obstacles_home_wind_and_agent(
    write: Callable[..., Path], caplog: pytest.LogCaptureFixture
) -> None:
    doc = {
        "drone": {"port": "sitl", "params": {"MPC_XY_CRUISE": 5}},
        "simulation": {
            "simulator": "gazebo",
            "speed": 2,
            "headless": True,
            "obstacles": [10, 5, 20, 10, 20, 0, 0, 10, 5, 20, -10, 20, 0, 45],
            "home_position": [47.5, 8.7, 440.0],
            "wind": {"velocity_mean": 3.0, "velocity_max": 5.0, "direction": [1, 0, 0]},
            "timeout": 300,
        },
        "test": {"commands": [{"timestamp": 1000, "mode": 3, "x": 0, "y": 0, "z": 0.5, "r": 0}]},
        "agent": {"engine": "k8s", "count": 7, "path": "/tmp", "id": "x"},
    }
    with caplog.at_level("INFO"):
        spec = load_test(write("flat.yaml", doc)).spec
    assert spec.replicas == 7 and spec.timeout == 300.0
    assert spec.vehicle.params == {"MPC_XY_CRUISE": 5}
    assert spec.vehicle.simulator.value == "builtin"
    assert any("gazebo" in r.getMessage() and "built-in" in r.getMessage() for r in caplog.records)
    a, b = spec.world.obstacles
    assert (a.size.l, a.size.w, a.size.h, a.position.x, a.position.y, a.position.z, a.position.r) == (
        10,
        5,
        20,
        10,
        20,
        0,
        0,
    )
    assert (b.position.x, b.position.r) == (-10, 45)
    assert spec.world.home.dump() == {"lat": 47.5, "lon": 8.7, "alt": 440.0}
    # Gazebo's wind direction is an ENU vector: [1, 0, 0] blows towards the East = 90° from North
    assert spec.world.wind.mean_speed == 3.0 and spec.world.wind.max_speed == 5.0
    assert spec.world.wind.direction == pytest.approx(90.0) and spec.world.wind.gusts
    assert spec.commands[0].at == pytest.approx(0.001) and spec.commands[0].mode == FlightMode.MISSION
    assert spec.mission is None


def test_aerialist_obstacle_objects_with_angle(write: Callable[..., Path]) -> None:
    doc = {
        "simulation": {
            "obstacles": [
                {
                    "size": {"l": 4, "w": 2, "h": 6},
                    "position": {"x": 1, "y": 2, "z": 0, "angle": 30},
                    "shape": "BOX",
                }
            ]
        },
        "mission": {"commands": [{"timestamp": 0, "mode": 3}]},
    }
    [o] = load_test(write("obj.yaml", doc)).spec.world.obstacles
    assert o.position.r == 30 and o.size.h == 6


def test_aerialist_waypoints_are_up_positive(write: Callable[..., Path]) -> None:
    doc = {"mission": {"waypoints": [{"x": 10, "y": 5, "z": 8, "r": 0}]}}
    spec = load_test(write("wp.yaml", doc)).spec
    assert spec.mission is not None and spec.mission.waypoints is not None
    assert spec.mission.waypoints[0].z == -8


def test_aerialist_log_file_becomes_a_similarity_assertion(write: Callable[..., Path]) -> None:
    log = write("samples/flights/ref.ulg", "not parsed when loading")
    doc = {
        "mission": {"commands": [{"timestamp": 0, "mode": 3}]},
        "assertion": {"log_file": "samples/flights/ref.ulg"},
    }
    similarity = load_test(write("samples/tests/s.yaml", doc)).spec.assertions.similarity
    assert similarity is not None
    assert similarity.log_file == str(log)
    assert similarity.metric.value == "dtw" and similarity.threshold == AERIALIST_SIMILARITY_THRESHOLD


def test_a_ulog_commands_file_is_refused_when_present(write: Callable[..., Path]) -> None:
    write("flights/manual.ulg", "ULog")
    with pytest.raises(BadInput, match="commands from a flight log are not supported"):
        load_test(write("m.yaml", {"mission": {"commands_file": "flights/manual.ulg"}}))


def test_plan_without_takeoff_gets_one(
    write: Callable[..., Path], native: Callable[..., dict[str, Any]], square_plan: dict[str, Any]
) -> None:
    square_plan["mission"]["items"] = [i for i in square_plan["mission"]["items"] if i["command"] != 22]
    spec = load_test(write("t.yaml", native({"mission": {"plan": square_plan, "takeoffAltitude": 7}}))).spec
    items = mission_items(spec)
    assert items[0].kind == MissionItemKind.TAKEOFF and items[0].alt == 7
    assert (items[0].lat, items[0].lon) == (spec.world.home.lat, spec.world.home.lon)
    assert [i.kind for i in items[1:]] == [
        MissionItemKind.WAYPOINT,
        MissionItemKind.CHANGE_SPEED,
        MissionItemKind.LOITER_TIME,
        MissionItemKind.RETURN,
    ]
    assert items[1].hold == 2 and items[2].speed == 4.5 and items[3].hold == 5 and items[3].alt == 12
    assert all(math.isfinite(i.lat) for i in items if i.lat is not None)
