"""uORB topic dataclasses: what modules exchange is what the ULog records."""

import dataclasses
import struct

import pytest

from uavtest.sitl import uorb
from uavtest.sitl.ulog_writer import _codes


def _classes() -> list[type]:
    return [getattr(uorb, n) for n in uorb.__all__ if isinstance(getattr(uorb, n), type)]


def test_every_topic_dataclass_is_slotted_and_has_a_format() -> None:
    names = set()
    for cls in _classes():
        assert dataclasses.is_dataclass(cls) and hasattr(cls, "__slots__"), cls
        names.add(uorb._NAME[cls])
    assert names == set(uorb.FORMATS)


@pytest.mark.parametrize("name", ["mission_result", "position_setpoint"])
def test_flat_values_match_the_format(name: str) -> None:
    sample = {
        "mission_result": uorb.MissionResult(1, 0, 0, 1, -1, 0, 0, False, False, False, False, 0, 0, 0, 0),
        "position_setpoint": uorb.INVALID_SETPOINT,
    }
    st = struct.Struct("<" + _codes(uorb.FORMATS[name], uorb.FORMATS))
    assert len(uorb.ulog_values(sample[name])) == len(st.unpack(bytes(st.size)))
    st.pack(*uorb.ulog_values(sample[name]))


def test_nested_triplet_flattens_three_setpoints() -> None:
    sp = uorb.setpoint(5, 47.0, 8.0, 500.0, 0.0, uorb.SETPOINT_TYPE_POSITION, 2.0, 5.0)
    triplet = uorb.PositionSetpointTriplet(5, uorb.INVALID_SETPOINT, sp, uorb.INVALID_SETPOINT)
    values = uorb.ulog_values(triplet)
    assert len(values) == 1 + 3 * len(uorb.FORMATS["position_setpoint"])
    assert values[1 + 16 + 1] == 47.0 and uorb.topic_name(triplet) == "position_setpoint_triplet"
