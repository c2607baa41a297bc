"""kstatus, the real library: tests/cluster/go/kstatus built from Go modules, run on JSON objects.

``sigs.k8s.io/cli-utils/pkg/kstatus/status`` is what Flux (and ``kstatus``-based waits) use to say
whether an object is Current, InProgress or Failed. The program is built once into the cluster
cache (``$UAVTEST_CACHE/bin/kstatus``, Go caches as tests/cluster/lib.sh sets them), and rebuilt
when its source changes (a version stamp: the hash of go.mod, go.sum and main.go).
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

SOURCE = Path(__file__).resolve().parents[1] / "cluster" / "go" / "kstatus"
CACHE = Path(os.environ.get("UAVTEST_CACHE") or Path.home() / ".cache" / "uavtest")
BIN = CACHE / "bin" / "kstatus"
STAMP = CACHE / "bin" / ".stamp-kstatus"


class KstatusUnavailable(RuntimeError):
    """Go is missing (or the build failed): the caller skips."""


def _key() -> str:
    digest = hashlib.sha256()
    for name in ("go.mod", "go.sum", "main.go"):
        digest.update((SOURCE / name).read_bytes())
    return digest.hexdigest()[:16]


def kstatus_binary() -> Path:
    """The built program, building it first when missing or stale."""
    key = _key()
    if BIN.is_file() and STAMP.is_file() and STAMP.read_text().strip() == key:
        return BIN
    go = shutil.which("go") or ("/usr/local/go/bin/go" if Path("/usr/local/go/bin/go").is_file() else None)
    if go is None:
        raise KstatusUnavailable("no Go toolchain to build tests/cluster/go/kstatus")
    BIN.parent.mkdir(parents=True, exist_ok=True)
    env = {
        **os.environ,
        "GOPATH": str(CACHE / "go" / "path"),
        "GOMODCACHE": str(CACHE / "go" / "mod"),
        "GOCACHE": str(CACHE / "go" / "build"),
        "GOFLAGS": "-buildvcs=false",
        "CGO_ENABLED": "0",
    }
    with open(CACHE / ".build-kstatus.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        tmp = BIN.with_suffix(".tmp")
        done = subprocess.run(
            [go, "build", "-trimpath", "-ldflags=-s -w", "-o", str(tmp), "."],
            cwd=SOURCE,
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
        )
        if done.returncode != 0:
            raise KstatusUnavailable(f"go build of {SOURCE} failed:\n{done.stderr[-3000:]}")
        tmp.replace(BIN)
        STAMP.write_text(key + "\n")
    return BIN


def kstatus(obj: dict[str, Any]) -> tuple[str, str]:
    """(status, message) of one object as kstatus computes it: Current, InProgress, Failed, ..."""
    done = subprocess.run(
        [str(kstatus_binary())], input=json.dumps(obj), capture_output=True, text=True, timeout=60, check=True
    )
    _, status, *message = done.stdout.strip().split(" ", 2)
    return status, (message[0] if message else "")
