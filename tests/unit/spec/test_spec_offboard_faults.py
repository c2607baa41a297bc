"""Offboard setpoints, goto, orbit, land_start, yaw and faults: the model rules, good and bad input
through ``uavtest validate`` (exit 0 / exit 2 naming the field, the value and what is allowed)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from uavtest.spec.models import Command, Fault, Goto, Orbit, Setpoint, UavTestSpec

ARM = {"at": 1, "action": "arm"}


def _doc(commands: list[dict[str, Any]], **spec: Any) -> dict[str, Any]:
    return {
        "apiVersion": "uavtest.io/v1alpha1",
        "kind": "UavTest",
        "metadata": {"name": "offboard"},
        "spec": {"commands": [ARM, *commands], **spec},
    }


def sp(at: float = 2, **setpoint: Any) -> dict[str, Any]:
    return {"at": at, "action": "setpoint", "setpoint": setpoint}


GOOD: list[tuple[str, dict[str, Any]]] = [
    ("position", _doc([sp(x=0, y=0, z=-5)])),
    ("position-yaw", _doc([sp(x=5, y=-5, z=-5, yaw=90)])),
    ("velocity-yawrate", _doc([sp(vx=1, vy=0, vz=-0.5, yawRate=-30)])),
    ("position-and-velocity", _doc([sp(x=1, y=2, z=-3, vx=1, vy=1, vz=0)])),
    ("mixed-axes", _doc([sp(x=1, y=2, vz=-1)])),  # z by velocity: PX4 accepts
    ("global", _doc([sp(frame="global", lat=47.3978, lon=8.5456, alt=10, yaw=0)])),
    ("global-velocity", _doc([sp(frame="global", vx=1, vy=0, vz=0)])),
    (
        "goto-local",
        _doc([{"at": 3, "action": "goto", "goto": {"x": 10, "y": 5, "z": -8, "speed": 3, "yaw": 45}}]),
    ),
    ("goto-global", _doc([{"at": 3, "action": "goto", "goto": {"lat": 47.398, "lon": 8.546, "alt": 12}}])),
    (
        "orbit",
        _doc(
            [{"at": 3, "action": "orbit", "orbit": {"radius": 10, "velocity": 2, "x": 0, "y": 0, "z": -10}}]
        ),
    ),
    ("orbit-here", _doc([{"at": 3, "action": "orbit", "orbit": {"radius": 5, "clockwise": False}}])),
    ("land-start", _doc([{"at": 3, "action": "land_start"}])),
    (
        "yaw",
        _doc([{"at": 3, "action": "yaw", "yaw": {"heading": 270, "rate": 20, "direction": "clockwise"}}]),
    ),
    ("yaw-relative", _doc([{"at": 3, "action": "yaw", "yaw": {"heading": -45, "relative": True}}])),
    ("fault", _doc([], faults=[{"at": 20, "unit": "gps", "type": "off"}])),
    ("fault-bare-off", _doc([], faults=[{"at": 20, "unit": "gps", "type": False}])),  # YAML 1.1: off is false
    ("fault-motor", _doc([], faults=[{"at": 20, "unit": "motor", "type": "off", "instance": 1}])),
    (
        "faults-all-units",
        _doc(
            [],
            faults=[
                {"at": 5, "unit": u, "type": "ok"}
                for u in (
                    "gyro",
                    "accel",
                    "mag",
                    "baro",
                    "gps",
                    "optical_flow",
                    "vio",
                    "distance_sensor",
                    "airspeed",
                    "battery",
                    "motor",
                    "servo",
                    "avoidance",
                    "rc_signal",
                    "mavlink_signal",
                )
            ],
        ),
    ),
    (
        "fault-with-sys-failure-en",
        _doc([], faults=[{"at": 5, "unit": "gps", "type": "off"}], vehicle={"params": {"SYS_FAILURE_EN": 1}}),
    ),
]

# (id, document, substrings of the message)
BAD: list[tuple[str, dict[str, Any], list[str]]] = [
    (
        "setpoint-missing",
        _doc([{"at": 2, "action": "setpoint"}]),
        ["spec.commands[1]", "action setpoint needs field 'setpoint'"],
    ),
    ("setpoint-empty", _doc([sp()]), ["spec.commands[1].setpoint", "missing: x or vx; y or vy; z or vz"]),
    ("setpoint-axis-missing", _doc([sp(x=1, y=2)]), ["spec.commands[1].setpoint", "missing: z or vz"]),
    (
        "setpoint-yaw-only",
        _doc([sp(yaw=90)]),
        ["spec.commands[1].setpoint", "position or a velocity on every axis"],
    ),
    (
        "setpoint-yaw-and-rate",
        _doc([sp(x=0, y=0, z=-5, yaw=1, yawRate=5)]),
        ["setpoint", "give yaw or yawRate, not both"],
    ),
    (
        "setpoint-nan",
        _doc([sp(x=0, y=0, z=float("nan"))]),
        ["spec.commands[1].setpoint.z", "not a finite number", "allowed: a number >= -10000 and <= 0"],
    ),
    ("setpoint-below-ground", _doc([sp(x=0, y=0, z=5)]), ["spec.commands[1].setpoint.z", "(got 5)", "<= 0"]),
    (
        "setpoint-too-fast",
        _doc([sp(vx=80, vy=0, vz=0)]),
        ["spec.commands[1].setpoint.vx", "(got 80)", "<= 50"],
    ),
    (
        "setpoint-yawrate-range",
        _doc([sp(vx=0, vy=0, vz=0, yawRate=400)]),
        ["setpoint.yawRate", "(got 400)", "<= 360"],
    ),
    ("setpoint-unknown-field", _doc([sp(x=0, y=0, z=-5, w=1)]), ["spec.commands[1].setpoint.w"]),
    (
        "setpoint-bad-frame",
        _doc([sp(frame="body", x=0, y=0, z=-5)]),
        ["setpoint.frame", "(got 'body')", "'local' or 'global'"],
    ),
    (
        "setpoint-global-partial",
        _doc([sp(frame="global", lat=47.3, lon=8.5)]),
        ["frame global needs all of lat, lon, alt"],
    ),
    (
        "setpoint-global-xyz",
        _doc([sp(frame="global", x=1, y=1, z=-1)]),
        ["frame global takes lat, lon, alt, not x, y, z"],
    ),
    (
        "setpoint-local-lat",
        _doc([sp(lat=47.3, lon=8.5, alt=5)]),
        ["lat, lon, alt only go with frame: global"],
    ),
    (
        "setpoint-with-mode",
        _doc([{"at": 2, "action": "mode", "mode": "offboard", "setpoint": {"x": 0, "y": 0, "z": -5}}]),
        ["field 'setpoint' only goes with action setpoint"],
    ),
    (
        "goto-partial",
        _doc([{"at": 3, "action": "goto", "goto": {"x": 10, "y": 5}}]),
        ["spec.commands[1].goto", "give all of x, y, z or all of lat, lon, alt (got x, y)"],
    ),
    (
        "goto-mixed",
        _doc([{"at": 3, "action": "goto", "goto": {"x": 10, "y": 5, "z": -5, "lat": 47.0}}]),
        ["not both"],
    ),
    (
        "goto-speed-zero",
        _doc([{"at": 3, "action": "goto", "goto": {"x": 1, "y": 1, "z": -5, "speed": 0}}]),
        ["goto.speed", "(got 0)", "> 0"],
    ),
    (
        "goto-bad-lat",
        _doc([{"at": 3, "action": "goto", "goto": {"lat": 95, "lon": 8, "alt": 5}}]),
        ["goto.lat", "(got 95)", "<= 90"],
    ),
    ("orbit-no-radius", _doc([{"at": 3, "action": "orbit", "orbit": {"velocity": 2}}]), ["orbit.radius"]),
    (
        "orbit-radius-range",
        _doc([{"at": 3, "action": "orbit", "orbit": {"radius": 5000}}]),
        ["orbit.radius", "(got 5000)", "<= 1000"],
    ),
    (
        "orbit-half-centre",
        _doc([{"at": 3, "action": "orbit", "orbit": {"radius": 5, "x": 3}}]),
        ["give both x and y of the centre"],
    ),
    (
        "land-start-with-arg",
        _doc([{"at": 3, "action": "land_start", "speed": 3}]),
        ["field 'speed' only goes with action speed"],
    ),
    ("yaw-missing", _doc([{"at": 3, "action": "yaw"}]), ["action yaw needs field 'yaw'"]),
    (
        "yaw-direction",
        _doc([{"at": 3, "action": "yaw", "yaw": {"heading": 90, "direction": "left"}}]),
        ["yaw.direction", "(got 'left')", "'clockwise'"],
    ),
    (
        "unknown-action",
        _doc([{"at": 3, "action": "teleport"}]),
        ["spec.commands[1].action", "(got 'teleport')", "'goto'"],
    ),
    (
        "fault-unit",
        _doc([], faults=[{"at": 5, "unit": "engine", "type": "off"}]),
        ["spec.faults[0].unit", "(got 'engine')", "'gps'"],
    ),
    (
        "fault-type",
        _doc([], faults=[{"at": 5, "unit": "gps", "type": "broken"}]),
        ["spec.faults[0].type", "(got 'broken')", "'intermittent'"],
    ),
    (
        "fault-time",
        _doc([], faults=[{"at": -1, "unit": "gps", "type": "off"}]),
        ["spec.faults[0].at", "(got -1)", ">= 0"],
    ),
    (
        "fault-instance",
        _doc([], faults=[{"at": 5, "unit": "motor", "type": "off", "instance": -1}]),
        ["spec.faults[0].instance", "(got -1)"],
    ),
    ("fault-no-type", _doc([], faults=[{"at": 5, "unit": "gps"}]), ["spec.faults[0].type"]),
    (
        "fault-disabled",
        _doc([], faults=[{"at": 5, "unit": "gps", "type": "off"}], vehicle={"params": {"SYS_FAILURE_EN": 0}}),
        ["faults need SYS_FAILURE_EN=1", "sets it to 0"],
    ),
]


@pytest.mark.parametrize("doc", [c[1] for c in GOOD], ids=[c[0] for c in GOOD])
def test_good_input_validates(write: Callable[..., Path], uavtest, doc: dict[str, Any]) -> None:
    result = uavtest("validate", write("test.yaml", doc))
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize(("doc", "expected"), [c[1:] for c in BAD], ids=[c[0] for c in BAD])
def test_bad_input_exits_2(
    write: Callable[..., Path], uavtest, doc: dict[str, Any], expected: list[str]
) -> None:
    path = write("test.yaml", doc)
    result = uavtest("validate", path)
    assert result.returncode == 2, (result.stdout, result.stderr)
    message = " ".join(result.stderr.split())
    assert message.startswith("error: ") and str(path) in message
    assert "Traceback" not in result.stderr
    for part in expected:
        assert part in message, f"{part!r} not in {message!r}"


def test_models_in_python() -> None:
    c = Command(at=2, action="setpoint", setpoint=Setpoint(x=1, y=2, z=-3, yaw_rate=10))
    assert c.dump()["setpoint"] == {"frame": "local", "x": 1.0, "y": 2.0, "z": -3.0, "yawRate": 10.0}
    assert Goto(x=1, y=2, z=-3).speed is None
    assert Orbit(radius=5).clockwise is True
    f = Fault(at=3, unit="motor", type="off", instance=2)
    assert f.dump() == {"at": 3.0, "unit": "motor", "type": "off", "instance": 2}
    with pytest.raises(ValidationError):
        Setpoint(x=1, y=1, z=-1, yaw=0, yaw_rate=0)


def test_faults_alone_do_not_make_a_test() -> None:
    with pytest.raises(ValidationError, match="a test needs a mission or commands"):
        UavTestSpec.model_validate({"faults": [{"at": 1, "unit": "gps", "type": "off"}]})


def test_examples_validate(repo_root: Path, uavtest) -> None:
    for name in ("offboard-square.yaml", "geofence-return.yaml", "gps-loss-land.yaml"):
        result = uavtest("validate", repo_root / "examples" / name)
        assert result.returncode == 0, (name, result.stderr)


def test_validate_warns_that_px4_v115_does_not_do_condition_yaw(tmp_path) -> None:
    import io

    from uavtest.spec.cli_support import validate_command

    test = tmp_path / "yaw.yaml"
    test.write_text(
        "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: y}\nspec:\n"
        "  mission: {waypoints: [{x: 5, 'y': 0, z: -5}]}\n"
        "  commands:\n    - {at: 1, action: mode, mode: mission}\n"
        "    - {at: 9, action: yaw, yaw: {heading: 90}}\n"
    )
    out = io.StringIO()
    assert validate_command(test, out=out) == 0
    assert "MAV_CMD_CONDITION_YAW, which PX4 v1.15 answers UNSUPPORTED" in out.getvalue()
