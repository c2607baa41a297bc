"""Aerialist test YAML (and the SBFT UAV competition's) → a native UavTest document.

Both generations of keys are read: old ``drone`` / ``test`` and new ``robot`` / ``mission``
(as ``aerialist/px4/aerialist_test.py`` does). Paths inside are relative to the upstream
repository root, so they are searched from the test file's folder upwards. Referenced files
are resolved first, so a test naming a missing file fails on that path before anything else.

Mapping (upstream → uavtest):
- ``robot.params_file`` / ``robot.params`` → ``vehicle.params`` (inline params win);
- ``robot.mission_file`` → ``mission.planFile`` (the loader inlines it), its ``plannedHomePosition``
  → ``world.home`` unless ``simulation.home_position`` is given;
- ``robot.port`` is ignored: uavtest always talks to the vehicle over its own link;
- ``simulation.simulator`` ros / gazebo / jmavsim → ``vehicle.simulator: builtin`` (a notice is
  logged); ``ros`` (PX4 with PX4-Avoidance's local planner, the UAV Testing Competition's system
  under test) also → ``vehicle.avoidance: local-planner``; ``speed``, ``headless``, ``world`` are
  ignored (the engine decides);
- ``simulation.obstacles``: objects (``size``/``position``, yaw as ``r`` or ``angle``) or flat
  lists of 7 numbers ``l, w, h, x, y, z, r`` per box; ``simulation.home_position: [lat, lon, alt]``;
  ``simulation.wind`` (Gazebo wind plugin fields, direction an ENU vector) → ``world.wind``;
  ``simulation.timeout`` → ``timeout``;
- ``mission.commands_file`` / ``mission.commands`` → ``commands``; ``mission.waypoints``
  (x North, y East, z up) → ``mission.waypoints`` (z Down);
- ``assertion.log_file`` → ``assertions.similarity`` (DTW against the reference flight, threshold
  ``AERIALIST_SIMILARITY_THRESHOLD``);
- ``agent.count`` → ``replicas``; ``engine``, ``path``, ``id`` are ignored.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from uavtest.errors import BadInput
from uavtest.spec.bounds import ALTITUDE_MAX, ALTITUDE_MIN, DURATION_MAX, LOCAL_MAX, SPEED_FACTOR_MAX
from uavtest.spec.commands_csv import command_from_aerialist, read_commands_csv
from uavtest.spec.models import API_VERSION, KIND, Obstacle, SimilarityMetric, Wind
from uavtest.spec.params_csv import PARAM_VALUE_ALLOWED, check_param_value, read_params_csv
from uavtest.spec.paths import resolve_reference
from uavtest.spec.validation import bad_input_from

__all__ = [
    "AERIALIST_SECTIONS",
    "AERIALIST_SIMILARITY_THRESHOLD",
    "dns_name",
    "from_aerialist",
    "is_aerialist",
    "upstream_simulator_notice",
]

log = logging.getLogger(__name__)

#: Largest mean DTW distance per step (metres) to the reference flight of ``assertion.log_file``.
#: PX4 flying the same plan three times from scratch differs by 0.1-0.56 m per step (PX4 SIH
#: logs in shared data); a reference recorded on another simulator or a real vehicle adds GPS and
#: estimator offsets of about a metre. 2 m allows both with margin, yet flags a flight that took
#: another route around a 5 m obstacle (Aerialist's samples), which moves it by several metres.
AERIALIST_SIMILARITY_THRESHOLD = 2.0

AERIALIST_SECTIONS: dict[str, tuple[str, ...]] = {
    "robot": ("port", "params", "params_file", "mission_file"),
    "simulation": (
        "simulator",
        "world",
        "speed",
        "headless",
        "obstacles",
        "home_position",
        "wind",
        "timeout",
        "world_file_name",
    ),
    "mission": ("commands", "commands_file", "speed", "waypoints"),
    "assertion": ("log_file", "variable"),
    "agent": ("engine", "count", "path", "id"),
}
_OLD_NAMES = {"drone": "robot", "test": "mission"}
_UPSTREAM_SIMULATORS = {"gazebo", "jmavsim", "ros"}
_WIND_KEYS = (
    "velocity_mean",
    "velocity_max",
    "velocity_variance",
    "direction",
    "direction_variance",
    "gust_start",
    "gust_duration",
    "gust_velocity_mean",
    "gust_velocity_max",
    "gust_velocity_variance",
    "gust_direction",
    "gust_direction_variance",
)


def upstream_simulator_notice(simulator: str) -> str:
    """How uavtest flies an upstream ``simulation.simulator`` (gazebo, jmavsim, ros)."""
    notice = "uavtest flies it with its built-in simulator (uavtest sitl)"
    if simulator == "ros":
        notice += (
            " and PX4-Avoidance's local planner (vehicle.avoidance: local-planner, COM_OBS_AVOID 1),"
            " the competition's system under test"
        )
    return notice


def is_aerialist(doc: Mapping[str, Any]) -> bool:
    """True for a document with Aerialist's top-level sections and no apiVersion/kind."""
    if "apiVersion" in doc or "kind" in doc or "spec" in doc:
        return False
    return any(k in doc for k in (*AERIALIST_SECTIONS, *_OLD_NAMES))


