"""Aerialist commands: CSV files with a ``timestamp,mode,x,y,z,r`` header (any column order).

``timestamp`` is in microseconds on the vehicle clock, ``mode`` an Aerialist code
(``aerialist/px4/command.py`` FlightMode, which follows PX4's commander main states plus
Aerialist's own arm/disarm/setpoint codes). ``x, y, z, r`` only matter for code 100
(sticks: x, y, r in [-1, 1], z throttle in [0, 1], 0.5 holds altitude).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from pathlib import Path

from pydantic import ValidationError

from uavtest.errors import BadInput, MissingFile
from uavtest.spec.bounds import DURATION_MAX
from uavtest.spec.models import Command, CommandAction, FlightMode, Sticks
from uavtest.spec.validation import bad_input_from
from uavtest.spec.yaml_io import check_file_size

__all__ = [
    "AERIALIST_MODES",
    "COLUMNS",
    "UNSUPPORTED_MODES",
    "command_from_aerialist",
    "parse_commands_csv",
    "read_commands_csv",
]

COLUMNS = ("timestamp", "mode", "x", "y", "z", "r")

STICKS_CODE = 100
ARM_CODE = 20
DISARM_CODE = 21

#: Aerialist mode code → flight mode it switches to.
AERIALIST_MODES: dict[int, FlightMode] = {
    0: FlightMode.MANUAL,
    1: FlightMode.ALTITUDE,
    2: FlightMode.POSITION,
    3: FlightMode.MISSION,
    4: FlightMode.HOLD,
    5: FlightMode.RETURN,
    7: FlightMode.OFFBOARD,
    10: FlightMode.TAKEOFF,
    11: FlightMode.LAND,
}

#: Aerialist codes that exist upstream but that uavtest does not fly.
UNSUPPORTED_MODES: dict[int, str] = {6: "acro", 8: "stabilized", 12: "follow-me"}

_ALLOWED_CODES = ", ".join(
    [f"{code} {mode.value}" for code, mode in AERIALIST_MODES.items()]
    + [f"{ARM_CODE} arm", f"{DISARM_CODE} disarm", f"{STICKS_CODE} sticks"]
)
_STICK_RANGE = {"x": (-1.0, 1.0), "y": (-1.0, 1.0), "z": (0.0, 1.0), "r": (-1.0, 1.0)}


def command_from_aerialist(row: Mapping[str, object], where: str, source: str) -> Command:
    """One Aerialist command (timestamp µs, mode code, x, y, z, r) as a uavtest ``Command``.

    ``where`` names the row for messages (``row 3``, ``mission.commands[2]``).
    """
    timestamp_allowed = f"microseconds on the vehicle clock, >= 0 and <= {DURATION_MAX * 1e6:.0f} (a day)"
    timestamp = _number(row.get("timestamp"), f"{where}, timestamp", source, timestamp_allowed)
    if timestamp < 0:
        raise BadInput(
            f"{where}: timestamp is negative",
            file=source,
            value=row.get("timestamp"),
            allowed=timestamp_allowed,
        )
    if timestamp > DURATION_MAX * 1e6:
        raise BadInput(
            f"{where}: timestamp out of range",
            file=source,
            value=row.get("timestamp"),
            allowed=timestamp_allowed,
        )
    code_value = _number(row.get("mode"), f"{where}, mode", source, _ALLOWED_CODES)
    if code_value != int(code_value):
        raise BadInput(
            f"{where}: mode code is not an integer",
            file=source,
            value=row.get("mode"),
            allowed=_ALLOWED_CODES,
        )
    try:
        return _command(timestamp / 1e6, int(code_value), row, where, source)
    except ValidationError as e:  # a safety net: the checks name the row and column
        raise bad_input_from(e, source=source, root=Command, prefix=where) from None


def _command(at: float, code: int, row: Mapping[str, object], where: str, source: str) -> Command:
    if code in AERIALIST_MODES:
        return Command(at=at, action=CommandAction.MODE, mode=AERIALIST_MODES[code])
    if code == ARM_CODE:
        return Command(at=at, action=CommandAction.ARM)
    if code == DISARM_CODE:
        return Command(at=at, action=CommandAction.DISARM)
    if code == STICKS_CODE:
        values: dict[str, float] = {}
        for axis, (low, high) in _STICK_RANGE.items():
            raw = row.get(axis, 0.5 if axis == "z" else 0.0)
            value = _number(raw, f"{where}, {axis}", source, f"{low:g} to {high:g}")
            if not low <= value <= high:
                raise BadInput(
                    f"{where}: stick {axis} out of range",
                    file=source,
                    value=raw,
                    allowed=f"{low:g} to {high:g}",
                )
            values[axis] = value
        return Command(at=at, action=CommandAction.STICKS, sticks=Sticks(**values))
    name = UNSUPPORTED_MODES.get(code)
    what = f"mode code {code} ({name}) is not supported" if name else f"unknown mode code {code}"
    raise BadInput(f"{where}: {what}", file=source, value=row.get("mode"), allowed=_ALLOWED_CODES)


def _number(raw: object, where: str, source: str, allowed: str) -> float:
    if isinstance(raw, bool):
        raise BadInput(f"{where} is not a number", file=source, value=raw, allowed=allowed)
    try:
        value = float(raw)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise BadInput(f"{where} is not a number", file=source, value=raw, allowed=allowed) from None
    if not math.isfinite(value):
        raise BadInput(f"{where} is not finite", file=source, value=raw, allowed=allowed)
    return value


def parse_commands_csv(text: str, source: str) -> list[Command]:
    """Commands of an Aerialist commands CSV, sorted by time (stable for equal times)."""
    reader = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    commands: list[Command] = []
    for lineno, row in enumerate(reader, start=1):
        cells = [c.strip() for c in row]
        if not cells or all(not c for c in cells):
            continue
        if header is None:
            header = [c.lower() for c in cells]
            missing = [c for c in COLUMNS if c not in header]
            unknown = [c for c in header if c not in COLUMNS]
            if missing or unknown or len(set(header)) != len(header):
                problem = (
                    f"missing column(s) {', '.join(missing)}"
                    if missing
                    else f"unknown column(s) {', '.join(unknown)}"
                    if unknown
                    else "a column is named twice"
                )
                raise BadInput(
                    f"line {lineno}: header: {problem}",
                    file=source,
                    value=",".join(row),
                    allowed="a header naming timestamp, mode, x, y, z, r once each, in any order",
                )
            continue
        if len(cells) != len(header):
            raise BadInput(
                f"row {lineno}: expected {len(header)} values, found {len(cells)}",
                file=source,
                value=",".join(row),
                allowed=",".join(header),
            )
        commands.append(
            command_from_aerialist(dict(zip(header, cells, strict=True)), f"row {lineno}", source)
        )
    if header is None:
        raise BadInput(
            "commands file is empty", file=source, allowed="a header timestamp,mode,x,y,z,r and rows"
        )
    return sorted(commands, key=lambda c: c.at)


def read_commands_csv(path: Path) -> list[Command]:
    """The I/O edge of ``parse_commands_csv``; a ULog is refused (commands from logs are not supported)."""
    if path.suffix.lower() == ".ulg":
        raise BadInput(
            "commands from a flight log are not supported",
            file=str(path),
            allowed="an Aerialist commands CSV",
        )
    check_file_size(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise MissingFile(str(path)) from None
    except (OSError, UnicodeDecodeError) as e:
        raise BadInput(f"cannot read commands file: {e}", file=str(path)) from None
    return parse_commands_csv(text, str(path))
