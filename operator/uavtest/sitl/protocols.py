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
mission MAV_MISSION_INVALID_SEQUENCE. Fence (mission_type 1) and rally (2) plans travel the same
way, each stored apart from the mission (PX4 ``mavlink_mission.cpp``): uploading, downloading or
clearing one leaves the others; MISSION_CLEAR_ALL with MAV_MISSION_TYPE_ALL clears all three;
every MISSION_REQUEST_INT / MISSION_ACK / MISSION_COUNT carries the plan's mission_type.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.sitl.mav import MissionResult, MissionType, Msg, ParamType
from uavtest.sitl.mission import GLOBAL_FRAMES, SUPPORTED_COMMANDS, NavItem, check_item
from uavtest.sitl.navigator.geofence import (
    FENCE_COMMANDS,
    NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
    NAV_FENCE_POLYGON_VERTEX_INCLUSION,
    NAV_RALLY_POINT,
)
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
    mission_type: int = MissionType.MISSION


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


def _request(msg: Msg, seq: int, mission_type: int = 0) -> Msg:
    return Msg(
        "MISSION_REQUEST_INT",
        {
            "target_system": msg.sysid,
            "target_component": msg.compid,
            "seq": seq,
            "mission_type": mission_type,
        },
    )


def item_message(item: NavItem, msg: Msg, current: int, mission_type: int = 0) -> Msg:
    return Msg(
        "MISSION_ITEM_INT",
        {
            "target_system": msg.sysid,
            "target_component": msg.compid,
            "seq": item.seq,
            "frame": item.frame,
            "command": item.command,
            "current": int(item.seq == current and mission_type == MissionType.MISSION),
            "autocontinue": item.autocontinue,
            "param1": item.param1,
            "param2": item.param2,
            "param3": item.param3,
            "param4": item.param4,
            "x": item.x,
            "y": item.y,
            "z": item.z,
            "mission_type": mission_type,
        },
    )


_PLAN_TYPES = (MissionType.MISSION, MissionType.FENCE, MissionType.RALLY)


def check_plan_item(item: NavItem, mission_type: int) -> MissionResult:
    """ACCEPTED, or PX4's refusal of an item of a fence / rally plan (``mavlink_mission.cpp``
    parse_mavlink_mission_item + handle_mission_item_both): fence and rally items need a global
    frame (else MAV_MISSION_UNSUPPORTED_FRAME), a command PX4 parses (else
    MAV_MISSION_UNSUPPORTED); a polygon vertex with fewer than 3 vertices is MAV_MISSION_ERROR
    ("Fence: too few vertices"); fence or rally items in a mission are MAV_MISSION_ERROR."""
    fence_or_rally = item.command in FENCE_COMMANDS or item.command == NAV_RALLY_POINT
    if mission_type == MissionType.MISSION:
        return MissionResult.ERROR if fence_or_rally else check_item(item)
    if not fence_or_rally and item.command not in SUPPORTED_COMMANDS:
        return MissionResult.UNSUPPORTED
    if item.frame not in GLOBAL_FRAMES:
        return MissionResult.UNSUPPORTED_FRAME
    if not math.isfinite(item.z) or abs(item.x) > 900_000_000 or abs(item.y) > 1_800_000_000:
        return MissionResult.INVALID
    if (
        mission_type == MissionType.FENCE
        and item.command
        in (
            NAV_FENCE_POLYGON_VERTEX_INCLUSION,
            NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
        )
        and int(item.param1 + 0.5) < 3
    ):
        return MissionResult.ERROR
    return MissionResult.ACCEPTED


