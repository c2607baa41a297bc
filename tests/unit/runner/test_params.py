"""Stage 2: parameters are set with PX4's encoding and verified by the vehicle's echo."""

from __future__ import annotations

import struct

import pytest

from uavtest.runner.events import ParamRequestRead, ParamSet, ParamValue
from uavtest.runner.params import ParamSetter, decode_param, encode_param, param_matches
from uavtest.runner.px4 import ParamType

INT32, REAL32 = int(ParamType.INT32), int(ParamType.REAL32)


def test_int32_travels_bytewise_inside_the_float() -> None:
    wire = encode_param(1, INT32)
    assert struct.pack("<f", wire) == struct.pack("<i", 1)  # a denormal, not 1.0
    assert wire != 1.0
    assert decode_param(wire, INT32) == 1


@pytest.mark.parametrize("value", [0, 1, -1, 3, 1000, 2**31 - 1, -(2**31)])
def test_int32_round_trips(value: int) -> None:
    assert decode_param(encode_param(value, INT32), INT32) == value


def test_real32_travels_as_a_float() -> None:
    assert encode_param(8.5, REAL32) == 8.5
    assert param_matches(0.1, encode_param(0.1, REAL32), REAL32)  # float32 precision


def test_a_fraction_for_an_integer_parameter_is_refused() -> None:
    with pytest.raises(ValueError, match="not a whole number"):
        encode_param(2.5, INT32)
    assert decode_param(encode_param(2.0, INT32), INT32) == 2


def _answer(setter: ParamSetter, name: str, value: float, ptype: int, wall: float = 0.0) -> list[object]:
    return list(setter.handle(ParamValue(name, value, ptype), wall))


def test_the_type_comes_from_the_vehicle_then_each_value_is_verified() -> None:
    setter = ParamSetter({"COM_RCL_EXCEPT": 4, "MPC_XY_CRUISE": 8})
    out = setter.start(0.0)
    assert out == [ParamRequestRead("COM_RCL_EXCEPT")]
    # PX4 says it is INT32: the set is byte-wise
    out = _answer(setter, "COM_RCL_EXCEPT", encode_param(0, INT32), INT32)
    assert out == [ParamSet("COM_RCL_EXCEPT", encode_param(4, INT32), INT32)]
    out = _answer(setter, "COM_RCL_EXCEPT", encode_param(4, INT32), INT32)
    assert out == [ParamRequestRead("MPC_XY_CRUISE")]
    # MPC_XY_CRUISE is REAL32 on the vehicle although the test wrote 8 (an int)
    out = _answer(setter, "MPC_XY_CRUISE", 12.0, REAL32)
    assert out == [ParamSet("MPC_XY_CRUISE", 8.0, REAL32)]
    assert _answer(setter, "MPC_XY_CRUISE", 8.0, REAL32) == []
    assert setter.done and setter.error is None
    assert setter.verified == {"COM_RCL_EXCEPT": 4, "MPC_XY_CRUISE": 8.0}


def test_other_parameters_streaming_by_are_ignored() -> None:
    setter = ParamSetter({"NAV_ACC_RAD": 2.0})
    setter.start(0.0)
    assert _answer(setter, "MIS_TAKEOFF_ALT", 2.5, REAL32) == []
    assert not setter.done


def test_silence_is_retried_then_an_unknown_parameter_is_set_with_its_own_type() -> None:
    setter = ParamSetter({"MY_CUSTOM": 7}, retry_s=1.0, attempts=3)
    setter.start(0.0)
    assert setter.tick(0.5) == []  # not yet
    assert setter.tick(1.0) == [ParamRequestRead("MY_CUSTOM")]
    assert setter.tick(2.0) == [ParamRequestRead("MY_CUSTOM")]
    out = setter.tick(3.0)  # third read unanswered: set it as INT32 (an int was given)
    assert out == [ParamSet("MY_CUSTOM", encode_param(7, INT32), INT32)]
    _answer(setter, "MY_CUSTOM", encode_param(7, INT32), INT32, 3.1)
    assert setter.done and setter.error is None


def test_a_vehicle_that_keeps_another_value_fails_the_stage_naming_the_parameter() -> None:
    setter = ParamSetter({"NAV_ACC_RAD": 2.0}, attempts=2)
    setter.start(0.0)
    _answer(setter, "NAV_ACC_RAD", 0.5, REAL32)
    assert _answer(setter, "NAV_ACC_RAD", 0.5, REAL32) == [ParamSet("NAV_ACC_RAD", 2.0, REAL32)]
    _answer(setter, "NAV_ACC_RAD", 0.5, REAL32)
    assert setter.done
    assert setter.error == "parameter NAV_ACC_RAD: vehicle kept 0.5 (wanted 2.0)"


def test_no_answer_to_sets_is_an_error_after_the_attempts() -> None:
    setter = ParamSetter({"NAV_ACC_RAD": 2.0}, attempts=2)
    setter.start(0.0)
    _answer(setter, "NAV_ACC_RAD", 0.5, REAL32, 0.0)
    assert setter.tick(1.0) == [ParamSet("NAV_ACC_RAD", 2.0, REAL32)]
    assert setter.tick(2.0) == []
    assert setter.error is not None and "NAV_ACC_RAD" in setter.error and "no PARAM_VALUE" in setter.error


def test_no_parameters_is_done_at_once() -> None:
    setter = ParamSetter({})
    assert setter.start(0.0) == [] and setter.done


def test_a_parameter_the_vehicle_never_answers_for_is_named_as_not_accepted() -> None:
    """PX4 v1.15 answers neither the read nor the set of a name it lacks (and nor does the sim)."""
    setter = ParamSetter({"NAV_ACC_RA": 0.5}, retry_s=1.0, attempts=2)
    setter.start(0.0)
    assert setter.tick(1.0) == [ParamRequestRead("NAV_ACC_RA")]
    assert setter.tick(2.0) == [ParamSet("NAV_ACC_RA", 0.5, REAL32)]  # reads unanswered: set it anyway
    assert setter.tick(3.0) == [ParamSet("NAV_ACC_RA", 0.5, REAL32)]
    assert setter.tick(4.0) == []
    assert setter.done
    assert setter.error is not None
    assert setter.error.startswith("PX4 did not accept parameter NAV_ACC_RA (unknown to this firmware?)")
