"""Stage 3: the mission protocol, including a vehicle that asks for an item again."""

from __future__ import annotations

import math

import pytest

from uavtest.runner.events import MissionAck, MissionCount, MissionItemInt, MissionRequest
from uavtest.runner.mission import FRAME_GLOBAL_RELATIVE_ALT_INT, MissionUploader, wire_items
from uavtest.runner.px4 import Cmd, MissionResult
from uavtest.spec.models import Home, MissionItem, MissionItemKind

HOME = Home(lat=47.397742, lon=8.545594, alt=488.0)


def _items(n: int) -> list[MissionItemInt]:
    return [MissionItemInt(i, FRAME_GLOBAL_RELATIVE_ALT_INT, Cmd.NAV_WAYPOINT, z=10.0) for i in range(n)]


def test_wire_items_use_global_int_coordinates_and_relative_altitude() -> None:
    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=10),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=47.3979, lon=8.5457, alt=12, hold=3),
        MissionItem(kind=MissionItemKind.LAND),
        MissionItem(kind=MissionItemKind.CHANGE_SPEED, speed=4),
    ]
    wire = wire_items(items, HOME)
    assert [w.command for w in wire] == [22, 16, 21, 178]
    assert [w.seq for w in wire] == [0, 1, 2, 3]
    assert wire[0].x == 473977420 and wire[0].y == 85455940 and wire[0].z == 10
    assert wire[1].param1 == 3 and wire[1].x == 473979000 and math.isnan(wire[1].param4)
    # a land item without a position lands where the previous item was
    assert (wire[2].x, wire[2].y, wire[2].z) == (wire[1].x, wire[1].y, 0.0)
    assert wire[3].param2 == 4 and wire[3].frame == 2


def test_an_items_heading_goes_out_in_param4_in_degrees() -> None:
    # PX4's mavlink_mission.cpp reads param4 of takeoff, waypoint, loiter-time and land as the
    # heading in degrees (wrap_2pi(radians(param4))); NaN leaves it to MPC_YAW_MODE
    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=10, yaw=45),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=47.3979, lon=8.5457, alt=12, yaw=270),
        MissionItem(kind=MissionItemKind.LOITER_TIME, lat=47.3979, lon=8.5457, alt=12, hold=2, yaw=-90),
        MissionItem(kind=MissionItemKind.LAND, yaw=0),
        MissionItem(kind=MissionItemKind.LAND),
    ]
    assert [w.param4 for w in wire_items(items, HOME)[:4]] == [45, 270, -90, 0]
    assert math.isnan(wire_items(items, HOME)[4].param4)


def test_upload_answers_each_request_and_ends_on_accepted() -> None:
    up = MissionUploader(_items(3))
    assert up.start(0.0) == [MissionCount(3)]
    assert up.handle(MissionRequest(0), 0.0) == [_items(3)[0]]
    assert up.handle(MissionRequest(1), 0.0) == [_items(3)[1]]
    assert up.handle(MissionRequest(2), 0.0) == [_items(3)[2]]
    assert up.handle(MissionAck(MissionResult.ACCEPTED), 0.0) == []
    assert up.done and up.error is None


def test_an_item_asked_for_again_is_sent_again() -> None:
    up = MissionUploader(_items(3))
    up.start(0.0)
    up.handle(MissionRequest(0), 0.0)
    up.handle(MissionRequest(1), 0.0)
    assert up.handle(MissionRequest(1), 0.1) == [_items(3)[1]]  # item 1 got lost on the way
    up.handle(MissionRequest(2), 0.2)
    up.handle(MissionAck(MissionResult.ACCEPTED), 0.2)
    assert up.done and up.error is None and up.resent == 1


def test_older_mission_request_works_like_request_int() -> None:
    # the link turns both MISSION_REQUEST and MISSION_REQUEST_INT into MissionRequest
    up = MissionUploader(_items(1))
    up.start(0.0)
    assert up.handle(MissionRequest(0, mission_type=0), 0.0) == [_items(1)[0]]
    assert up.handle(MissionRequest(0, mission_type=1), 0.0) == []  # a geofence upload is not ours


def test_silence_resends_the_last_message() -> None:
    up = MissionUploader(_items(2), retry_s=1.0)
    up.start(0.0)
    assert up.tick(0.9) == []
    assert up.tick(1.0) == [MissionCount(2)]
    up.handle(MissionRequest(0), 1.1)
    assert up.tick(2.1) == [_items(2)[0]]


def test_a_refusal_restarts_the_upload_and_gives_up_after_the_attempts() -> None:
    up = MissionUploader(_items(2), uploads=3)
    up.start(0.0)
    for attempt in range(3):
        up.handle(MissionRequest(0), 0.0)
        out = up.handle(MissionAck(MissionResult.NO_SPACE), 0.0)
        if attempt < 2:
            assert out == [MissionCount(2)]
    assert up.done
    assert up.error == "mission upload refused after 3 attempts: MISSION_ACK NO_SPACE"


def test_a_vehicle_that_stops_answering_fails_the_upload() -> None:
    up = MissionUploader(_items(2), retry_s=1.0, attempts=2, uploads=1)
    up.start(0.0)
    up.tick(1.0)
    up.tick(2.0)
    assert up.done and up.error is not None and "silent" in up.error and "item 0" in up.error


@pytest.mark.parametrize("seq", [-1, 5])
def test_a_request_outside_the_mission_is_a_refusal(seq: int) -> None:
    up = MissionUploader(_items(2), uploads=1)
    up.start(0.0)
    up.handle(MissionRequest(seq), 0.0)
    assert up.done and up.error is not None and f"item {seq}" in up.error
