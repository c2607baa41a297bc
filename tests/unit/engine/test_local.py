"""The local engine's checks before anything flies, run ids and the Aerialist notice."""

from __future__ import annotations

import re
from datetime import UTC, datetime
from pathlib import Path

import pytest

from uavtest.engine.local import RunOptions, aerialist_simulator_notice, new_run_id, run_local
from uavtest.errors import BadInput, MissingFile

TEST = """\
apiVersion: uavtest.io/v1alpha1
kind: UavTest
metadata: {name: t}
spec:
  replicas: 4
  vehicle: {simulator: SIM}
  mission:
    waypoints: [{x: 0, y: 0, z: -5}]
"""


def _test(tmp_path: Path, simulator: str = "builtin") -> Path:
    path = tmp_path / "t.yaml"
    path.write_text(TEST.replace("SIM", simulator))
    return path


def test_run_ids_are_timestamped_unique_and_store_safe() -> None:
    now = datetime(2025, 3, 4, 5, 6, 7, tzinfo=UTC)
    ids = {new_run_id(now) for _ in range(50)}
    assert len(ids) > 40  # 16 random bits
    assert all(re.fullmatch(r"20250304-050607-[0-9a-f]{4}", i) for i in ids)


def test_competition_file_gets_a_builtin_simulator_notice(shared_data: Path) -> None:
    notice = aerialist_simulator_notice(shared_data / "competition/snippets/case_studies/mission2.yaml")
    assert notice == (
        "mission2.yaml asks for the 'ros' simulator; "
        "uavtest flies it with its built-in simulator (uavtest sitl) and PX4-Avoidance's local planner "
        "(vehicle.avoidance: local-planner, COM_OBS_AVOID 1), the competition's system under test"
    )


def test_native_file_gets_no_notice(tmp_path: Path) -> None:
    assert aerialist_simulator_notice(_test(tmp_path)) is None


@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"replica": 4}, "--replica"),  # replicas 0..3
        ({"replica": 9, "replicas": 5}, "--replica"),
        ({"replicas": 0}, "--replicas"),
        ({"jobs": 0}, "--jobs"),
        ({"seed": -5}, "--seed"),
    ],
)
def test_bad_options_are_bad_input_before_flying(tmp_path: Path, options: dict, field: str) -> None:
    with pytest.raises(BadInput) as e:
        run_local(RunOptions(test=_test(tmp_path), out=tmp_path / "runs", **options))
    assert e.value.field == field
    assert not (tmp_path / "runs").exists()


def test_px4_without_binary_names_the_env_var(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("UAVTEST_PX4_BIN", raising=False)
    with pytest.raises(BadInput, match="UAVTEST_PX4_BIN"):
        run_local(RunOptions(test=_test(tmp_path, "px4"), out=tmp_path / "runs"))
    monkeypatch.setenv("UAVTEST_PX4_BIN", str(tmp_path / "nope" / "px4"))
    with pytest.raises(BadInput, match="UAVTEST_PX4_BIN"):
        run_local(RunOptions(test=_test(tmp_path, "px4"), out=tmp_path / "runs"))


def test_missing_test_file(tmp_path: Path) -> None:
    with pytest.raises(MissingFile):
        run_local(RunOptions(test=tmp_path / "absent.yaml", out=tmp_path / "runs"))


def test_waiting_for_a_runner_ends_at_its_first_line_or_gives_up(tmp_path: Path) -> None:
    import threading

    from uavtest.engine.local import wait_for_first_line

    log = tmp_path / "runner.stderr.log"
    log.write_text("--- attempt 1 ---\n")
    assert not wait_for_first_line(log, wait_s=0.2)  # the header alone is not a line of the runner
    timer = threading.Timer(0.2, lambda: log.write_text("--- attempt 1 ---\nINFO: store: here\n"))
    timer.start()
    assert wait_for_first_line(log, wait_s=30.0)
    timer.join()
    assert not wait_for_first_line(tmp_path / "absent.log", wait_s=0.1)


@pytest.mark.parametrize(
    ("launch", "px4", "replicas", "warm", "forked"),
    [
        ("fork", False, 1, False, False),  # one replica alone: its two processes import in parallel
        ("fork", False, 4, False, True),
        ("fork", False, 1, True, True),  # several tests in one `uavtest run`: the server pays
        ("fork", True, 4, True, False),  # PX4 is a binary
        ("exec", False, 4, True, False),  # the user's choice
    ],
)
def test_replica_processes_are_forked_where_a_warm_server_pays(
    launch: str, px4: bool, replicas: int, warm: bool, forked: bool
) -> None:
    from uavtest.engine.launch import WarmLauncher
    from uavtest.engine.local import EngineSettings, _launcher

    settings = EngineSettings(launch=launch)
    launcher = _launcher(settings, Path("/opt/px4/bin/px4") if px4 else None, replicas, warm)
    assert isinstance(launcher, WarmLauncher) is forked
