"""Stage 2: set the vehicle's parameters and verify each one (pure state machine).

PX4 sends and takes integer parameters *byte-wise* inside PARAM_VALUE/PARAM_SET's float field:
the float's four bytes are the int32's bytes. Which parameters are integers the vehicle says:
the runner first reads each parameter (PARAM_REQUEST_READ) and encodes by the ``param_type`` of
the answer. A parameter the vehicle does not know (no answer) is set with the type of the value
given (an ``int`` → INT32, a ``float`` → REAL32) and still verified by its echo: PX4 v1.15 and
the built-in simulator answer an unknown name with silence, and the stage fails with
"PX4 did not accept parameter NAME (unknown to this firmware?)".
"""

from __future__ import annotations

import logging
import math
import struct
from collections.abc import Mapping
from enum import Enum

from uavtest.runner.events import Incoming, Outgoing, ParamRequestRead, ParamSet, ParamValue
from uavtest.runner.px4 import ParamType

__all__ = ["ParamSetter", "decode_param", "encode_param", "param_matches"]

log = logging.getLogger(__name__)

_INT_FORMATS: dict[int, str] = {
    ParamType.UINT8: "<B",
    ParamType.INT8: "<b",
    ParamType.UINT16: "<H",
    ParamType.INT16: "<h",
    ParamType.UINT32: "<I",
    ParamType.INT32: "<i",
}


def encode_param(value: float, param_type: int) -> float:
    """The wire float for ``value`` of ``param_type`` (byte-wise for integer types, as PX4).

    Raises ValueError for a fractional value of an integer type or an out-of-range integer.
    """
    if param_type in (ParamType.REAL32, ParamType.REAL64):
        return float(value)
    fmt = _INT_FORMATS.get(param_type)
    if fmt is None:
        raise ValueError(f"parameter type {ParamType(param_type).name} cannot travel in a float")
    if isinstance(value, float) and not value.is_integer():
        raise ValueError(f"{value} is not a whole number, and the parameter is {ParamType(param_type).name}")
    raw = struct.pack(fmt, int(value))  # struct.error (a ValueError) when out of range
    return struct.unpack("<f", raw.ljust(4, b"\0"))[0]


def decode_param(wire: float, param_type: int) -> float | int:
    """The value inside a PARAM_VALUE's float field."""
    fmt = _INT_FORMATS.get(param_type)
    if fmt is None:
        return float(wire)
    raw = struct.pack("<f", wire)
    return struct.unpack(fmt, raw[: struct.calcsize(fmt)])[0]


def param_matches(wanted: float, got: float | int, param_type: int) -> bool:
    """Whether the vehicle holds ``wanted`` (integers exactly, floats to float32 precision)."""
    if param_type in _INT_FORMATS:
        return float(got) == float(wanted)
    want32 = struct.unpack("<f", struct.pack("<f", float(wanted)))[0]
    if math.isnan(want32):
        return math.isnan(got)
    return abs(float(got) - want32) <= 1e-6 * max(1.0, abs(want32))


class _Phase(Enum):
    READ = "read"
    SET = "set"


class ParamSetter:
    """Reads, sets and verifies parameters one at a time, with bounded retries (wall clock).

    ``done`` once every parameter is verified; ``error`` names the parameter and what went wrong.
    """

    def __init__(self, params: Mapping[str, float | int], *, retry_s: float = 1.0, attempts: int = 5) -> None:
        self._todo = list(params.items())
        self.retry_s = retry_s
        self.attempts = attempts
        self.done = False
        self.error: str | None = None
        self.verified: dict[str, float | int] = {}
        self.retries = 0
        self._name = ""
        self._value: float | int = 0.0
        self._type = ParamType.REAL32
        self._phase = _Phase.READ
        self._tries = 0
        self._deadline = math.inf
        self.answered_read = False  # the current parameter's read was answered (the vehicle has it)

    @property
    def deadline(self) -> float:
        return self._deadline

    def start(self, wall: float) -> list[Outgoing]:
        return self._next(wall)

    def _next(self, wall: float) -> list[Outgoing]:
        if not self._todo:
            self.done = True
            self._deadline = math.inf
            return []
        self._name, self._value = self._todo.pop(0)
        self._phase = _Phase.READ
        self.answered_read = False
        self._tries = 1
        self._deadline = wall + self.retry_s
        return [ParamRequestRead(self._name)]

    def _send_set(self, wall: float) -> list[Outgoing]:
        try:
            wire = encode_param(self._value, self._type)
        except (ValueError, struct.error) as e:
            return self._fail(f"parameter {self._name}: cannot set {self._value}: {e}")
        self._deadline = wall + self.retry_s
        return [ParamSet(self._name, wire, int(self._type))]

    def _fail(self, reason: str) -> list[Outgoing]:
        self.error = reason
        self.done = True
        self._deadline = math.inf
        return []

    def handle(self, msg: Incoming, wall: float) -> list[Outgoing]:
        if self.done or not isinstance(msg, ParamValue) or msg.name != self._name:
            return []
        if self._phase is _Phase.READ:
            try:
                self._type = ParamType(msg.param_type)
            except ValueError:
                return self._fail(f"parameter {self._name}: unknown MAV_PARAM_TYPE {msg.param_type}")
            self._phase = _Phase.SET
            self.answered_read = True
            self._tries = 1
            return self._send_set(wall)
        got = decode_param(msg.value, msg.param_type)
        if param_matches(self._value, got, msg.param_type):
            log.info("param %s = %s (%s) verified", self._name, got, self._type.name)
            self.verified[self._name] = got
            return self._next(wall)
        # an older value still on its way, or the vehicle refused: retry until the attempts run out
        if self._tries >= self.attempts:
            return self._fail(f"parameter {self._name}: vehicle kept {got} (wanted {self._value})")
        self._tries += 1
        self.retries += 1
        log.warning(
            "param %s: vehicle answered %s, wanted %s; retry %d", self._name, got, self._value, self._tries
        )
        return self._send_set(wall)

    def tick(self, wall: float) -> list[Outgoing]:
        if self.done or wall < self._deadline:
            return []
        self.retries += 1
        if self._tries >= self.attempts:
            if self._phase is _Phase.READ:
                guessed = ParamType.INT32 if isinstance(self._value, int) else ParamType.REAL32
                log.warning(
                    "param %s: no answer to %d reads; setting it as %s", self._name, self._tries, guessed.name
                )
                self._type = guessed
                self._phase = _Phase.SET
                self._tries = 1
                return self._send_set(wall)
            if not self.answered_read:
                return self._fail(
                    f"PX4 did not accept parameter {self._name} (unknown to this firmware?): "
                    f"no answer to {self.attempts} reads and {self._tries} PARAM_SETs"
                )
            return self._fail(f"parameter {self._name}: no PARAM_VALUE after {self._tries} PARAM_SETs")
        self._tries += 1
        log.warning("param %s: no answer; retry %d of %d", self._name, self._tries, self.attempts)
        if self._phase is _Phase.READ:
            self._deadline = wall + self.retry_s
            return [ParamRequestRead(self._name)]
        return self._send_set(wall)