class MissionProtocol:
    """Mission, fence and rally plan transfers (one store per MAV_MISSION_TYPE, as PX4's
    ``MavlinkMissionManager``); ``installed`` / ``fence_installed`` / ``rally_installed`` hold a
    plan the vehicle should take (set when an upload or clear of that type completes)."""

    def __init__(self) -> None:
        self.items: list[NavItem] = []
        self.fence: list[NavItem] = []
        self.rally: list[NavItem] = []
        self.upload: Upload | None = None
        self.installed: list[NavItem] | None = None
        self.fence_installed: list[NavItem] | None = None
        self.rally_installed: list[NavItem] | None = None

    def _stored(self, mtype: int) -> list[NavItem]:
        if mtype == MissionType.FENCE:
            return self.fence
        if mtype == MissionType.RALLY:
            return self.rally
        return self.items

    def _install(self, mtype: int, items: list[NavItem]) -> None:
        if mtype == MissionType.FENCE:
            self.fence = items
            self.fence_installed = list(items)
        elif mtype == MissionType.RALLY:
            self.rally = items
            self.rally_installed = list(items)
        else:
            self.items = items
            self.installed = list(items)

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
        if name == "MISSION_CLEAR_ALL":
            if mtype == MissionType.ALL:
                for t in _PLAN_TYPES:
                    self._install(t, [])
            elif mtype in _PLAN_TYPES:
                self._install(mtype, [])
            else:
                return [_ack(msg, MissionResult.ERROR, mtype)]
            self.upload = None
            return [_ack(msg, MissionResult.ACCEPTED, mtype)]
        if mtype not in _PLAN_TYPES:  # PX4: "Received unknown mission type, abort."
            return [_ack(msg, MissionResult.ERROR, mtype)]
        if name == "MISSION_COUNT":
            count = int(msg.get("count", 0))
            if count == 0:
                self._install(mtype, [])
                self.upload = None
                return [_ack(msg, MissionResult.ACCEPTED, mtype)]
            if count > 2000:
                return [_ack(msg, MissionResult.NO_SPACE, mtype)]
            self.upload = Upload(count, [], now_us, (msg.sysid, msg.compid), mtype)
            return [_request(msg, 0, mtype)]
        if name in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            return self._item(msg, now_us, mtype)
        stored = self._stored(mtype)
        if name == "MISSION_REQUEST_LIST":
            return [
                Msg(
                    "MISSION_COUNT",
                    {
                        "target_system": msg.sysid,
                        "target_component": msg.compid,
                        "count": len(stored),
                        "mission_type": mtype,
                    },
                )
            ]
        # MISSION_REQUEST_INT / MISSION_REQUEST
        seq = int(msg.get("seq", -1))
        if not 0 <= seq < len(stored):
            return [_ack(msg, MissionResult.INVALID_SEQUENCE, mtype)]
        item = item_message(stored[seq], msg, current, mtype)
        if name == "MISSION_REQUEST":
            fields = dict(item.fields)
            fields["x"], fields["y"] = item.fields["x"] / 1e7, item.fields["y"] / 1e7
            return [Msg("MISSION_ITEM", fields)]
        return [item]

    def _item(self, msg: Msg, now_us: int, mtype: int) -> list[Msg]:
        up = self.upload
        if up is not None and now_us - up.started_us > UPLOAD_TIMEOUT_US and len(up.items) == 0:
            up = None
        if up is None or up.mission_type != mtype:
            return [_ack(msg, MissionResult.INVALID_SEQUENCE, mtype)]
        seq = int(msg.get("seq", -1))
        expected = len(up.items)
        if seq != expected:
            if seq < expected:
                return []  # a duplicate: the partner resends; ours is still pending
            return [_request(msg, expected, mtype)]
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
        verdict = check_plan_item(item, mtype)
        if verdict != MissionResult.ACCEPTED:
            self.upload = None
            return [_ack(msg, verdict, mtype)]
        up.items.append(item)
        up.started_us = now_us
        if len(up.items) < up.count:
            return [_request(msg, len(up.items), mtype)]
        self._install(mtype, up.items)
        self.upload = None
        return [_ack(msg, MissionResult.ACCEPTED, mtype)]
