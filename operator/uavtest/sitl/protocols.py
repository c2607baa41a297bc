"""The parameter and mission micro-protocols, as PX4 answers them (pure: messages in, out).

Parameters: PARAM_REQUEST_LIST → every PARAM_VALUE; PARAM_REQUEST_READ (by name or index)
→ PARAM_VALUE; PARAM_SET → store and echo PARAM_VALUE. INT32 values travel byte-wise in the float.
A PX4 v1.15 parameter the vehicle does not model is stored (first read or set) and echoed like
any other. A name PX4 v1.15 does not have gets no answer at all, as PX4 v1.15 does
(src/modules/mavlink/mavlink_parameters.cpp, release/1.15: PARAM_SET of an unknown name only
logs ``PX4_ERR("unknown param: %s")`` on the console — no PARAM_VALUE, no STATUSTEXT, and v1.15
has no PARAM_ERROR; PARAM_REQUEST_READ of one calls send_param(PARAM_INVALID), which sends nothing).

Missions (MISSION_ITEM_INT, mission_type 0): upload MISSION_COUNT → MISSION_REQUEST_INT* →
MISSION_ACK; download MISSION_REQUEST_LIST → MISSION_COUNT, MISSION_REQUEST_INT → MISSION_ITEM_INT;
MISSION_CLEAR_ALL → MISSION_ACK. Refusals: unsupported item commands MAV_MISSION_UNSUPPORTED,
bad frames MAV_MISSION_UNSUPPORTED_FRAME, an item outside an upload or a request beyond the
mission MAV_MISSION_INVALID_SEQUENCE, fence/rally plans MAV_MISSION_UNSUPPORTED.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.sitl.mav import MissionResult, MissionType, Msg, ParamType
from uavtest.sitl.mission import NavItem, check_item
from uavtest.sitl.params import ParamStore, decode_param_value, encode_param_value

__all__ = ["MissionProtocol", "ParamProtocol", "Upload"]

UPLOAD_TIMEOUT_US = 5_000_000


class ParamProtocol:
    def __init__(self, params: ParamStore) -> None:
        self.params = params
        self.changed: list[str] = []  # names set since last drained (for the log)

    def value(self, name: str) -> Msg:
        ptype = self.params.type_of(name)
        return Msg(
            "PARAM_VALUE",
            {
                "param_id": name,
                "param_value": encode_param_value(self.params[name], ptype),
                "param_type": int(ptype),
                "param_count": len(self.params),
                "param_index": self.params.index_of(name),
            },
        )

    def handle(self, msg: Msg) -> list[Msg] | None:
        """Replies, or None when the message is not a parameter message."""
        if msg.name == "PARAM_REQUEST_LIST":
            return [self.value(name) for name in self.params]
        if msg.name == "PARAM_REQUEST_READ":
            index = int(msg.get("param_index", -1))
            name = str(msg.get("param_id", "")).rstrip("\x00")
            if index >= 0:
                found = self.params.name_at(index)
                if found is None:
                    return []
                name = found
            return [self.value(name)] if self.params.ensure(name) else []
        if msg.name == "PARAM_SET":
            name = str(msg.get("param_id", "")).rstrip("\x00")
            if not name or not self.params.known(name):
                return []  # PX4 v1.15: console error only, no echo
            raw_type = int(msg.get("param_type", ParamType.REAL32))
            raw = float(msg.get("param_value", 0.0))
            if (
                name in self.params
                and self.params.type_of(name) == ParamType.INT32
                and raw_type != ParamType.INT32
            ):
                value: int | float = round(raw) if math.isfinite(raw) else 0
            elif (
                name in self.params
                and self.params.type_of(name) == ParamType.REAL32
                and raw_type == ParamType.INT32
            ):
                value = float(decode_param_value(raw, ParamType.INT32))
            else:
                value = decode_param_value(raw, raw_type)
            self.params.set(name, value, raw_type)
            self.changed.append(name)
            return [self.value(name)]
        return None


@dataclass(slots=True)
class Upload:
    count: int
    items: list[NavItem]
    started_us: int
    partner: tuple[int, int]


def _ack(msg: Msg, result: MissionResult, mission_type: int = 0) -> Msg:
    return Msg(
        "MISSION_ACK",
        {
            "target_system": msg.sysid,
            "target_component": msg.compid,
            "type": int(result),
            "mission_type": mission_type,
        },
    )


def _request(msg: Msg, seq: int) -> Msg:
    return Msg(
        "MISSION_REQUEST_INT",
        {"target_system": msg.sysid, "target_component": msg.compid, "seq": seq, "mission_type": 0},
    )


def item_message(item: NavItem, msg: Msg, current: int) -> Msg:
    return Msg(
        "MISSION_ITEM_INT",
        {
            "target_system": msg.sysid,
            "target_component": msg.compid,
            "seq": item.seq,
            "frame": item.frame,
            "command": item.command,
            "current": int(item.seq == current),
            "autocontinue": item.autocontinue,
            "param1": item.param1,
            "param2": item.param2,
            "param3": item.param3,
            "param4": item.param4,
            "x": item.x,
            "y": item.y,
            "z": item.z,
            "mission_type": 0,
        },
    )


class MissionProtocol:
    """Mission transfer state; ``installed`` holds a mission the vehicle should take."""

    def __init__(self) -> None:
        self.items: list[NavItem] = []
        self.upload: Upload | None = None
        self.installed: list[NavItem] | None = None  # set when an upload or clear completes

    def handle(self, msg: Msg, now_us: int, current: int) -> list[Msg] | None:
        name = msg.name
        if name not in {
            "MISSION_COUNT",
            "MISSION_ITEM_INT",
            "MISSION_ITEM",
            "MISSION_REQUEST_LIST",
            "MISSION_REQUEST_INT",
            "MISSION_REQUEST",
            "MISSION_CLEAR_ALL",
            "MISSION_ACK",
        }:
            return None
        mtype = int(msg.get("mission_type", 0) or 0)
        if name == "MISSION_ACK":
            return []
        if mtype != MissionType.MISSION:
            if name == "MISSION_REQUEST_LIST":
                return [
                    Msg(
                        "MISSION_COUNT",
                        {
                            "target_system": msg.sysid,
                            "target_component": msg.compid,
                            "count": 0,
                            "mission_type": mtype,
                        },
                    )
                ]
            if name == "MISSION_CLEAR_ALL":
                return [_ack(msg, MissionResult.ACCEPTED, mtype)]
            return [_ack(msg, MissionResult.UNSUPPORTED, mtype)]
        if name == "MISSION_CLEAR_ALL":
            self.items = []
            self.upload = None
            self.installed = []
            return [_ack(msg, MissionResult.ACCEPTED)]
        if name == "MISSION_COUNT":
            count = int(msg.get("count", 0))
            if count == 0:
                self.items = []
                self.installed = []
                self.upload = None
                return [_ack(msg, MissionResult.ACCEPTED)]
            if count > 2000:
                return [_ack(msg, MissionResult.NO_SPACE)]
            self.upload = Upload(count, [], now_us, (msg.sysid, msg.compid))
            return [_request(msg, 0)]
        if name in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            return self._item(msg, now_us)
        if name == "MISSION_REQUEST_LIST":
            return [
                Msg(
                    "MISSION_COUNT",
                    {
                        "target_system": msg.sysid,
                        "target_component": msg.compid,
                        "count": len(self.items),
                        "mission_type": 0,
                    },
                )
            ]
        # MISSION_REQUEST_INT / MISSION_REQUEST
        seq = int(msg.get("seq", -1))
        if not 0 <= seq < len(self.items):
            return [_ack(msg, MissionResult.INVALID_SEQUENCE)]
        item = item_message(self.items[seq], msg, current)
        if name == "MISSION_REQUEST":
            fields = dict(item.fields)
            fields["x"], fields["y"] = item.fields["x"] / 1e7, item.fields["y"] / 1e7
            return [Msg("MISSION_ITEM", fields)]
        return [item]

    def _item(self, msg: Msg, now_us: int) -> list[Msg]:
        up = self.upload
        if up is not None and now_us - up.started_us > UPLOAD_TIMEOUT_US and len(up.items) == 0:
            up = None
        if up is None:
            return [_ack(msg, MissionResult.INVALID_SEQUENCE)]
        seq = int(msg.get("seq", -1))
        expected = len(up.items)
        if seq != expected:
            if seq < expected:
                return []  # a duplicate: the partner resends; ours is still pending
            return [_request(msg, expected)]
        x, y = msg.get("x", 0), msg.get("y", 0)
        if msg.name == "MISSION_ITEM":
            x, y = round(float(x) * 1e7), round(float(y) * 1e7)
        item = NavItem(
            seq=seq,
            command=int(msg.get("command", 0)),
            frame=int(msg.get("frame", 0)),
            param1=float(msg.get("param1", 0.0)),
            param2=float(msg.get("param2", 0.0)),
            param3=float(msg.get("param3", 0.0)),
            param4=float(msg.get("param4", 0.0)),
            x=int(x),
            y=int(y),
            z=float(msg.get("z", 0.0)),
            autocontinue=int(msg.get("autocontinue", 1)),
        )
        verdict = check_item(item)
        if verdict != MissionResult.ACCEPTED:
            self.upload = None
            return [_ack(msg, verdict)]
        up.items.append(item)
        up.started_us = now_us
        if len(up.items) < up.count:
            return [_request(msg, len(up.items))]
        self.items = up.items
        self.installed = list(up.items)
        self.upload = None
        return [_ack(msg, MissionResult.ACCEPTED)]