def dns_name(stem: str) -> str:
    """A Kubernetes object name (DNS-1123 label) made from a file name: lowercased, '-' for the rest."""
    name = re.sub(r"[^a-z0-9-]+", "-", stem.lower())
    name = re.sub(r"-{2,}", "-", name).strip("-")[:63].strip("-")
    return name or "test"


def _sections(doc: Mapping[str, Any], source: str) -> dict[str, dict[str, Any]]:
    allowed_top = ", ".join([*AERIALIST_SECTIONS, *_OLD_NAMES])
    sections: dict[str, dict[str, Any]] = {}
    written: dict[str, str] = {}
    for key, body in doc.items():
        name = _OLD_NAMES.get(str(key), str(key))
        if name not in AERIALIST_SECTIONS:
            raise BadInput(f"unknown section '{key}'", file=source, field=str(key), allowed=allowed_top)
        if name in sections:
            raise BadInput(
                f"'{key}' and '{written[name]}' are the same section; give one",
                file=source,
                field=str(key),
                allowed=f"{name} (new) or {written[name]} (old), not both",
            )
        if body is None:
            body = {}
        if not isinstance(body, Mapping):
            raise BadInput(
                "a section must be a mapping",
                file=source,
                field=str(key),
                value=body,
                allowed=f"a mapping with {', '.join(AERIALIST_SECTIONS[name])}",
            )
        for field in body:
            if field not in AERIALIST_SECTIONS[name]:
                raise BadInput(
                    f"unknown field '{field}'",
                    file=source,
                    field=f"{key}.{field}",
                    allowed=", ".join(AERIALIST_SECTIONS[name]),
                )
        sections[name] = dict(body)
        written[name] = str(key)
    return sections


