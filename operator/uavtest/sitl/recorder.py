"""The flight recorder: PX4 topics encoded as ULog, handed to a sink (file, memory).

PX4's ``logger`` module. The vehicle calls ``start`` / ``data`` (a ``uorb`` topic dataclass, recorded
as it is) / ``text`` / ``param`` / ``stop``; the recorder encodes (pure) and passes bytes to a
``LogSink`` — the I/O edge decides where they go.
"""

from __future__ import annotations

from typing import Protocol

from uavtest.sitl.mav import ParamType
from uavtest.sitl.params import ParamStore
from uavtest.sitl.ulog_writer import ULogEncoder
from uavtest.sitl.uorb import FORMATS, RECORD, TOPICS

__all__ = ["FlightRecorder", "LogSink", "MemorySink"]


class LogSink(Protocol):
    def open(self, header: bytes) -> None: ...
    def write(self, chunk: bytes) -> None: ...
    def close(self) -> None: ...


class MemorySink:
    """Keeps every log in memory (tests, benchmarks): ``logs`` holds one bytes per closed log."""

    def __init__(self) -> None:
        self.logs: list[bytes] = []
        self._current: bytearray | None = None

    def open(self, header: bytes) -> None:
        self._current = bytearray(header)

    def write(self, chunk: bytes) -> None:
        if self._current is not None:
            self._current += chunk

    def close(self) -> None:
        if self._current is not None:
            self.logs.append(bytes(self._current))
            self._current = None

    @property
    def current(self) -> bytes | None:
        return bytes(self._current) if self._current is not None else None


class FlightRecorder:
    def __init__(self, sink: LogSink | None, info: dict[str, int | float | str]) -> None:
        self.sink = sink
        self.info = info
        self.active = False
        self._enc = ULogEncoder(FORMATS)

    def start(self, t_us: int, params: ParamStore) -> None:
        if self.sink is None or self.active:
            return
        plist = [(n, t == ParamType.INT32, v) for n, t, v in params.items()]
        self.sink.open(self._enc.header(t_us, self.info, plist, TOPICS))
        self.active = True

    def data(self, msg: object) -> None:
        """Record one uORB topic dataclass (``uorb.VehicleStatus(...)``) as it is."""
        if self.active:
            assert self.sink is not None
            name, flatten = RECORD[type(msg)]
            self.sink.write(self._enc.data(name, flatten(msg)))

    def text(self, level: int, t_us: int, text: str) -> None:
        if self.active:
            assert self.sink is not None
            self.sink.write(self._enc.logging(level, t_us, text))

    def param(self, name: str, is_int: bool, value: float) -> None:
        if self.active:
            assert self.sink is not None
            self.sink.write(self._enc.parameter(name, is_int, value))

    def stop(self) -> None:
        if self.active:
            assert self.sink is not None
            self.sink.close()
            self.active = False
