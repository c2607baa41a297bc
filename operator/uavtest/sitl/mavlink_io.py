"""The one pymavlink adapter: ``Msg`` values to MAVLink 2 bytes and back.

Uses pymavlink's generated ``common`` dialect directly (``pymavlink.dialects.v20.common``), so
importing it sets no global state. One ``Codec`` per link keeps that link's sequence numbers.
Fields missing from a ``Msg`` are sent as zeros (empty strings, zero arrays), so MAVLink 2
extension fields may be left out.
"""

from __future__ import annotations

from typing import Any

from pymavlink.dialects.v20 import common as mavlink2

from uavtest.sitl.mav import COMPONENT_ID, SYSTEM_ID, Msg

__all__ = ["Codec", "command_name", "custom_mode_name"]

_Spec = tuple[type, list[tuple[str, str, int]]]
_SPECS: dict[str, _Spec] = {}


def _spec(name: str) -> _Spec:
    spec = _SPECS.get(name)
    if spec is None:
        cls = getattr(mavlink2, f"MAVLink_{name.lower()}_message")
        spec = (cls, list(zip(cls.fieldnames, cls.fieldtypes, cls.array_lengths, strict=True)))
        _SPECS[name] = spec
    return spec


def _arg(value: Any, ftype: str, length: int) -> Any:
    if ftype == "char":
        if value is None:
            return b""
        return value.encode("ascii", errors="replace") if isinstance(value, str) else bytes(value)
    if value is None:
        return [0] * length if length else 0
    return value


class Codec:
    """MAVLink 2 encoder/decoder for one link, as system ``sysid`` component ``compid``."""

    def __init__(self, sysid: int = SYSTEM_ID, compid: int = COMPONENT_ID) -> None:
        self._mav = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self._mav.robust_parsing = True

    def encode(self, msg: Msg) -> bytes:
        cls, fields = _spec(msg.name)
        values = msg.fields
        args = [_arg(values.get(fname), ftype, length) for fname, ftype, length in fields]
        return bytes(cls(*args).pack(self._mav))

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
