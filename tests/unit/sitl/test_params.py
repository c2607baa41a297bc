import struct

from uavtest.sitl.mav import Msg, ParamType
from uavtest.sitl.params import ParamStore, decode_param_value, encode_param_value
from uavtest.sitl.protocols import ParamProtocol


def test_int32_values_travel_bytewise_in_the_float():
    raw = encode_param_value(10040, ParamType.INT32)
    assert struct.pack("<f", raw) == struct.pack("<i", 10040)
    assert decode_param_value(raw, ParamType.INT32) == 10040
    assert decode_param_value(encode_param_value(-1, ParamType.INT32), ParamType.INT32) == -1


def test_px4_defaults_and_types():
    p = ParamStore()
    assert p.type_of("MPC_YAW_MODE") == ParamType.INT32
    assert p.type_of("NAV_ACC_RAD") == ParamType.REAL32
    assert p["MIS_TAKEOFF_ALT"] == 2.5
    assert p["MPC_XY_CRUISE"] == 5.0


def _set(proto: ParamProtocol, name: str, value: float, ptype: int) -> Msg:
    msg = Msg(
        "PARAM_SET",
        {"target_system": 1, "param_id": name, "param_value": value, "param_type": ptype},
        255,
        190,
    )
    (reply,) = proto.handle(msg) or []
    return reply


def test_param_set_echoes_the_stored_value():
    proto = ParamProtocol(ParamStore())
    reply = _set(proto, "NAV_DLL_ACT", encode_param_value(2, ParamType.INT32), ParamType.INT32)
    assert reply.fields["param_id"] == "NAV_DLL_ACT"
    assert reply.fields["param_type"] == ParamType.INT32
    assert decode_param_value(reply.fields["param_value"], ParamType.INT32) == 2
    assert proto.params["NAV_DLL_ACT"] == 2


def test_an_int_param_set_as_a_plain_float_is_rounded():
    proto = ParamProtocol(ParamStore())
    _set(proto, "NAV_RCL_ACT", 3.0, ParamType.REAL32)
    assert proto.params["NAV_RCL_ACT"] == 3 and proto.params.type_of("NAV_RCL_ACT") == ParamType.INT32


def test_a_name_px4_v1_15_lacks_gets_no_answer_like_px4() -> None:
    """PX4 v1.15 (mavlink_parameters.cpp): PARAM_SET of an unknown name is a console error only."""
    proto = ParamProtocol(ParamStore())
    count = len(proto.params)
    msg = Msg("PARAM_SET", {"param_id": "MY_PARAM", "param_value": 1.25, "param_type": ParamType.REAL32})
    assert proto.handle(msg) == []
    assert "MY_PARAM" not in proto.params and len(proto.params) == count and proto.changed == []
    assert proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "MY_PARAM", "param_index": -1})) == []


def test_a_px4_parameter_the_vehicle_does_not_model_is_stored_and_echoed() -> None:
    proto = ParamProtocol(ParamStore())
    count = len(proto.params)
    read = proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "EKF2_GPS_DELAY", "param_index": -1}))
    assert read and read[0].fields["param_type"] == ParamType.REAL32
    assert read[0].fields["param_value"] == 110.0  # PX4's value
    assert read[0].fields["param_count"] == count + 1
    # PX4 keeps its own type: an INT32 parameter set as a plain float stays INT32
    reply = _set(proto, "SYS_HAS_GPS", 0.0, ParamType.REAL32)
    assert reply.fields["param_type"] == ParamType.INT32
    assert decode_param_value(reply.fields["param_value"], ParamType.INT32) == 0


def test_a_px4_parameter_read_by_code_that_was_never_stored_has_its_sih_value() -> None:
    p = ParamStore()
    assert p["COM_LOW_BAT_ACT"] == 2 and p.type_of("COM_LOW_BAT_ACT") == ParamType.INT32
    try:
        p["NO_SUCH_PARAM"]
    except KeyError:
        pass
    else:
        raise AssertionError("an unknown name must raise KeyError")


def test_list_and_read_by_index():
    proto = ParamProtocol(ParamStore())
    values = proto.handle(Msg("PARAM_REQUEST_LIST", {})) or []
    assert len(values) == len(proto.params)
    assert [v.fields["param_index"] for v in values] == list(range(len(values)))
    by_index = proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "", "param_index": 3})) or []
    assert by_index[0].fields["param_id"] == values[3].fields["param_id"]
    assert proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "NO_SUCH", "param_index": -1})) == []