def _is_number(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def from_aerialist(doc: Mapping[str, Any], source: str, test_file: Path | None) -> dict[str, Any]:
    """The native UavTest document (a plain dict, not yet validated) of an Aerialist test."""
    sections = _sections(doc, source)
    key = {name: next((k for k in doc if _OLD_NAMES.get(str(k), str(k)) == name), name) for name in sections}
    robot = sections.get("robot", {})
    simulation = sections.get("simulation", {})
    mission = sections.get("mission", {})
    assertion = sections.get("assertion", {})
    agent = sections.get("agent", {})

    # referenced files first: a missing file is the first thing a user has to fix
    def ref(section: str, field: str) -> Path | None:
        body = sections.get(section, {})
        if body.get(field) is None:
            return None
        return resolve_reference(str(body[field]), test_file, field=f"{key[section]}.{field}")

    params_path = ref("robot", "params_file")
    plan_path = ref("robot", "mission_file")
    commands_path = ref("mission", "commands_file")
    log_path = ref("assertion", "log_file")

    spec: dict[str, Any] = {}
    vehicle: dict[str, Any] = {}
    world: dict[str, Any] = {}

    # vehicle
    params: dict[str, Any] = read_params_csv(params_path) if params_path else {}
    inline = robot.get("params")
    if inline is not None:
        if not isinstance(inline, Mapping):
            raise BadInput(
                "params must be a mapping",
                file=source,
                field=f"{key['robot']}.params",
                value=inline,
                allowed="NAME: number",
            )
        for name, value in inline.items():
            if not check_param_value(value):
                raise BadInput(
                    "parameter value is not a finite number in PX4's range",
                    file=source,
                    field=f"{key['robot']}.params.{name}",
                    value=value,
                    allowed=PARAM_VALUE_ALLOWED,
                )
        params.update(inline)
    if params:
        vehicle["params"] = params
    simulator = simulation.get("simulator")
    if simulator is not None:
        if str(simulator) in _UPSTREAM_SIMULATORS:
            log.info(
                "%s: simulation.simulator %s: %s",
                source,
                simulator,
                upstream_simulator_notice(str(simulator)),
            )
            vehicle["simulator"] = "builtin"
            if str(simulator) == "ros":  # Aerialist's ros: PX4 + PX4-Avoidance, the competition's SUT
                vehicle["avoidance"] = "local-planner"
        elif str(simulator) in ("builtin", "px4"):
            vehicle["simulator"] = str(simulator)
        else:
            raise BadInput(
                "unknown simulator",
                file=source,
                field="simulation.simulator",
                value=simulator,
                allowed="gazebo, jmavsim, ros (all flown by the built-in simulator), builtin, px4",
            )
    if vehicle:
        spec["vehicle"] = vehicle

    # mission: the plan is read (and its home taken) by the loader, naming the plan file in errors
    if plan_path is not None:
        spec["mission"] = {"planFile": str(plan_path)}
    waypoints = mission.get("waypoints")
    if waypoints is not None:
        spec["mission"] = {
            **spec.get("mission", {}),
            "waypoints": _waypoints(waypoints, source, key["mission"]),
        }

    # world
    if simulation.get("home_position") is not None:
        world["home"] = _home(simulation["home_position"], source)
    obstacles = simulation.get("obstacles")
    if obstacles is not None:
        world["obstacles"] = _obstacles(obstacles, source)
    if simulation.get("wind") is not None:
        world["wind"] = _wind(simulation["wind"], source)
    if world:
        spec["world"] = world
    timeout = simulation.get("timeout")
    if timeout is not None and not (_is_number(timeout) and timeout <= 0):  # upstream: -1 means none
        if not _is_number(timeout) or timeout > DURATION_MAX:
            raise BadInput(
                "timeout is not a number in range",
                file=source,
                field="simulation.timeout",
                value=timeout,
                allowed=f"seconds > 0 and <= {DURATION_MAX:g} (or -1 for the default)",
            )
        spec["timeout"] = float(timeout)
    for section, field in (("simulation", "speed"), ("mission", "speed")):
        factor = sections.get(section, {}).get(field)
        if factor is not None and not (_is_number(factor) and 0 < factor <= SPEED_FACTOR_MAX):
            raise BadInput(
                "speed is not a number in range (it is ignored, but must make sense)",
                file=source,
                field=f"{key.get(section, section)}.{field}",
                value=factor,
                allowed=f"a number > 0 and <= {SPEED_FACTOR_MAX:g}",
            )

    # commands
    commands = [c.dump() for c in read_commands_csv(commands_path)] if commands_path else []
    inline_commands = mission.get("commands")
    if inline_commands is not None:
        if not isinstance(inline_commands, list):
            raise BadInput(
                "commands must be a list",
                file=source,
                field=f"{key['mission']}.commands",
                value=inline_commands,
                allowed="a list of {timestamp, mode, x, y, z, r}",
            )
        for i, row in enumerate(inline_commands):
            where = f"{key['mission']}.commands[{i}]"
            if not isinstance(row, Mapping):
                raise BadInput(
                    "a command must be a mapping",
                    file=source,
                    field=where,
                    value=row,
                    allowed="timestamp, mode, x, y, z, r",
                )
            commands.append(command_from_aerialist(row, where, source).dump())
    if commands:
        spec["commands"] = sorted(commands, key=lambda c: c["at"])

    # assertions
    variable = assertion.get("variable")
    if variable is not None and variable != "trajectory":
        raise BadInput(
            "unsupported assertion variable",
            file=source,
            field="assertion.variable",
            value=variable,
            allowed="trajectory",
        )
    if log_path is not None:
        spec["assertions"] = {
            "similarity": {
                "metric": SimilarityMetric.DTW.value,
                "threshold": AERIALIST_SIMILARITY_THRESHOLD,
                "logFile": str(log_path),
            }
        }

    # replicas
    count = agent.get("count")
    if count is not None:
        if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= 1000:
            raise BadInput(
                "agent count out of range",
                file=source,
                field="agent.count",
                value=count,
                allowed="an integer from 1 to 1000",
            )
        spec["replicas"] = count

    if "mission" not in spec and "commands" not in spec:
        section = key.get("mission", "mission")
        raise BadInput(
            "a test needs a mission or commands (or both)",
            file=source,
            field=section,
            allowed=f"{key.get('robot', 'robot')}.mission_file, or {section}.commands_file, "
            f"{section}.commands or {section}.waypoints",
        )
    stem = test_file.stem if test_file is not None else Path(source).stem
    return {"apiVersion": API_VERSION, "kind": KIND, "metadata": {"name": dns_name(stem)}, "spec": spec}


def _home(raw: Any, source: str) -> dict[str, float]:
    if not (isinstance(raw, list) and len(raw) == 3 and all(_is_number(v) for v in raw)):
        raise BadInput(
            "home position must be three numbers",
            file=source,
            field="simulation.home_position",
            value=raw,
            allowed="[lat, lon, alt]: degrees, degrees, metres AMSL",
        )
    lat, lon, alt = (float(v) for v in raw)
    if not (-90 <= lat <= 90 and -180 <= lon <= 180 and ALTITUDE_MIN <= alt <= ALTITUDE_MAX):
        raise BadInput(
            "home position out of range",
            file=source,
            field="simulation.home_position",
            value=raw,
            allowed=f"lat -90..90, lon -180..180, alt {ALTITUDE_MIN:g}..{ALTITUDE_MAX:g} m AMSL",
        )
    return {"lat": lat, "lon": lon, "alt": alt}


def _validated_obstacle(data: dict[str, Any], source: str, field: str) -> dict[str, Any]:
    try:
        return Obstacle.model_validate(data).dump()
    except ValidationError as e:
        raise bad_input_from(e, source=source, root=Obstacle, prefix=field) from None


def _obstacles(raw: Any, source: str) -> list[dict[str, Any]]:
    field = "simulation.obstacles"
    shape = "objects {size: {l, w, h}, position: {x, y, z, r}} or flat lists of 7 numbers l, w, h, x, y, z, r"
    if not isinstance(raw, list):
        raise BadInput("obstacles must be a list", file=source, field=field, value=raw, allowed=shape)
    if raw and all(isinstance(o, Mapping) for o in raw):
        result = []
        for i, obstacle in enumerate(raw):
            data = dict(obstacle)
            where = f"{field}[{i}]"
            kind = str(data.pop("shape", "box")).lower()
            if kind != "box":
                raise BadInput(
                    "only box obstacles are supported",
                    file=source,
                    field=f"{where}.shape",
                    value=kind,
                    allowed="box",
                )
            position = data.get("position")
            if isinstance(position, Mapping) and "angle" in position:
                position = dict(position)
                if "r" in position:
                    raise BadInput(
                        "give the yaw as r or angle, not both",
                        file=source,
                        field=f"{where}.position.angle",
                        value=position["angle"],
                        allowed="r or angle",
                    )
                position["r"] = position.pop("angle")
                data["position"] = position
            result.append(_validated_obstacle(data, source, where))
        return result
    rows: list[list[Any]]
    if raw and all(isinstance(o, list) for o in raw):
        rows = raw
    else:
        if len(raw) % 7:
            raise BadInput(
                f"a flat obstacle list needs 7 numbers per box, found {len(raw)}",
                file=source,
                field=field,
                value=raw,
                allowed=shape,
            )
        rows = [raw[i : i + 7] for i in range(0, len(raw), 7)]
    result = []
    for i, row in enumerate(rows):
        where = f"{field}[{i}]"
        if len(row) != 7 or not all(_is_number(v) for v in row):
            raise BadInput(
                "an obstacle needs 7 numbers",
                file=source,
                field=where,
                value=row,
                allowed="l, w, h, x, y, z, r (metres, degrees)",
            )
        l, w, h, x, y, z, r = row  # noqa: E741
        data = {"size": {"l": l, "w": w, "h": h}, "position": {"x": x, "y": y, "z": z, "r": r}}
        result.append(_validated_obstacle(data, source, where))
    return result


def _wind(raw: Any, source: str) -> dict[str, Any]:
    field = "simulation.wind"
    if not isinstance(raw, Mapping):
        raise BadInput(
            "wind must be a mapping", file=source, field=field, value=raw, allowed=", ".join(_WIND_KEYS)
        )
    for k in raw:
        if k not in _WIND_KEYS:
            raise BadInput(
                f"unknown field '{k}'", file=source, field=f"{field}.{k}", allowed=", ".join(_WIND_KEYS)
            )
    for k, v in raw.items():
        if k not in ("direction", "gust_direction") and v is not None and not _is_number(v):
            raise BadInput("not a number", file=source, field=f"{field}.{k}", value=v, allowed="a number")
    mean = float(raw.get("velocity_mean") or 0.0)
    peaks = [float(raw[k]) for k in ("velocity_max", "gust_velocity_max") if raw.get(k) is not None]
    data: dict[str, Any] = {"meanSpeed": mean, "gusts": bool(peaks) and max(peaks) > mean}
    if peaks:
        data["maxSpeed"] = max(peaks)
    direction = raw.get("direction")
    if direction is not None:
        if not (
            isinstance(direction, list) and len(direction) == 3 and all(_is_number(v) for v in direction)
        ):
            raise BadInput(
                "direction must be a vector",
                file=source,
                field=f"{field}.direction",
                value=direction,
                allowed="[x East, y North, z Up] (Gazebo world frame)",
            )
        east, north = float(direction[0]), float(direction[1])
        data["direction"] = round(math.degrees(math.atan2(east, north)) % 360.0, 6) if east or north else 0.0
    try:
        return Wind.model_validate(data).dump()
    except ValidationError as e:
        raise bad_input_from(e, source=source, root=Wind, prefix=field) from None


def _waypoints(raw: Any, source: str, section: str) -> list[dict[str, Any]]:
    field = f"{section}.waypoints"
    if not isinstance(raw, list):
        raise BadInput(
            "waypoints must be a list", file=source, field=field, value=raw, allowed="a list of {x, y, z}"
        )
    result = []
    for i, wp in enumerate(raw):
        where = f"{field}[{i}]"
        if not isinstance(wp, Mapping) or not all(_is_number(wp.get(a)) for a in ("x", "y")):
            raise BadInput(
                "a waypoint needs numbers x and y",
                file=source,
                field=where,
                value=wp,
                allowed="{x North, y East, z up, r yaw} in metres and degrees",
            )
        for axis in ("x", "y"):
            if abs(wp[axis]) > LOCAL_MAX:
                raise BadInput(
                    "waypoint out of range",
                    file=source,
                    field=f"{where}.{axis}",
                    value=wp[axis],
                    allowed=f"metres from home >= {-LOCAL_MAX:g} and <= {LOCAL_MAX:g}",
                )
        up = wp.get("z", 0.0)
        if not _is_number(up) or not 0 <= up <= ALTITUDE_MAX:
            raise BadInput(
                "waypoint height must be a number >= 0",
                file=source,
                field=f"{where}.z",
                value=up,
                allowed=f"metres above home, >= 0 and <= {ALTITUDE_MAX:g}",
            )
        result.append({"x": float(wp["x"]), "y": float(wp["y"]), "z": -float(up)})
    return result
