"""PX4's speed factor: vehicle.speedFactor or the measured default, and the budgets it sets."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from uavtest.engine.speed import (
    SCAN_SPEED_MAX,
    default_speed_factor,
    px4_speed_env,
    px4_speed_factor,
    speed_factor_notice,
    speed_factor_source,
    wall_timeout,
)
from uavtest.spec.models import Avoidance, Simulator, UavTestSpec


def spec(simulator: str = "px4", speed: float | None = None) -> UavTestSpec:
    vehicle: dict[str, object] = {"simulator": simulator}
    if speed is not None:
        vehicle["speedFactor"] = speed
    commands = [{"at": 1, "action": "arm"}]
    return UavTestSpec.model_validate({"vehicle": vehicle, "timeout": 300, "commands": commands})


def test_the_default_leaves_the_runner_its_share_of_each_core() -> None:
    # measured on 2 cores: one replica at 20x starved its runner (PX4 alone took 1.6-1.9 cores)
    assert default_speed_factor(cores=2, at_once=1) == 15.0
    assert default_speed_factor(cores=2, at_once=2) == 7.0  # floor(7.5 * 2 / 2)
    assert default_speed_factor(cores=8, at_once=4) == 15.0
    assert default_speed_factor(cores=2, at_once=4) == 3.0
    assert default_speed_factor(cores=4, at_once=1) == 20.0


def test_the_default_is_capped_and_never_below_real_time() -> None:
    assert default_speed_factor(cores=64, at_once=1) == 20.0  # one PX4 SIH ran at most ~18x
    assert default_speed_factor(cores=3, at_once=1) == 20.0
    assert default_speed_factor(cores=1, at_once=10) == 1.0
    with pytest.raises(ValueError):
        default_speed_factor(cores=0, at_once=1)


def test_the_tests_speed_factor_wins_over_the_default() -> None:
    assert px4_speed_factor(spec(speed=3.5), cores=2, at_once=2) == 3.5
    assert px4_speed_factor(spec(), cores=2, at_once=2) == 7.0


def test_px4_gets_the_speed_factor_in_its_environment() -> None:
    assert px4_speed_env(10.0) == {"PX4_SIM_SPEED_FACTOR": "10"}
    assert px4_speed_env(2.5) == {"PX4_SIM_SPEED_FACTOR": "2.5"}


def test_the_wall_budget_shrinks_with_the_speed_factor() -> None:
    slow = wall_timeout(600.0, Simulator.PX4, 1.0)
    fast = wall_timeout(600.0, Simulator.PX4, 10.0)
    assert slow > 2 * 600  # real time, with room for boot and a busy machine
    assert fast < slow / 5
    assert fast > (600 + 46) / 10  # still longer than boot, settle and flight at full speed
    assert wall_timeout(600.0, Simulator.PX4, None) == slow  # PX4's own default: real time
    assert wall_timeout(600.0, Simulator.BUILTIN, None) > 600


def test_a_speed_factor_for_the_builtin_simulator_is_ignored_out_loud() -> None:
    notice = speed_factor_notice(spec("builtin", 10.0))
    assert notice is not None and "speedFactor 10 is ignored" in notice and "lockstep" in notice
    assert speed_factor_notice(spec("builtin")) is None
    assert speed_factor_notice(spec("px4", 10.0)) is None


def test_validate_says_the_builtin_simulator_ignores_the_speed_factor(tmp_path: Path) -> None:
    from uavtest.spec.cli_support import validate_command

    test = tmp_path / "fast.yaml"
    test.write_text(
        "apiVersion: uavtest.io/v1alpha1\nkind: UavTest\nmetadata: {name: fast}\nspec:\n"
        "  vehicle: {simulator: builtin, speedFactor: 10}\n"
        "  commands:\n    - {at: 1, action: arm}\n"
    )
    out = io.StringIO()
    assert validate_command(test, out=out) == 0
    assert "warning: vehicle.speedFactor 10 is ignored" in out.getvalue()


def test_while_the_runner_is_px4s_range_sensor_the_default_is_at_most_ten() -> None:
    """PX4's Collision Prevention drops scans older than 0.5 s of its clock: the runner that sends
    them must be scheduled within 500 ms / factor of wall time."""
    cp = spec().model_copy(deep=True)
    cp.vehicle.avoidance = Avoidance.COLLISION_PREVENTION
    assert px4_speed_factor(cp, cores=2, at_once=1) == SCAN_SPEED_MAX == 10.0
    assert px4_speed_factor(cp, cores=2, at_once=2) == 7.0  # below the cap already
    assert px4_speed_factor(spec(), cores=2, at_once=1) == 15.0  # no range sensor: no cap
    assert px4_speed_factor(spec(speed=20), cores=2, at_once=1) == 20.0  # the test's own wins
    how = speed_factor_source(cp, cores=2, at_once=1)
    assert how == "default for 1 at a time on 2 cores, at most 10x while the runner is PX4's range sensor"
    assert speed_factor_source(cp, cores=2, at_once=2) == "default for 2 at a time on 2 cores"
    assert speed_factor_source(spec(speed=3), cores=2, at_once=1) == "vehicle.speedFactor"
