"""The replica processes' bytecode cache: only where Python may not write bytecode itself."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from uavtest.engine.bytecode import cache_env, default_cache_dir, has_own_bytecode
from uavtest.engine.launch import ExecLauncher

NO_WRITES = {"PYTHONDONTWRITEBYTECODE": "1", "HOME": "/home/u", "PATH": "/usr/bin"}


def test_an_editable_install_told_not_to_write_bytecode_gets_a_cache_under_home() -> None:
    env = cache_env(NO_WRITES, own_bytecode=False)
    assert env is not None
    assert env["PYTHONPYCACHEPREFIX"] == "/home/u/.cache/uavtest/pycache"
    assert "PYTHONDONTWRITEBYTECODE" not in env  # the processes fill it
    assert env["PATH"] == "/usr/bin"  # the rest of the environment as it was


def test_the_cache_follows_xdg_and_the_users_choice() -> None:
    xdg = {**NO_WRITES, "XDG_CACHE_HOME": "/var/cache/u"}
    assert default_cache_dir(xdg) == Path("/var/cache/u/uavtest/pycache")
    chosen = cache_env({**xdg, "UAVTEST_PYCACHE": "/scratch/pyc"}, own_bytecode=False)
    assert chosen is not None and chosen["PYTHONPYCACHEPREFIX"] == "/scratch/pyc"


def test_the_environment_is_left_alone_unless_the_cache_helps() -> None:
    assert cache_env({"HOME": "/home/u"}, own_bytecode=False) is None  # Python writes it itself
    assert cache_env(NO_WRITES, own_bytecode=True) is None  # pip compiled uavtest
    assert cache_env({**NO_WRITES, "UAVTEST_PYCACHE": "off"}, own_bytecode=False) is None
    assert cache_env({**NO_WRITES, "PYTHONPYCACHEPREFIX": "/mine"}, own_bytecode=False) is None


def test_own_bytecode_is_the_compiled_init_beside_the_package(tmp_path: Path) -> None:
    init = tmp_path / "pkg" / "__init__.py"
    init.parent.mkdir()
    init.write_text("")
    assert not has_own_bytecode(init)
    subprocess.run([sys.executable, "-m", "py_compile", str(init)], check=True, env={})
    assert has_own_bytecode(init)


def test_uavtest_processes_fill_the_cache_and_other_commands_keep_their_environment(tmp_path: Path) -> None:
    cache = tmp_path / "pycache"
    env = cache_env({**NO_WRITES, "PATH": "", "UAVTEST_PYCACHE": str(cache)}, own_bytecode=False)
    assert env is not None
    launcher = ExecLauncher(environ={**env, "PYTHONPATH": ":".join(sys.path)})
    out, err = tmp_path / "out.log", tmp_path / "err.log"
    runner = [sys.executable, "-m", "uavtest.engine.entry", "runner", "--help"]
    assert launcher.start(runner, stdout=out, stderr=err).wait(timeout=60) == 0, err.read_text()
    compiled = {p.relative_to(cache).as_posix() for p in cache.rglob("*.pyc")}
    entry = f"uavtest/engine/entry.{sys.implementation.cache_tag}.pyc"
    assert any(path.endswith(entry) for path in compiled), sorted(compiled)[:5]

    # anything else (a PX4 binary) runs in this process's environment, not the cache's
    probe = [sys.executable, "-c", "import os; print(os.environ.get('PYTHONPYCACHEPREFIX'))"]
    assert launcher.start(probe, stdout=out, stderr=err).wait(timeout=60) == 0
    assert out.read_text().splitlines()[-1] != str(cache)
