"""PX4 v1.15's parameter table: generated from PX4's own facts, and the built-in vehicle against it."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path
from types import ModuleType

import pytest

from uavtest.px4.parameters import check_value, known, lookup, parameters, suggest
from uavtest.sitl.mav import ParamType
from uavtest.sitl.params import DEFAULTS, READ_WHEN_USED, UNMODELLED_AT_BOOT, ParamStore

REPO = Path(__file__).resolve().parents[3]
TABLE = REPO / "operator" / "uavtest" / "px4" / "parameters_v1_15.json"


def _generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_px4_params", REPO / "tools" / "gen_px4_params.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_table_is_what_the_generator_makes_from_the_shared_data(shared_data: Path) -> None:
    text = _generator().generate(shared_data)
    assert text == TABLE.read_text(), "regenerate: python3 tools/gen_px4_params.py"


def test_the_table_holds_every_px4_v1_15_parameter_with_types_and_ranges() -> None:
    table = parameters()
    assert len(table) == 1786
    nav = lookup("NAV_ACC_RAD")
    assert nav is not None and nav.type == "FLOAT" and nav.default == 10.0 and nav.sih == 2.0
    assert (nav.min, nav.max) == (0.05, 200.0)
    yaw = lookup("MPC_YAW_MODE")
    assert yaw is not None and yaw.is_int and yaw.values == (0, 1, 2, 3, 4)
    assert lookup("NAV_RCL_ACT") is not None and lookup("NAV_RCL_ACT").is_int  # an enum: INT32
    assert not known("UAVTEST_X") and known("EKF2_GPS_DELAY")


def test_sih_values_where_logs_disagree_come_from_the_real_time_logs() -> None:
    sih = _generator().sih_values(
        {
            "competition-mission1-run1.ulg": {"COM_DL_LOSS_T": 200, "A": 1.0},
            "competition-mission1-sf1.ulg": {"COM_DL_LOSS_T": 10, "A": 1.0, "LOC": 488.0},
            "square-mission.ulg": {"COM_DL_LOSS_T": 10, "A": 1.0, "LOC": 32.0},
        }
    )
    assert sih == {"A": 1.0, "COM_DL_LOSS_T": 10}


@pytest.mark.parametrize(
    ("name", "value", "problem"),
    [
        ("NAV_ACC_RAD", 0.5, None),
        ("NAV_ACC_RAD", 0.01, "value out of range"),
        ("NAV_ACC_RAD", 500, "value out of range"),
        ("NAV_RCL_ACT", 3, None),
        ("NAV_RCL_ACT", 3.0, None),
        ("NAV_RCL_ACT", 2.5, "not an integer (the parameter is INT32)"),
        ("MPC_YAW_MODE", 7, "value out of range"),
        ("NAV_RCL_ACT", 0, "value out of range"),  # documented 1..6 (PX4 itself would store it)
        ("COM_LOW_BAT_ACT", 1, None),  # not among the documented 0, 2, 3 but no min / max
        ("MIS_TAKEOFF_ALT", float("nan"), "not a finite number"),
        ("NO_SUCH_PARAM", 1, None),
    ],
)
def test_check_value(name: str, value: float, problem: str | None) -> None:
    assert check_value(name, value) == problem


def test_close_names_are_suggested() -> None:
    assert "NAV_ACC_RAD" in suggest("NAV_ACC_RA")
    assert "MPC_XY_CRUISE" in suggest("mpc_xy_cruse")


def test_every_modelled_parameter_is_a_px4_parameter_of_the_same_type_and_sih_value() -> None:
    for name, (ptype, default) in DEFAULTS.items():
        p = lookup(name)
        assert p is not None, f"{name} is not a PX4 v1.15 parameter"
        assert p.is_int == (ptype == ParamType.INT32), name
        assert p.sih is not None, f"{name}: the SIH logs do not hold it"
        assert default == pytest.approx(p.sih, rel=1e-6), f"{name}: DEFAULTS {default}, PX4 SIH {p.sih}"
    assert all(known(n) and n not in DEFAULTS for n in UNMODELLED_AT_BOOT)


def test_defaults_agree_with_the_sih_logs_themselves(shared_data: Path) -> None:
    from pyulog import ULog

    boot = ULog(str(shared_data / "px4-sih" / "square-mission.ulg"), [], True).initial_parameters
    store = ParamStore()
    for name in store:
        assert store[name] == pytest.approx(boot[name], rel=1e-6, abs=1e-9), name


def _sitl_sources() -> str:
    folder = REPO / "operator" / "uavtest" / "sitl"
    return "".join(p.read_text() for p in sorted(folder.rglob("*.py")) if p.name != "params.py")


def test_modelled_means_read_by_the_simulator_both_ways() -> None:
    """A name in DEFAULTS is read somewhere in the simulator; a PX4 name it reads is in DEFAULTS."""
    read = {n for n in re.findall(r'"([A-Z][A-Z0-9_]{2,15})"', _sitl_sources()) if known(n)}
    assert set(DEFAULTS) - read == set(), "declared as modelled but read nowhere"
    assert read - set(DEFAULTS) - set(READ_WHEN_USED) == set(), (
        "read by the simulator but not declared in DEFAULTS"
    )
    assert all(known(n) and n not in DEFAULTS for n in READ_WHEN_USED)


def test_the_readme_table_lists_exactly_the_modelled_parameters() -> None:
    text = (REPO / "README.md").read_text()
    section = text.split("## What the built-in vehicle models", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| [a-z0-9_]+ \| ([A-Z0-9_]+) \| .+ \|$", section, flags=re.M)
    assert sorted(rows) == sorted(DEFAULTS)
    assert len(rows) == len(set(rows))
