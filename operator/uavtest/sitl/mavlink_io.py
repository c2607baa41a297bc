"""The one pymavlink adapter: ``Msg`` values to MAVLink 2 bytes and back.

Uses pymavlink's generated ``common`` dialect directly (``pymavlink.dialects.v20.common``), so
importing it sets no global state. One ``Codec`` per link keeps that link's sequence numbers.
Fields missing from a ``Msg`` are sent as zeros (empty strings, zero arrays), so MAVLink 2
extension fields may be left out.

Encoding is the simulator's hottest I/O path (PX4's ONBOARD link streams ~300 messages per
second of flight), so it packs with pymavlink's own per-message ``struct`` layout, CRC extra and
MAVLink 2 framing (trailing-zero truncation, X.25 CRC) without building pymavlink message
objects: the same bytes as ``MAVLink_..._message.pack`` (a unit test compares them), about four
times cheaper.
"""

from __future__ import annotations

import struct
from typing import Any

from pymavlink.dialects.v20 import common as mavlink2
from pymavlink.generator import mavcrc

from uavtest.sitl.mav import COMPONENT_ID, SYSTEM_ID, Msg

__all__ = ["Codec", "command_name", "custom_mode_name"]

_SCALAR, _CHARS, _ARRAY = 0, 1, 2
_HEADER = struct.Struct("<BBBBBBBHB")
_STX_V2 = 0xFD


def _crc_slow(data: bytes, crc: int) -> int:
    acc = mavcrc.x25crc()
    acc.crc = crc
    acc.accumulate(data)
    return int(acc.crc)


#: CRC-16/MCRF4XX: fastcrc's when installed (as pymavlink uses it), else pymavlink's pure Python
_crc = mavcrc.mcrf4xx or _crc_slow

#: message name → (struct, msgid, crc extra, [(field, kind, array length)] in wire order)
_Plan = tuple[struct.Struct, int, bytes, list[tuple[str, int, int]]]
_PLANS: dict[str, _Plan] = {}


def _plan(name: str) -> _Plan:
    plan = _PLANS.get(name)
    if plan is None:
        cls = getattr(mavlink2, f"MAVLink_{name.lower()}_message")
        types = dict(zip(cls.fieldnames, cls.fieldtypes, strict=True))
        fields = []
        for fname, length in zip(cls.ordered_fieldnames, cls.array_lengths, strict=True):
            kind = _CHARS if types[fname] == "char" else _ARRAY if length else _SCALAR
            fields.append((fname, kind, length))
        plan = (cls.unpacker, cls.id, bytes((cls.crc_extra,)), fields)
        _PLANS[name] = plan
    return plan


class Codec:
    """MAVLink 2 encoder/decoder for one link, as system ``sysid`` component ``compid``."""

    def __init__(self, sysid: int = SYSTEM_ID, compid: int = COMPONENT_ID) -> None:
        self._mav = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self._mav.robust_parsing = True
        self._sysid = sysid
        self._compid = compid
        self._seq = 0

    def encode(self, msg: Msg) -> bytes:
        """One MAVLink 2 frame, byte for byte what pymavlink's ``pack`` gives (see the module doc)."""
        packer, msgid, crc_extra, fields = _plan(msg.name)
        values = msg.fields
        flat: list[Any] = []
        for fname, kind, length in fields:
            value = values.get(fname)
            if kind == _SCALAR:
                flat.append(0 if value is None else value)
            elif kind == _CHARS:
                if value is None:
                    flat.append(b"")
                else:
                    flat.append(
                        value.encode("ascii", errors="replace") if isinstance(value, str) else bytes(value)
                    )
            elif value is None:
                flat.extend([0] * length)
            else:
                flat.extend(value)
        payload = packer.pack(*flat)
        plen = len(payload)
        while plen > 1 and payload[plen - 1] == 0:  # MAVLink 2 drops trailing zero bytes
            plen -= 1
        seq = self._seq
        self._seq = (seq + 1) & 0xFF
        frame = _HEADER.pack(_STX_V2, plen, 0, 0, seq, self._sysid, self._compid, msgid & 0xFFFF, msgid >> 16)
        frame += payload[:plen]
        crc = _crc(crc_extra, _crc(frame[1:], 0xFFFF))
        return frame + struct.pack("<H", crc)

    def decode(self, data: bytes) -> list[Msg]:
        """Every complete message in ``data`` (bad bytes are skipped)."""
        try:
            parsed = self._mav.parse_buffer(data) or []
        except mavlink2.MAVError:
            return []
        out = []
        for m in parsed:
            name = m.get_type()
            if name == "BAD_DATA" or name.startswith("UNKNOWN"):
                continue
            fields = {f: getattr(m, f) for f in m.get_fieldnames()}
            out.append(Msg(name, fields, m.get_srcSystem(), m.get_srcComponent()))
        return out


def command_name(command: int) -> str:
    """``MAV_CMD_...`` name of a command number (common.xml), or ``MAV_CMD <n>``."""
    entry = mavlink2.enums["MAV_CMD"].get(int(command))
    return entry.name if entry is not None else f"MAV_CMD {int(command)}"


_MAIN_MODES = dict(
    enumerate(("", "MANUAL", "ALTCTL", "POSCTL", "AUTO", "ACRO", "OFFBOARD", "STABILIZED", "RATTITUDE"))
)
_AUTO_SUB_MODES = {1: "READY", 2: "TAKEOFF", 3: "LOITER", 4: "MISSION", 5: "RTL", 6: "LAND"}
_AUTO_SUB_MODES.update({8: "FOLLOW_TARGET", 9: "PRECLAND", 10: "VTOL_TAKEOFF"})


def custom_mode_name(main: int, sub: int) -> str:
    """PX4's name of a main/sub custom mode (px4_custom_mode.h), e.g. ``AUTO_FOLLOW_TARGET``."""
    name = _MAIN_MODES.get(main, f"main {main}")
    if main == 4:
        return f"{name}_{_AUTO_SUB_MODES.get(sub, f'sub {sub}')}"
    return name
