"""A PX4 v1.15 SITL (SIH) process for one test, from ``UAVTEST_PX4_BIN``; instance 0 sends its
onboard link to UDP 14540, as always."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

import pytest

from harness.sitl import stop_process
from uavtest.engine.px4home import px4_home_env, sih_latlon_is_int
from uavtest.spec.models import Home

PX4_API_PORT = 14540  # instance 0's onboard (API) link


def px4_binary() -> Path:
    """``UAVTEST_PX4_BIN``, resolved; skips the test when it is unset, fails it when it is no file."""
    binary = os.environ.get("UAVTEST_PX4_BIN")
    if not binary:
        pytest.skip("UAVTEST_PX4_BIN is not set (a PX4 v1.15 SITL binary: build/px4_sitl_default/bin/px4)")
    exe = Path(binary).resolve()
    if not exe.is_file():
        pytest.fail(f"UAVTEST_PX4_BIN={binary} is not a file")
    return exe


def px4_command(exe: Path, instance: int = 0, speed: str | None = None) -> tuple[list[str], dict[str, str]]:
    """The command line and environment of PX4 SIH (quadrotor) instance ``instance`` at the default
    ``world.home``, at ``speed`` (``UAVTEST_PX4_SPEED``, default 10) times real time."""
    env = {
        **os.environ,
        "PX4_SIM_MODEL": "sihsim_quadx",
        "PX4_SYS_AUTOSTART": "10040",
        "PX4_SIMULATOR": "sihsim",
        "PX4_SIM_SPEED_FACTOR": speed or os.environ.get("UAVTEST_PX4_SPEED", "10"),
        "HEADLESS": "1",
        # start where the test's mission is (the default world.home), not at PX4's default place
        **px4_home_env(Home(), int_latlon=sih_latlon_is_int(exe)),
    }
    return [str(exe), "-i", str(instance), "-d", str(exe.parent.parent / "etc")], env


def start_px4(
    exe: Path, rootfs: Path, log: IO[bytes], instance: int = 0, speed: str | None = None
) -> subprocess.Popen[bytes]:
    """PX4 SIH instance ``instance`` started in ``rootfs`` (``px4_command``), its console to ``log``."""
    argv, env = px4_command(exe, instance, speed)
    return subprocess.Popen(
        argv, cwd=rootfs, env=env, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT
    )


def stop_px4(proc: subprocess.Popen[bytes]) -> None:
    """SIGINT (PX4's shell stops its modules and closes its log), then SIGKILL after 15 s."""
    stop_process(proc, timeout=15.0, sig=signal.SIGINT)


@contextmanager
def running_px4(workdir: Path, speed: str | None = None) -> Iterator[subprocess.Popen[bytes]]:
    """PX4 SIH (quadrotor) booted in a fresh ``workdir`` (default parameters) at the default
    ``world.home``, at ``speed`` (``UAVTEST_PX4_SPEED``, default 10) times real time; stopped with
    SIGINT (then SIGKILL) on the way out. Its console goes to ``workdir/px4.log``."""
    exe = px4_binary()
    rootfs = workdir / "rootfs"
    rootfs.mkdir(parents=True)
    log = open(workdir / "px4.log", "wb")  # noqa: SIM115
    proc = start_px4(exe, rootfs, log, speed=speed)
    try:
        yield proc
    finally:
        stop_px4(proc)
        log.close()
        shutil.rmtree(rootfs, ignore_errors=True)
