"""The upstream test cases (Aerialist samples, SBFT competition case studies) load as they are."""

from __future__ import annotations

from pathlib import Path

import pytest

from uavtest.spec.commands import resolved_commands
from uavtest.spec.loaders import load_test, load_test_text
from uavtest.spec.mission import mission_items
from uavtest.spec.models import CommandAction, FlightMode, MissionItemKind, Simulator

# Facts read from the files in shared/data (see their contents):
# competition params: mission-params.csv has 8 lines; commands: one row "1,3,0,0,0.5,0" (mission at 1 µs)
COMPETITION_PARAMS = {
    "NAV_ACC_RAD": 0.5,
    "NAV_MC_ALT_RAD": 0.5,
    "NAV_RCL_ACT": 3,
    "NAV_DLL_ACT": 0,
    "MIS_YAW_ERR": 12.0,
    "MIS_TAKEOFF_ALT": 1.0,
    "MPC_YAW_MODE": 0,
    "SDLOG_PROFILE": 7,
}
COMPETITION = [
    # file, mission item kinds (530 dropped), plannedHomePosition of the plan
    ("mission1.yaml", ["takeoff", "land"], (47.39773803960678, 8.545595700982858, 488.7567016192512)),
    ("mission2.yaml", ["takeoff", "waypoint", "land"], (47.3977419, 8.5455938, 488.7857654975923)),
    (
        "mission3.yaml",
        ["takeoff", "waypoint", "waypoint", "land"],
        (47.39773803960678, 8.545595700982858, 488.7567016192512),
    ),
]


@pytest.mark.parametrize(("name", "kinds", "home"), COMPETITION)
def test_competition_case_studies_load(
    shared_data: Path, name: str, kinds: list[str], home: tuple[float, ...]
) -> None:
    test = load_test(shared_data / "competition" / "snippets" / "case_studies" / name)
    spec = test.spec
    assert test.metadata.name == name.removesuffix(".yaml")
    assert spec.replicas == 1
    assert spec.vehicle.simulator == Simulator.BUILTIN  # upstream "ros"
    assert spec.vehicle.params == COMPETITION_PARAMS
    assert isinstance(spec.vehicle.params["NAV_RCL_ACT"], int)
    assert isinstance(spec.vehicle.params["MIS_YAW_ERR"], float)
    assert spec.world.obstacles == []  # commented out upstream
    assert (spec.world.home.lat, spec.world.home.lon, spec.world.home.alt) == home
    assert [i.kind.value for i in mission_items(spec)] == kinds
    commands = resolved_commands(spec)
    assert len(commands) == 1
    assert commands[0].action == CommandAction.MODE and commands[0].mode == FlightMode.MISSION
    assert commands[0].at == pytest.approx(1e-6)
    assert spec.assertions.similarity is None  # assertion section commented out upstream


def test_competition_mission2_waypoint_is_where_the_plan_puts_it(shared_data: Path) -> None:
    spec = load_test(shared_data / "competition" / "snippets" / "case_studies" / "mission2.yaml").spec
    takeoff, waypoint, land = mission_items(spec)
    assert (takeoff.alt, waypoint.alt, land.alt) == (10.0, 10.0, 0.0)
    assert (waypoint.lat, waypoint.lon) == (47.39768051930175, 8.546310969707491)


@pytest.mark.parametrize(("name", "replicas"), [("mission1.yaml", 1), ("mission1-k8s.yaml", 3)])
def test_aerialist_samples_load(shared_data: Path, name: str, replicas: int) -> None:
    path = shared_data / "aerialist" / "samples" / "tests" / name
    spec = load_test(path).spec
    assert spec.replicas == replicas  # agent.count: 3 in the k8s sample, no agent section in the other
    assert len(spec.vehicle.params) == 8
    assert spec.vehicle.params["MIS_TAKEOFF_ALT"] == 1.0
    [obstacle] = spec.world.obstacles
    assert (obstacle.size.l, obstacle.size.w, obstacle.size.h) == (5, 5, 5)
    assert (obstacle.position.x, obstacle.position.y, obstacle.position.z, obstacle.position.r) == (
        -8,
        3,
        0,
        0,
    )
    items = mission_items(spec)
    assert [i.kind for i in items] == [MissionItemKind.TAKEOFF, MissionItemKind.LAND]
    assert items[0].alt == 3.0  # the plan's takeoff altitude
    assert spec.world.home.lat == pytest.approx(47.49636519617687)  # the real flight's site
    similarity = spec.assertions.similarity
    assert similarity is not None and similarity.log_file is not None
    expected = shared_data / "aerialist" / "samples" / "flights" / "mission1.ulg"
    assert Path(similarity.log_file).resolve() == expected.resolve()
    assert similarity.metric.value == "dtw"


@pytest.mark.parametrize(
    ("name", "missing", "field"),
    [
        ("template.yaml", "path/to/params.csv", "robot.params_file"),
        ("manual1.yaml", "samples/flights/manual1.ulg", "mission.commands_file"),
    ],
)
def test_upstream_files_naming_absent_files_fail_with_exit_2(
    shared_data: Path, cli, name: str, missing: str, field: str
) -> None:
    path = shared_data / "aerialist" / "samples" / "tests" / name
    result = cli("validate", path)
    assert result.returncode == 2, result.stderr
    assert f"file not found: {missing}" in result.stderr
    assert str(path) in result.stderr
    assert field in result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout == ""


def test_validate_prints_a_summary(shared_data: Path, cli) -> None:
    path = shared_data / "aerialist" / "samples" / "tests" / "mission1-k8s.yaml"
    result = cli("validate", path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip().splitlines() == [
        f"ok: {path}: UavTest mission1-k8s, 3 replicas, 2 mission items, 1 command, 1 obstacle",
        # simulator: ros is PX4 with PX4-Avoidance, the competition's system under test
        "notice: mission1-k8s.yaml asks for the 'ros' simulator; uavtest flies it with its built-in "
        "simulator (uavtest sitl) and PX4-Avoidance's local planner (vehicle.avoidance: local-planner, "
        "COM_OBS_AVOID 1), the competition's system under test",
        # its params CSV sets SDLOG_PROFILE, which the built-in vehicle does not model
        "warning: 1 PX4 parameter set by the test has no effect in the built-in simulator: SDLOG_PROFILE",
    ]


def test_plan_530_is_ignored_with_a_warning(shared_data: Path, caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level("WARNING"):
        load_test(shared_data / "competition" / "snippets" / "case_studies" / "mission2.yaml")
    warnings = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert any("mission.items[0]: command 530" in w and "mission2.plan" in w for w in warnings)


@pytest.mark.parametrize(
    ("simulator", "avoidance"), [("ros", "local-planner"), ("gazebo", "none"), ("jmavsim", "none")]
)
def test_simulator_ros_flies_with_px4_avoidance(simulator: str, avoidance: str) -> None:
    """Aerialist's ros simulator is PX4 + PX4-Avoidance (the competition's system under test)."""
    waypoints = "[{x: 0, y: 0, z: 10}, {x: 20, y: 0, z: 10}]"
    text = f"simulation:\n  simulator: {simulator}\nmission:\n  waypoints: {waypoints}\n"
    spec = load_test_text(text, "upstream.yaml").spec
    assert spec.vehicle.simulator.value == "builtin"
    assert spec.vehicle.avoidance.value == avoidance
