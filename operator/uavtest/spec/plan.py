"""QGroundControl ``.plan`` documents → mission items.

Supported simple items (MAV_CMD numbers): takeoff 22, waypoint 16, land 21, return 20,
loiter-time 19, change-speed 178, land-start 189. Command 530 (SET_CAMERA_MODE, which QGC puts first in
every plan drawn for a camera-less vehicle) is skipped with a warning. Anything else, and
every complex item (survey, corridor scan, structure scan), is refused with a message naming
the command and the item.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from uavtest.errors import BadInput, MissingFile
from uavtest.spec.bounds import ALTITUDE_MAX, ALTITUDE_MIN, DURATION_MAX, MAX_DEPTH, SPEED_MAX
from uavtest.spec.models import MISSION_ITEM_CMD, Home, MissionItem, MissionItemKind
from uavtest.spec.validation import bad_input_from
from uavtest.spec.yaml_io import check_file_size

__all__ = ["IGNORED_COMMANDS", "parse_plan", "plan_home", "read_plan"]

log = logging.getLogger(__name__)

_KIND_OF_CMD = {cmd: kind for kind, cmd in MISSION_ITEM_CMD.items()}

#: commands skipped with a warning: MAV_CMD_SET_CAMERA_MODE
IGNORED_COMMANDS = {530: "SET_CAMERA_MODE"}

_ALLOWED = ", ".join(f"{cmd} {kind.value}" for kind, cmd in MISSION_ITEM_CMD.items()) + " (530 is ignored)"

# MAV_FRAME values
_RELATIVE_FRAMES = {3, 6}  # GLOBAL_RELATIVE_ALT(_INT)
_AMSL_FRAMES = {0, 5}  # GLOBAL(_INT)
_MISSION_FRAME = 2  # MAV_FRAME_MISSION: no position
_POSITIONAL = {
    MissionItemKind.TAKEOFF,
    MissionItemKind.WAYPOINT,
    MissionItemKind.LAND,
    MissionItemKind.LOITER_TIME,
}


def read_plan(path: Path) -> dict[str, Any]:
    """The JSON document of a ``.plan`` file (I/O edge); ``BadInput`` with line/column on bad JSON."""
    check_file_size(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise MissingFile(str(path)) from None
    except (OSError, UnicodeDecodeError) as e:
        raise BadInput(f"cannot read plan file: {e}", file=str(path)) from None
    try:
        doc = json.loads(text, parse_constant=_refuse_constant)
    except _NotJsonNumber as e:
        raise BadInput(
            f"{e.args[0]} is not a JSON number",
            file=str(path),
            value=e.args[0],
            allowed="finite numbers (QGroundControl writes null for an unset value)",
        ) from None
    except RecursionError:
        raise _too_deep(str(path)) from None
    except json.JSONDecodeError as e:
        raise BadInput(
            f"not valid JSON at line {e.lineno}, column {e.colno}: {e.msg}",
            file=str(path),
            allowed="a QGroundControl .plan (JSON)",
        ) from None
    if _depth(doc) > MAX_DEPTH:
        raise _too_deep(str(path))
    if not isinstance(doc, dict):
        raise BadInput(
            "a .plan must be a JSON object",
            file=str(path),
            value=type(doc).__name__,
            allowed="a QGroundControl .plan (JSON object)",
        )
    return doc


class _NotJsonNumber(ValueError):
    """NaN, Infinity or -Infinity in a JSON text (Python's json module accepts them)."""


def _refuse_constant(name: str) -> Any:
    raise _NotJsonNumber(name)


def _too_deep(source: str) -> BadInput:
    return BadInput(
        "the plan is nested too deeply",
        file=source,
        allowed=f"at most {MAX_DEPTH} levels of nested objects and lists",
    )


def _depth(doc: Any) -> int:
    """How deeply ``doc`` nests (without recursion: a parsed document may be deeper than Python's stack)."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(doc, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        if deepest > MAX_DEPTH:
            break
        children = node.values() if isinstance(node, dict) else node if isinstance(node, list) else ()
        stack.extend((child, depth + 1) for child in children if isinstance(child, dict | list))
    return deepest


def _items(doc: Mapping[str, Any], source: str) -> list[Any]:
    if doc.get("fileType", "Plan") != "Plan":
        raise BadInput(
            "not a QGroundControl plan",
            file=source,
            field="fileType",
            value=doc.get("fileType"),
            allowed="Plan",
        )
    mission = doc.get("mission")
    if not isinstance(mission, Mapping):
        raise BadInput(
            "a plan needs a mission object",
            file=source,
            field="mission",
            value=mission,
            allowed="an object with items",
        )
    items = mission.get("items")
    if not isinstance(items, list):
        raise BadInput(
            "a plan's mission needs a list of items",
            file=source,
            field="mission.items",
            value=items,
            allowed="a list of mission items",
        )
    return items


def plan_home(doc: Mapping[str, Any], source: str, *, prefix: str = "") -> Home | None:
    """The plan's ``plannedHomePosition`` (lat, lon, AMSL alt), or None when it has none."""
    try:
        return _plan_home(doc, source)
    except BadInput as e:
        raise _prefixed(e, prefix) from None


def _prefixed(e: BadInput, prefix: str) -> BadInput:
    if not prefix:
        return e
    field = f"{prefix}.{e.field}" if e.field else prefix
    return BadInput(e.reason, file=e.file, field=field, value=e.value, allowed=e.allowed)


def _plan_home(doc: Mapping[str, Any], source: str) -> Home | None:
    mission = doc.get("mission")
    raw = mission.get("plannedHomePosition") if isinstance(mission, Mapping) else None
    if raw is None:
        return None
    field = "mission.plannedHomePosition"
    if not (isinstance(raw, list) and len(raw) == 3 and all(_is_number(v) for v in raw)):
        raise BadInput("bad home position", file=source, field=field, value=raw, allowed="[lat, lon, alt]")
    lat, lon, alt = (float(v) for v in raw)
    if not (-90 <= lat <= 90 and -180 <= lon <= 180 and ALTITUDE_MIN <= alt <= ALTITUDE_MAX):
        raise BadInput(
            "home position out of range",
            file=source,
            field=field,
            value=raw,
            allowed=f"lat -90..90, lon -180..180, alt {ALTITUDE_MIN:g}..{ALTITUDE_MAX:g} m AMSL",
        )
    return Home(lat=lat, lon=lon, alt=alt)


def _is_number(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def parse_plan(
    doc: Mapping[str, Any], source: str, *, home_alt: float, warn: bool = True, prefix: str = ""
) -> list[MissionItem]:
    """The plan's items in order, in global coordinates with altitude relative to home.

    ``home_alt`` (AMSL metres) converts items given in an AMSL frame. No takeoff is added
    here (``uavtest.spec.mission.mission_items`` does that). ``warn=False`` skips the
    warnings about ignored items (for a plan that was checked once already). ``prefix`` is put
    before field paths in messages (``spec.mission.plan`` for a plan inline in a test).
    """
    try:
        return _parse_plan(doc, source, home_alt=home_alt, warn=warn, prefix=prefix)
    except BadInput as e:
        raise _prefixed(e, prefix) from None


def _parse_plan(
    doc: Mapping[str, Any], source: str, *, home_alt: float, warn: bool, prefix: str
) -> list[MissionItem]:
    result: list[MissionItem] = []
    for index, item in enumerate(_items(doc, source)):
        field = f"mission.items[{index}]"
        if not isinstance(item, Mapping):
            raise BadInput("a mission item must be an object", file=source, field=field, value=item)
        kind_name = item.get("type", "SimpleItem")
        if kind_name == "ComplexItem":
            complex_type = item.get("complexItemType", "unknown")
            raise BadInput(
                f"complex item '{complex_type}' is not supported",
                file=source,
                field=f"{field}.complexItemType",
                value=complex_type,
                allowed=f"simple items: {_ALLOWED}",
            )
        if kind_name != "SimpleItem":
            raise BadInput(
                "unknown item type", file=source, field=f"{field}.type", value=kind_name, allowed="SimpleItem"
            )
        command = item.get("command")
        if command in IGNORED_COMMANDS:
            if warn:
                where = f"{prefix}.{field}" if prefix else field
                log.warning(
                    "%s: %s: command %s (%s) ignored", source, where, command, IGNORED_COMMANDS[command]
                )
            continue
        if not isinstance(command, int) or command not in _KIND_OF_CMD:
            raise BadInput(
                f"command {command} is not supported",
                file=source,
                field=f"{field}.command",
                value=command,
                allowed=_ALLOWED,
            )
        result.append(_item(_KIND_OF_CMD[command], item, field, source, home_alt))
    return result


def _param(params: list[Any], i: int) -> float | None:
    v = params[i] if i < len(params) else None
    return float(v) if _is_number(v) else None


def _item(
    kind: MissionItemKind, item: Mapping[str, Any], field: str, source: str, home_alt: float
) -> MissionItem:
    params = item.get("params", [])
    if not isinstance(params, list) or len(params) > 7 or not all(p is None or _is_number(p) for p in params):
        raise BadInput(
            "bad params",
            file=source,
            field=f"{field}.params",
            value=params,
            allowed="a list of 7 numbers or nulls",
        )
    frame = item.get("frame", 3)
    if kind == MissionItemKind.CHANGE_SPEED:
        speed = _param(params, 1)
        if speed is None or not 0 < speed <= SPEED_MAX:
            raise BadInput(
                f"change-speed needs a speed > 0 and <= {SPEED_MAX:g} m/s in params[1]",
                file=source,
                field=f"{field}.params[1]",
                value=speed,
                allowed=f"a ground speed > 0 and <= {SPEED_MAX:g} m/s",
            )
        return MissionItem(kind=kind, speed=speed)
    if kind in (MissionItemKind.RETURN, MissionItemKind.LAND_START):
        return MissionItem(kind=kind)  # a land start's optional position is not used by PX4's jump
    lat, lon, alt = _param(params, 4), _param(params, 5), _param(params, 6)
    if frame in _AMSL_FRAMES and alt is not None:
        alt -= home_alt
    elif frame not in _RELATIVE_FRAMES and not (frame == _MISSION_FRAME and lat is None and lon is None):
        raise BadInput(
            f"frame {frame} is not supported",
            file=source,
            field=f"{field}.frame",
            value=frame,
            allowed="3 or 6 (altitude relative to home), 0 or 5 (AMSL)",
        )
    if (lat is None) != (lon is None):
        raise BadInput(
            "give both latitude and longitude or neither",
            file=source,
            field=f"{field}.params",
            value=params,
            allowed="params[4] latitude and params[5] longitude, both or null",
        )
    if lat is not None and lon is not None and not (-90 <= lat <= 90 and -180 <= lon <= 180):
        raise BadInput(
            "position out of range",
            file=source,
            field=f"{field}.params",
            value=[lat, lon],
            allowed="latitude -90..90, longitude -180..180",
        )
    hold = 0.0
    if kind in (MissionItemKind.WAYPOINT, MissionItemKind.LOITER_TIME):
        hold = _param(params, 0) or 0.0
        if not 0 <= hold <= DURATION_MAX:
            raise BadInput(
                "hold time out of range",
                file=source,
                field=f"{field}.params[0]",
                value=hold,
                allowed=f"seconds >= 0 and <= {DURATION_MAX:g}",
            )
    if kind in _POSITIONAL and kind != MissionItemKind.LAND and alt is None:
        raise BadInput(
            "the item needs an altitude in params[6]",
            file=source,
            field=f"{field}.params[6]",
            value=None,
            allowed="metres",
        )
    if alt is not None and not ALTITUDE_MIN <= alt <= ALTITUDE_MAX:
        raise BadInput(
            "altitude out of range",
            file=source,
            field=f"{field}.params[6]",
            value=alt,
            allowed=f"metres above home >= {ALTITUDE_MIN:g} and <= {ALTITUDE_MAX:g}",
        )
    # param4 of takeoff, waypoint, loiter-time and land is the heading in degrees (PX4's
    # mavlink_mission.cpp reads it as yaw for each); QGC writes null for "no heading"
    yaw = _param(params, 3)
    if yaw is not None and not -360 <= yaw <= 360:
        raise BadInput(
            "heading out of range",
            file=source,
            field=f"{field}.params[3]",
            value=yaw,
            allowed="degrees clockwise from North, -360..360, or null (PX4's MPC_YAW_MODE)",
        )
    try:
        return MissionItem(kind=kind, lat=lat, lon=lon, alt=alt, hold=hold, yaw=yaw)
    except ValidationError as e:  # a safety net: the checks above name the params index
        raise bad_input_from(e, source=source, root=MissionItem, prefix=field) from None
