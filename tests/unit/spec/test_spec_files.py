"""The small file formats: PX4 params CSV, Aerialist commands CSV, QGC plans."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import pytest

from uavtest.errors import BadInput
from uavtest.spec.commands_csv import parse_commands_csv, read_commands_csv
from uavtest.spec.models import CommandAction, FlightMode, MissionItemKind
from uavtest.spec.params_csv import parse_params_csv, read_params_csv
from uavtest.spec.plan import parse_plan, plan_home


def test_params_keep_ints_and_floats() -> None:
    params = parse_params_csv("NAV_RCL_ACT, 3\nMIS_YAW_ERR, 12.0\n\nMPC_XY_CRUISE,1e1\n# comment\n", "p.csv")
    assert params == {"NAV_RCL_ACT": 3, "MIS_YAW_ERR": 12.0, "MPC_XY_CRUISE": 10.0}
    assert [type(v) for v in params.values()] == [int, float, float]


@pytest.mark.parametrize(
    ("text", "part"),
    [
        ("NAV_RCL_ACT, 3, 4\n", "expected 2 columns"),
        ("NAV RCL, 3\n", "not a PX4 parameter name"),
        ("A_NAME_LONGER_THAN_16, 1\n", "not a PX4 parameter name"),
        ("NAV_RCL_ACT, nan\n", "not finite"),
    ],
)
def test_bad_params(text: str, part: str) -> None:
    with pytest.raises(BadInput, match=part):
        parse_params_csv(text, "p.csv")


def test_real_params_files(shared_data: Path) -> None:
    p = read_params_csv(shared_data / "aerialist" / "samples" / "flights" / "mission2-params.csv")
    assert p["NAV_ACC_RAD"] == 1.5 and p["SDLOG_PROFILE"] == 131 and len(p) == 8


@pytest.mark.parametrize(
    ("code", "action", "mode"),
    [
        (0, CommandAction.MODE, FlightMode.MANUAL),
        (1, CommandAction.MODE, FlightMode.ALTITUDE),
        (2, CommandAction.MODE, FlightMode.POSITION),
        (3, CommandAction.MODE, FlightMode.MISSION),
        (4, CommandAction.MODE, FlightMode.HOLD),
        (5, CommandAction.MODE, FlightMode.RETURN),
        (7, CommandAction.MODE, FlightMode.OFFBOARD),
        (10, CommandAction.MODE, FlightMode.TAKEOFF),
        (11, CommandAction.MODE, FlightMode.LAND),
        (20, CommandAction.ARM, None),
        (21, CommandAction.DISARM, None),
    ],
)
def test_aerialist_mode_codes(code: int, action: CommandAction, mode: FlightMode | None) -> None:
    [command] = parse_commands_csv(f"timestamp,mode,x,y,z,r\n2500000,{code},0,0,0.5,0\n", "c.csv")
    assert (command.at, command.action, command.mode) == (2.5, action, mode)


@pytest.mark.parametrize("code", [6, 8, 12, 9, 99])
def test_unflyable_codes_are_refused(code: int) -> None:
    with pytest.raises(BadInput) as e:
        parse_commands_csv(f"timestamp,mode,x,y,z,r\n0,{code},0,0,0.5,0\n", "c.csv")
    assert f"mode code {code}" in str(e.value) and "allowed: 0 manual" in str(e.value)


def test_real_manual_commands(shared_data: Path) -> None:
    flights = shared_data / "aerialist" / "samples" / "flights"
    manual1 = read_commands_csv(flights / "manual1-commands.csv")
    manual2 = read_commands_csv(flights / "manual2-commands.csv")  # columns in another order
    assert (len(manual1), len(manual2)) == (159, 502)  # data rows of the files
    assert (manual1[0].at, manual1[0].mode) == (6.512, FlightMode.HOLD)
    assert manual1[-1].action == CommandAction.DISARM and manual1[-1].at == 57.428
    assert manual2[0].mode == FlightMode.HOLD and manual2[1].action == CommandAction.STICKS
    assert all(a.at <= b.at for a, b in itertools.pairwise(manual1))
    assert sum(c.action == CommandAction.ARM for c in manual1) == 1


def test_plan_items_and_home(square_plan: dict[str, Any]) -> None:
    items = parse_plan(square_plan, "s.plan", home_alt=488.0)
    assert [i.kind for i in items] == [
        MissionItemKind.TAKEOFF,
        MissionItemKind.WAYPOINT,
        MissionItemKind.CHANGE_SPEED,
        MissionItemKind.LOITER_TIME,
        MissionItemKind.RETURN,
    ]
    home = plan_home(square_plan, "s.plan")
    assert home is not None and (home.lat, home.lon, home.alt) == (47.3977419, 8.5455938, 488.0)


def test_a_plan_items_heading_is_kept_and_null_means_none(square_plan: dict[str, Any]) -> None:
    # QGC writes an item's heading in params[3], degrees; null: "no heading" (MPC_YAW_MODE)
    square_plan["mission"]["items"][2]["params"][3] = 270
    items = parse_plan(square_plan, "s.plan", home_alt=488.0)
    assert items[1].kind == MissionItemKind.WAYPOINT and items[1].yaw == 270
    assert items[0].yaw is None  # the takeoff's params[3] is null


def test_a_plan_heading_out_of_range_names_params_3(square_plan: dict[str, Any]) -> None:
    square_plan["mission"]["items"][2]["params"][3] = 400
    with pytest.raises(BadInput, match="heading out of range") as e:
        parse_plan(square_plan, "s.plan", home_alt=488.0)
    assert e.value.field == "mission.items[2].params[3]" and e.value.value == 400


def test_plan_amsl_frame_is_made_relative(square_plan: dict[str, Any]) -> None:
    square_plan["mission"]["items"][2].update(frame=0, params=[0, 0, 0, None, 47.398, 8.5456, 503.0])
    items = parse_plan(square_plan, "s.plan", home_alt=488.0)
    assert items[1].alt == pytest.approx(15.0)


def test_plan_terrain_frame_is_refused(square_plan: dict[str, Any]) -> None:
    square_plan["mission"]["items"][2]["frame"] = 10
    with pytest.raises(BadInput, match=r"frame 10 is not supported") as e:
        parse_plan(square_plan, "s.plan", home_alt=0)
    assert e.value.field == "mission.items[2].frame"


def test_plan_inline_errors_name_the_field_inside_the_test(square_plan: dict[str, Any]) -> None:
    square_plan["mission"]["items"][3]["params"][1] = 0
    with pytest.raises(BadInput) as e:
        parse_plan(square_plan, "t.yaml", home_alt=0, prefix="spec.mission.plan")
    assert e.value.field == "spec.mission.plan.mission.items[3].params[1]"
    assert "speed > 0" in str(e.value)
