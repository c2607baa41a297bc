"""Bodies of ``uavtest validate``, ``uavtest render`` and ``uavtest crd``.

Each returns an exit code; problems are raised as ``UavTestError`` and become messages and
exit codes in ``uavtest.cli.main``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TextIO

from uavtest.engine.speed import speed_factor_notice
from uavtest.errors import ExitCode
from uavtest.spec.collision_prevention import collision_prevention_warnings
from uavtest.spec.commands import resolved_commands
from uavtest.spec.crd import crd_yaml
from uavtest.spec.loaders import load_test
from uavtest.spec.mission import mission_items
from uavtest.spec.models import CommandAction
from uavtest.spec.px4_params import unmodelled_notice, unmodelled_params
from uavtest.spec.render import render
from uavtest.spec.yaml_io import dump_yaml

__all__ = ["crd_command", "render_command", "validate_command"]


#: PX4 v1.15's commander has no handler for MAV_CMD_CONDITION_YAW (Commander.cpp: UNSUPPORTED)
YAW_NOTICE = (
    "action yaw sends MAV_CMD_CONDITION_YAW, which PX4 v1.15 answers UNSUPPORTED (so does the "
    "built-in simulator): the replica will end error; give the yaw with a goto or a setpoint instead"
)


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def validate_command(test: Path, *, out: TextIO | None = None) -> int:
    """Load and check ``test``; print a one-line summary."""
    out = out or sys.stdout
    loaded = load_test(test)
    spec = loaded.spec
    items = mission_items(spec)
    commands = resolved_commands(spec)
    print(
        f"ok: {test}: UavTest {loaded.metadata.name}, {_plural(spec.replicas, 'replica')}, "
        f"{_plural(len(items), 'mission item')}, {_plural(len(commands), 'command')}, "
        f"{_plural(len(spec.world.obstacles), 'obstacle')}",
        file=out,
    )
    from uavtest.engine.local import aerialist_simulator_notice

    upstream = aerialist_simulator_notice(test)
    if upstream:
        print(f"notice: {upstream}", file=out)
    notice = unmodelled_notice(unmodelled_params(spec))
    if notice:
        print(f"warning: {notice}", file=out)
    if any(c.action == CommandAction.YAW for c in commands):
        print(f"warning: {YAW_NOTICE}", file=out)
    for w in collision_prevention_warnings(spec):
        print(f"warning: {w}", file=out)
    speed = speed_factor_notice(spec)
    if speed:
        print(f"warning: {speed}", file=out)
    return int(ExitCode.PASS)


def render_command(
    test: Path, *, name: str | None = None, namespace: str | None = None, out: TextIO | None = None
) -> int:
    """Print the self-contained manifest of ``test`` as YAML."""
    out = out or sys.stdout
    manifest = render(load_test(test), name=name, namespace=namespace)
    out.write(dump_yaml(manifest))
    return int(ExitCode.PASS)


def crd_command(*, out: TextIO | None = None) -> int:
    """Print the CustomResourceDefinition."""
    out = out or sys.stdout
    out.write(crd_yaml())
    return int(ExitCode.PASS)
