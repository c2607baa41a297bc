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


def test_unknown_params_are_stored_and_echoed():
    proto = ParamProtocol(ParamStore())
    count = len(proto.params)
    reply = _set(proto, "MY_PARAM", 1.25, ParamType.REAL32)
    assert reply.fields["param_value"] == 1.25
    assert reply.fields["param_count"] == count + 1
    read = proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "MY_PARAM", "param_index": -1}))
    assert read and read[0].fields["param_value"] == 1.25


def test_list_and_read_by_index():
    proto = ParamProtocol(ParamStore())
    values = proto.handle(Msg("PARAM_REQUEST_LIST", {})) or []
    assert len(values) == len(proto.params)
    assert [v.fields["param_index"] for v in values] == list(range(len(values)))
    by_index = proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "", "param_index": 3})) or []
    assert by_index[0].fields["param_id"] == values[3].fields["param_id"]
    assert proto.handle(Msg("PARAM_REQUEST_READ", {"param_id": "NO_SUCH", "param_index": -1})) == []
