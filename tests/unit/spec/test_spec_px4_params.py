"""A test's PX4 parameters against PX4 v1.15: unknown names, types, ranges; the unmodelled ones."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from uavtest.errors import BadInput
from uavtest.sitl.params import DEFAULTS
from uavtest.spec.loaders import load_test
from uavtest.spec.models import UavTestSpec
from uavtest.spec.px4_params import check_params, modelled_params, unmodelled_notice, unmodelled_params

ARM: dict[str, Any] = {"commands": [{"at": 0, "action": "arm"}]}


def _hover(native: Callable[..., dict[str, Any]], params: dict[str, Any], **vehicle: Any) -> dict[str, Any]:
    return native({"vehicle": {"params": params, **vehicle}, "commands": [{"at": 0, "action": "arm"}]})


def test_an_unknown_name_is_refused_with_close_names(native, write) -> None:
    path = write("t.yaml", _hover(native, {"NAV_ACC_RA": 0.5}))
    with pytest.raises(BadInput) as e:
        load_test(path)
    text = str(e.value)
    assert "unknown PX4 parameter NAV_ACC_RA (did you mean NAV_ACC_RAD" in text
    assert e.value.field == "spec.vehicle.params.NAV_ACC_RA" and e.value.file == str(path)
    assert e.value.value == 0.5


def test_a_fraction_for_an_int32_parameter_names_the_type(native, write) -> None:
    with pytest.raises(BadInput) as e:
        load_test(write("t.yaml", _hover(native, {"NAV_RCL_ACT": 2.5})))
    assert e.value.field == "spec.vehicle.params.NAV_RCL_ACT" and e.value.value == 2.5
    assert "not an integer (the parameter is INT32)" in str(e.value)
    assert e.value.allowed == "an integer in [1, 6] (1, 2, 3, 5, 6)"


def test_an_enum_out_of_its_range_names_range_and_values(native, write) -> None:
    with pytest.raises(BadInput) as e:
        load_test(write("t.yaml", _hover(native, {"MPC_YAW_MODE": 7})))
    assert "PX4 parameter MPC_YAW_MODE: value out of range" in str(e.value)
    assert e.value.allowed == "an integer in [0, 4] (0, 1, 2, 3, 4)"


def test_out_of_range_names_the_range(native, write) -> None:
    with pytest.raises(BadInput) as e:
        load_test(write("t.yaml", _hover(native, {"NAV_ACC_RAD": 500})))
    assert "PX4 parameter NAV_ACC_RAD: value out of range" in str(e.value)
    assert e.value.allowed == "a number in [0.05, 200]"


def test_params_from_a_csv_are_checked_naming_the_csv(native, write) -> None:
    csv = write("p.csv", "NAV_ACC_RAD, 0.5\nNOT_A_PX4_PARAM, 1\n")
    path = write("t.yaml", native({"vehicle": {"paramsFile": "p.csv"}, **ARM}))
    with pytest.raises(BadInput) as e:
        load_test(path)
    assert e.value.file == str(csv) and e.value.field == "NOT_A_PX4_PARAM"
    assert "unknown PX4 parameter NOT_A_PX4_PARAM" in str(e.value)


def test_the_competition_params_are_all_px4_params(shared_data: Path) -> None:
    test = load_test(shared_data / "competition" / "snippets" / "case_studies" / "mission1.yaml")
    assert unmodelled_params(test.spec) == ["SDLOG_PROFILE"]


def test_unmodelled_params_only_for_the_builtin_simulator() -> None:
    spec = UavTestSpec.model_validate(
        {"vehicle": {"params": {"NAV_ACC_RAD": 1, "EKF2_GPS_DELAY": 100}}, **ARM}
    )
    assert unmodelled_params(spec) == ["EKF2_GPS_DELAY"]
    px4 = UavTestSpec.model_validate(
        {"vehicle": {"simulator": "px4", "params": {"EKF2_GPS_DELAY": 100}}, **ARM}
    )
    assert unmodelled_params(px4) == []
    assert modelled_params() == frozenset(DEFAULTS)
    assert unmodelled_notice([]) is None
    assert unmodelled_notice(["A", "B"]) == (
        "2 PX4 parameters set by the test have no effect in the built-in simulator: A, B"
    )


def test_check_params_passes_good_values() -> None:
    check_params({"NAV_ACC_RAD": 0.5, "NAV_RCL_ACT": 3, "MPC_YAW_MODE": 0.0}, source="x")


def test_validate_warns_about_unmodelled_params(uavtest, native, write) -> None:
    path = write("t.yaml", _hover(native, {"NAV_ACC_RAD": 1.0, "EKF2_GPS_DELAY": 100, "SYS_HAS_GPS": 1}))
    result = uavtest("validate", path)
    assert result.returncode == 0, result.stderr
    assert "ok: " in result.stdout
    assert (
        "warning: 2 PX4 parameters set by the test have no effect in the built-in simulator: "
        "EKF2_GPS_DELAY, SYS_HAS_GPS" in result.stdout
    )


def test_validate_refuses_an_unknown_param_with_exit_2_and_no_traceback(uavtest, native, write) -> None:
    path = write("t.yaml", _hover(native, {"MPC_XY_CRUSE": 8}))
    result = uavtest("validate", path)
    assert result.returncode == 2
    assert "unknown PX4 parameter MPC_XY_CRUSE" in result.stderr and "MPC_XY_CRUISE" in result.stderr
    assert "Traceback" not in result.stderr
