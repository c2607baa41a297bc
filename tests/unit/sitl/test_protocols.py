from uavtest.sitl.mav import MavCmd, MavFrame, MissionResult, Msg
from uavtest.sitl.protocols import MissionProtocol

GCS = (255, 190)


def _item(seq: int, command: int = MavCmd.NAV_WAYPOINT, frame: int = MavFrame.GLOBAL_RELATIVE_ALT_INT) -> Msg:
    return Msg(
        "MISSION_ITEM_INT",
        {
            "seq": seq,
            "command": command,
            "frame": frame,
            "x": 473977420 + seq,
            "y": 85455940,
            "z": 10.0,
            "autocontinue": 1,
            "mission_type": 0,
        },
        *GCS,
    )


def _upload(proto: MissionProtocol, items: list[Msg]) -> list[Msg]:
    replies = proto.handle(Msg("MISSION_COUNT", {"count": len(items), "mission_type": 0}, *GCS), 0, 0) or []
    for item in items:
        replies += proto.handle(item, 0, 0) or []
    return replies


def test_upload_requests_each_item_and_acks():
    proto = MissionProtocol()
    replies = _upload(proto, [_item(0, MavCmd.NAV_TAKEOFF), _item(1), _item(2, MavCmd.NAV_LAND)])
    assert [r.name for r in replies] == ["MISSION_REQUEST_INT"] * 3 + ["MISSION_ACK"]
    assert [r.fields["seq"] for r in replies[:3]] == [0, 1, 2]
    assert replies[-1].fields["type"] == MissionResult.ACCEPTED
    assert [i.command for i in proto.installed or []] == [22, 16, 21]


def test_download_returns_what_was_uploaded():
    proto = MissionProtocol()
    _upload(proto, [_item(0), _item(1)])
    (count,) = proto.handle(Msg("MISSION_REQUEST_LIST", {"mission_type": 0}, *GCS), 0, 0) or []
    assert count.fields["count"] == 2
    (item,) = proto.handle(Msg("MISSION_REQUEST_INT", {"seq": 1, "mission_type": 0}, *GCS), 0, 0) or []
    assert item.name == "MISSION_ITEM_INT"
    assert (item.fields["seq"], item.fields["x"], item.fields["z"]) == (1, 473977421, 10.0)
    (bad,) = proto.handle(Msg("MISSION_REQUEST_INT", {"seq": 5, "mission_type": 0}, *GCS), 0, 0) or []
    assert bad.fields["type"] == MissionResult.INVALID_SEQUENCE


def test_clear_all_empties_the_mission():
    proto = MissionProtocol()
    _upload(proto, [_item(0)])
    (ack,) = proto.handle(Msg("MISSION_CLEAR_ALL", {"mission_type": 0}, *GCS), 0, 0) or []
    assert ack.fields["type"] == MissionResult.ACCEPTED
    assert proto.items == [] and proto.installed == []


def test_unsupported_item_command_and_frame_are_refused():
    proto = MissionProtocol()
    replies = _upload(proto, [_item(0, command=31000)])
    assert replies[-1].fields["type"] == MissionResult.UNSUPPORTED
    replies = _upload(proto, [_item(0, frame=MavFrame.LOCAL_NED)])
    assert replies[-1].fields["type"] == MissionResult.UNSUPPORTED_FRAME
    assert proto.items == []


def test_items_out_of_sequence():
    proto = MissionProtocol()
    (ack,) = proto.handle(_item(0), 0, 0) or []  # no upload in progress
    assert ack.fields["type"] == MissionResult.INVALID_SEQUENCE
    proto.handle(Msg("MISSION_COUNT", {"count": 2, "mission_type": 0}, *GCS), 0, 0)
    (again,) = proto.handle(_item(1), 0, 0) or []  # skipped item 0: re-requested
    assert again.name == "MISSION_REQUEST_INT" and again.fields["seq"] == 0


def test_fence_and_rally_plans_are_stored_apart():
    proto = MissionProtocol()
    (req,) = proto.handle(Msg("MISSION_COUNT", {"count": 3, "mission_type": 1}, *GCS), 0, 0) or []
    assert req.name == "MISSION_REQUEST_INT" and req.fields["mission_type"] == 1
    (ack,) = proto.handle(Msg("MISSION_COUNT", {"count": 0, "mission_type": 2}, *GCS), 0, 0) or []
    assert ack.fields["type"] == MissionResult.ACCEPTED and ack.fields["mission_type"] == 2


def test_mavlink_ftp_is_refused_at_once_with_a_nak_and_said_once():
    """Not modelled: every FILE_TRANSFER_PROTOCOL request gets a NAK UnknownCommand (the next
    sequence number, the request's session and opcode), so MAVProxy falls back to
    PARAM_REQUEST_LIST at once instead of timing out; one STATUSTEXT says why."""
    from uavtest.sitl.mavlink_ftp import ERR_UNKNOWN_COMMAND, RSP_NAK
    from uavtest.sitl.vehicle import SimConfig, Vehicle

    v = Vehicle(SimConfig())
    open_ro = [7, 0, 3, 4, 31, 0, 0, 0, 0, 0, 0, 0, *b"@PARAM/param.pck?withdefaults=1"]
    texts: list[str] = []
    for seq in (7, 8):
        open_ro[0] = seq
        fields = {"target_network": 0, "target_system": 1, "target_component": 1, "payload": open_ro}
        (reply,) = v.receive(Msg("FILE_TRANSFER_PROTOCOL", fields, *GCS))
        texts += [m.fields["text"] for m in v.drain() if m.name == "STATUSTEXT"]
        p = reply.fields["payload"]
        assert reply.name == "FILE_TRANSFER_PROTOCOL" and len(p) == 251
        assert (p[0] | p[1] << 8, p[2], p[3], p[4], p[5], p[12]) == (
            seq + 1,
            3,
            RSP_NAK,
            1,
            4,
            ERR_UNKNOWN_COMMAND,
        )
        assert (reply.fields["target_system"], reply.fields["target_component"]) == GCS
    assert "".join(texts) == "MAVLink FTP not supported by the built-in simulator"  # 2 chunks, once
