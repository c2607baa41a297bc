"""A command-line process that skips the interpreter's teardown still ends as a normal exit does.

Each case runs a real Python process: what it printed, its exit handlers, its threads and its exit
status are what a user of ``uavtest`` (or a shell script reading its output) sees.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def _python(code: str) -> subprocess.CompletedProcess[str]:
    # block-buffered standard streams, as for any command whose output goes to a pipe
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=env,
    )


@pytest.mark.parametrize(
    ("body", "status"),
    [("return None", 0), ("raise SystemExit(1)", 1), ("raise SystemExit(3)", 3), ("sys.exit('bad')", 1)],
)
def test_the_exit_status_is_the_commands(body: str, status: int) -> None:
    proc = _python(
        f"""
        import sys
        from uavtest.process_exit import run_then_end
        def main():
            print("done", flush=False)
            {body}
        run_then_end(main)
        """
    )
    assert proc.returncode == status, proc.stderr
    assert proc.stdout == "done\n"  # buffered output is flushed, not lost
    if body.startswith("sys.exit('"):
        assert proc.stderr.strip() == "bad"  # a message is printed, as the interpreter does


def test_exit_handlers_run_and_threads_are_waited_for() -> None:
    proc = _python(
        """
        import atexit, logging, sys, threading, time
        from uavtest.process_exit import run_then_end
        handler = logging.StreamHandler(sys.stderr)
        logging.getLogger().addHandler(handler)
        def late():
            time.sleep(0.3)
            print("thread finished", flush=False)
        def main():
            atexit.register(lambda: print("exit handler ran", flush=False))
            threading.Thread(target=late).start()  # not a daemon: a normal exit waits for it
            logging.getLogger().warning("logged")
        run_then_end(main)
        """
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == ["thread finished", "exit handler ran"]
    assert "logged" in proc.stderr


def test_the_uavtest_command_prints_everything_and_keeps_its_exit_codes(tmp_path: Path) -> None:
    """``python -m uavtest.cli`` ends through ``script``: output read through a pipe is complete."""
    cli = [sys.executable, "-m", "uavtest.cli"]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    missing = subprocess.run(
        [*cli, "validate", str(tmp_path / "none.yaml")], capture_output=True, text=True, env=env
    )
    assert missing.returncode == 2
    assert "file not found" in missing.stderr
    example = REPO / "examples" / "hover.yaml"
    proc = subprocess.run(
        [*cli, "run", str(example), "--replicas", "1", "--out", str(tmp_path / "runs"), "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads(proc.stdout)  # the whole document, flushed before the process ended
    assert report["passed"] == 1 and report["results"][0]["verdict"] == "pass"


def test_an_executor_left_running_does_not_hang_the_exit() -> None:
    """Idle workers of a ThreadPoolExecutor nobody shut down wait for work forever; a normal
    exit tells them to stop first, and so must this one."""
    proc = _python(
        """
        from concurrent.futures import ThreadPoolExecutor
        from uavtest.process_exit import run_then_end
        pool = ThreadPoolExecutor(max_workers=2)
        def main():
            print(pool.submit(lambda: 6 * 7).result(), flush=False)
        run_then_end(main)
        """
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "42\n"
