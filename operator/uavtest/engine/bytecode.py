"""A bytecode cache for the replica processes when Python is told not to write one.

Every replica starts two Python processes (runner and simulator). ``PYTHONDONTWRITEBYTECODE``,
set by most Python container images and CI machines, keeps Python from caching compiled modules
beside their sources. An installed uavtest was compiled by pip at install time; an editable one
(``pip install -e .``, the README's fresh-machine commands) was not, so each of those processes
compiles uavtest's modules from source at every start: 0.2-0.3 s of a replica's ~2 s on a
2-core machine.

``cache_env`` gives the replica processes a bytecode cache of their own, under
``~/.cache/uavtest/pycache`` (``PYTHONPYCACHEPREFIX``: never beside the sources), only in that
case: uavtest has no bytecode of its own, Python was told not to write it, and the user has not
chosen a cache prefix. ``UAVTEST_PYCACHE=off`` keeps the environment as it is; a path puts the
cache there. With a prefix Python looks for every module's bytecode there, so the first replica
compiles the standard library and the dependencies too (once; Python checks each file against
its source and rewrites it when the source changed).

Only processes the engine execs get it (``ExecLauncher``: one replica, or ``UAVTEST_LAUNCH=exec``).
A warm fork server imports once per run, and multiprocessing starts it with ``-B`` whenever this
process runs without writing bytecode, so it could read such a cache but never fill it, and
with an empty one would compile the standard library from source as well.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path

__all__ = ["CACHE_ENV", "cache_env", "default_cache_dir", "has_own_bytecode", "replica_environ"]

CACHE_ENV = "UAVTEST_PYCACHE"  # off | a directory; unset: the default below when needed


def has_own_bytecode(package_init: Path | None = None) -> bool:
    """Whether uavtest's ``__init__`` has compiled bytecode beside it (pip compiled it)."""
    init = package_init or Path(__file__).resolve().parent.parent / "__init__.py"
    tag = sys.implementation.cache_tag
    return tag is not None and (init.parent / "__pycache__" / f"{init.stem}.{tag}.pyc").is_file()


def default_cache_dir(environ: Mapping[str, str]) -> Path:
    """``$XDG_CACHE_HOME/uavtest/pycache``, else ``~/.cache/uavtest/pycache``."""
    base = environ.get("XDG_CACHE_HOME") or str(Path(environ.get("HOME") or Path.home()) / ".cache")
    return Path(base) / "uavtest" / "pycache"


def cache_env(environ: Mapping[str, str], *, own_bytecode: bool | None = None) -> dict[str, str] | None:
    """The replica processes' environment with a bytecode cache, or None to leave it as it is."""
    choice = environ.get(CACHE_ENV, "").strip()
    if choice.lower() == "off" or not environ.get("PYTHONDONTWRITEBYTECODE"):
        return None  # told to leave it, or Python writes bytecode beside the sources itself
    if environ.get("PYTHONPYCACHEPREFIX"):
        return None  # the user chose where bytecode goes
    if own_bytecode if own_bytecode is not None else has_own_bytecode():
        return None  # installed and compiled: the cache would only recompile what pip did
    env = {k: v for k, v in environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(Path(choice) if choice else default_cache_dir(environ))
    return env


def replica_environ() -> dict[str, str] | None:
    """``cache_env`` of this process's environment (the I/O edge)."""
    return cache_env(os.environ)
