"""A streaming writer of PX4 ULog files (format version 1), written as the vehicle flies.

ULog (https://docs.px4.io/main/en/dev_log/ulog_file_format.html): a 16-byte header
(``ULog\\x01\\x12\\x35``, version, start timestamp), the flag-bits message, then definitions
(formats ``F``, info ``I``, parameters ``P``), then data (``A`` subscriptions, ``D`` data,
``L`` logged strings, ``P`` changed parameters, ``S`` sync). Formats may nest other formats
(PX4's ``position_setpoint_triplet`` holds three ``position_setpoint``); data is packed
without padding in format order, little-endian.

``ULogEncoder`` turns records into bytes (pure); ``ULogFile`` is the file edge: it writes
``NAME.ulg.part`` and renames it to ``NAME.ulg`` when closed, so a reader never sees half a log.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import BinaryIO

from uavtest.errors import InfrastructureError

__all__ = ["LOG_LEVEL", "ULogEncoder", "ULogFile"]

MAGIC = b"ULog\x01\x12\x35"
VERSION = 1
SYNC_MAGIC = bytes([0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12])

#: logged-string levels (ASCII digits as in the Linux kernel, as PX4 writes them)
LOG_LEVEL = {
    "emergency": ord("0"),
    "error": ord("3"),
    "warning": ord("4"),
    "notice": ord("5"),
    "info": ord("6"),
}

_CODES = {
    "int8_t": "b",
    "uint8_t": "B",
    "int16_t": "h",
    "uint16_t": "H",
    "int32_t": "i",
    "uint32_t": "I",
    "int64_t": "q",
    "uint64_t": "Q",
    "float": "f",
    "double": "d",
    "bool": "?",
    "char": "c",
}


def _split(field: str) -> tuple[str, int, str]:
    """'float[4] q' → ('float', 4, 'q'); 'float x' → ('float', 0, 'x')."""
    ftype, name = field.split()
    if "[" in ftype:
        base, count = ftype[:-1].split("[")
        return base, int(count), name
    return ftype, 0, name


def _codes(fields: Sequence[str], formats: Mapping[str, Sequence[str]]) -> str:
    out = []
    for field in fields:
        base, count, _ = _split(field)
        if base in _CODES:
            out.append(f"{count}{_CODES[base]}" if count else _CODES[base])
            if base == "char" and count:
                out[-1] = f"{count}s"
        else:
            inner = _codes(formats[base], formats)
            out.append(inner * max(count, 1))
    return "".join(out)


def _msg(kind: str, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def _key_value(key_type: str, name: str, value: int | float | str) -> bytes:
    key = f"{key_type} {name}".encode()
    if key_type == "int32_t":
        raw = struct.pack("<i", int(value))
    elif key_type == "float":
        raw = struct.pack("<f", float(value))
    elif key_type.startswith("char["):
        raw = str(value).encode()
    else:
        raise ValueError(f"unsupported info type {key_type}")
    return bytes([len(key)]) + key + raw


def _info_type(value: int | float | str) -> tuple[str, int | float | str]:
    if isinstance(value, str):
        return f"char[{len(value.encode())}]", value
    if isinstance(value, int):
        return "int32_t", value
    return "float", value


class ULogEncoder:
    """Bytes of a ULog: ``header()`` first, then records in time order."""

    def __init__(self, formats: Mapping[str, Sequence[str]]) -> None:
        self._formats = dict(formats)
        self._ids: dict[str, int] = {}
        self._structs: dict[str, struct.Struct] = {}

    def header(
        self,
        start_us: int,
        info: Mapping[str, int | float | str],
        params: Iterable[tuple[str, bool, float]],
        topics: Sequence[str],
    ) -> bytes:
        """Header, flag bits, formats, info, initial parameters (name, is_int, value) and subscriptions."""
        out = bytearray(MAGIC + bytes([VERSION]) + struct.pack("<Q", start_us))
        out += _msg("B", bytes(16) + bytes(24))  # no compat/incompat flags, no appended data
        for name, fields in self._formats.items():
            out += _msg("F", f"{name}:{''.join(f + ';' for f in fields)}".encode())
        for key, value in info.items():
            key_type, typed = _info_type(value)
            out += _msg("I", _key_value(key_type, key, typed))
        for name, is_int, value in params:
            out += self.parameter(name, is_int, value)
        for msg_id, topic in enumerate(topics):
            self._ids[topic] = msg_id
            codes = _codes(self._formats[topic], self._formats)
            self._structs[topic] = struct.Struct("<HBH" + codes)
            out += _msg("A", struct.pack("<BH", 0, msg_id) + topic.encode())
        out += _msg("S", SYNC_MAGIC)
        return bytes(out)

    def data(self, topic: str, values: Sequence[object]) -> bytes:
        """One data message of a subscribed topic; ``values`` flat, in format order, timestamp first."""
        st = self._structs[topic]
        return st.pack(st.size - 3, 68, self._ids[topic], *values)

    @staticmethod
    def logging(level: int, timestamp_us: int, text: str) -> bytes:
        return _msg("L", struct.pack("<BQ", level, timestamp_us) + text.encode())

    @staticmethod
    def parameter(name: str, is_int: bool, value: float) -> bytes:
        return _msg("P", _key_value("int32_t" if is_int else "float", name, value))


class ULogFile:
    """A ULog being written to ``<path>.part``; ``close()`` renames it to ``<path>``."""

    def __init__(self, path: Path, header: bytes) -> None:
        self.path = path
        self.part = path.with_name(path.name + ".part")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._fh: BinaryIO | None = open(self.part, "wb")  # noqa: SIM115 - closed in close()
        except OSError as e:
            raise InfrastructureError(f"cannot write the flight log {self.part}: {e}") from e
        self._buf = bytearray(header)

    @property
    def closed(self) -> bool:
        return self._fh is None

    def write(self, chunk: bytes) -> None:
        if self._fh is None:
            return
        self._buf += chunk
        if len(self._buf) > 1 << 16:
            self.flush()

    def flush(self) -> None:
        if self._fh is not None and self._buf:
            self._fh.write(self._buf)
            self._buf.clear()

    def close(self) -> Path:
        """Write what is left, close, and rename ``.part`` to ``.ulg``; returns the final path."""
        if self._fh is not None:
            self.flush()
            self._fh.close()
            self._fh = None
            self.part.replace(self.path)
        return self.path
