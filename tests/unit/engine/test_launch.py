"""Warm launcher: `uavtest` commands forked from a fork server behave like exec'd ones."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from uavtest.engine.launch import ExecLauncher, WarmLauncher, is_uavtest_cli
from uavtest.engine.replica import _stop


@pytest.fixture(scope="module")
def warm() -> WarmLauncher:
    return WarmLauncher()


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "uavtest.engine.entry", *args]


@pytest.mark.parametrize("launcher", [ExecLauncher(), "warm"])
def test_exit_codes_and_output_files_match_exec(
    launcher: ExecLauncher | str, warm: WarmLauncher, tmp_path: Path
) -> None:
    start = warm.start if launcher == "warm" else launcher.start  # type: ignore[union-attr]
    out, err = tmp_path / "out.log", tmp_path / "err.log"
    ok = start(_cli("runner", "--help"), stdout=out, stderr=err)
    assert ok.wait(timeout=60) == 0
    assert "--run-id" in out.read_text()

    absent = str(tmp_path / "absent.yaml")
    bad = start(
        _cli("runner", "--test", absent, "--store", str(tmp_path), "--run-id", "r"), stdout=out, stderr=err
    )
    assert bad.wait(timeout=60) == 2
    assert "absent.yaml" in err.read_text()
    # the process ends without the interpreter's teardown: its last line still reaches stdout
    last = json.loads(out.read_text().splitlines()[-1])
    assert last["verdict"] == "error" and "absent.yaml" in last["reason"]


def test_a_forked_simulator_is_stopped_cleanly(warm: WarmLauncher, tmp_path: Path) -> None:
    err = tmp_path / "sim.err"
    sim = warm.start(
        _cli(
            "sitl",
            "--lockstep",
            "--api-port",
            "0",
            "--api-local-port",
            "0",
            "--gcs-local-port",
            "0",
            "--log-dir",
            str(tmp_path),
        ),
        stdout=None,
        stderr=err,
    )
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob("*.ulg.part")) and time.monotonic() < deadline:  # the sim is up
        assert sim.poll() is None, err.read_text()
        time.sleep(0.02)
    assert _stop(sim) == 0  # SIGTERM: the simulator closes its log and exits 0


def test_only_uavtest_cli_commands_are_forked() -> None:
    assert is_uavtest_cli(_cli("runner"))
    assert not is_uavtest_cli([sys.executable, "-c", "pass"])
    assert not is_uavtest_cli(
        [sys.executable, "-m", "uavtest.cli", "runner"]
    )  # the engine never runs the CLI
    assert not is_uavtest_cli(["/opt/px4/bin/px4", "-i", "0"])


def test_the_engine_does_not_import_the_cli() -> None:
    """The replica processes have their own entry point: nothing under engine imports uavtest.cli."""
    code = (
        "import sys, uavtest.engine.launch, uavtest.engine.replica, uavtest.engine.local;"
        "import uavtest.engine.entry;"
        "sys.exit('uavtest.cli' in sys.modules)"
    )
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


def test_a_runner_starts_without_the_simulator_or_the_console() -> None:
    """Start-up is on every replica's clock: the runner's process imports neither the built-in
    vehicle (only its range sensor's scan) nor rich (the user's console, not a replica's)."""
    code = (
        "import sys, uavtest.engine.entry, uavtest.runner.main;"
        "heavy = [m for m in ('uavtest.sitl.vehicle', 'rich', 'uavtest.engine.command') if m in sys.modules];"
        "print(heavy); sys.exit(bool(heavy))"
    )
    _assert_exits_0(code)


def test_the_fork_server_leaves_its_children_no_start_up_work() -> None:
    """What every replica process would otherwise redo is done once in the warm server: the
    replica command line is built, the test loaders imported, PX4's parameter table read."""
    from uavtest.engine.launch import PRELOAD

    code = (
        "import sys\n"
        f"for name in {PRELOAD!r}: __import__(name)\n"
        "from uavtest.engine.entry import command\n"
        "from uavtest.px4.parameters import parameters\n"
        "left = [what for what, done in (('command', command.cache_info().currsize),"
        " ('parameters', parameters.cache_info().currsize),"
        " ('loaders', 'uavtest.spec.loaders' in sys.modules)) if not done]\n"
        "print(left); sys.exit(bool(left))"
    )
    _assert_exits_0(code)


def _assert_exits_0(code: str) -> None:
    """Run ``code`` in a fresh interpreter (nothing imported yet); it exits 0 or says why not."""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_replica_command_line_is_built_once_and_still_answers() -> None:
    from uavtest.engine.entry import command

    assert command() is command()
    proc = subprocess.run(_cli("sitl", "--help"), capture_output=True, text=True, check=False)
    assert proc.returncode == 0 and "--lockstep" in proc.stdout, proc.stderr
