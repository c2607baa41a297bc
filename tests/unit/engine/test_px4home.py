"""PX4 SITL starts at the test's home: PX4_HOME_* in the form the build's SIH parameters take."""

from __future__ import annotations

import json
from pathlib import Path

from uavtest.engine.ports import ReplicaPorts
from uavtest.engine.px4home import px4_home_env, sih_latlon_is_int
from uavtest.engine.replica import ReplicaJob, plan_processes
from uavtest.spec.models import Home, Simulator


def _build(tmp_path: Path, sih_type: str | None) -> Path:
    """A px4_sitl build folder: bin/px4 and, when sih_type is given, parameters.json."""
    build = tmp_path / "build"
    (build / "bin").mkdir(parents=True)
    px4 = build / "bin" / "px4"
    px4.write_text("")
    if sih_type is not None:
        params = [
            {"name": "SIH_LOC_H0", "type": "Float"},
            {"name": "SIH_LOC_LAT0", "type": sih_type},
            {"name": "SIH_LOC_LON0", "type": sih_type},
        ]
        (build / "parameters.json").write_text(json.dumps({"parameters": params, "version": 1}))
    return px4


def test_px4_v1_15_takes_the_home_in_degrees_times_1e7(tmp_path: Path) -> None:
    px4 = _build(tmp_path, "Int32")
    assert sih_latlon_is_int(px4)
    env = px4_home_env(Home(lat=47.3977380, lon=8.5455957, alt=488.76), int_latlon=True)
    assert env == {"PX4_HOME_LAT": "473977380", "PX4_HOME_LON": "85455957", "PX4_HOME_ALT": "488.76"}


def test_newer_px4_takes_the_home_in_degrees(tmp_path: Path) -> None:
    px4 = _build(tmp_path, "Float")
    assert not sih_latlon_is_int(px4)
    env = px4_home_env(Home(lat=-33.5, lon=-70.25, alt=500.0), int_latlon=False)
    assert float(env["PX4_HOME_LAT"]) == -33.5 and float(env["PX4_HOME_LON"]) == -70.25


def test_a_build_without_parameter_metadata_gets_degrees(tmp_path: Path) -> None:
    assert not sih_latlon_is_int(_build(tmp_path, None))


def test_the_px4_replica_starts_at_the_tests_home(tmp_path: Path) -> None:
    px4 = _build(tmp_path, "Int32")
    job = ReplicaJob(
        test_path=tmp_path / "t.yaml",
        test_name="t",
        run_id="r1",
        index=0,
        seed=1,
        store_url=str(tmp_path / "store"),
        out_dir=tmp_path / "out",
        wall_timeout=60.0,
        simulator=Simulator.PX4,
        px4_bin=px4,
        home=Home(lat=45.0, lon=-73.5, alt=30.0),
    )
    plan = plan_processes(job, ReplicaPorts(api=14540, gcs=0, instance=0), tmp_path / "w")
    assert plan.sim_env is not None
    assert plan.sim_env["PX4_HOME_LAT"] == "450000000" and plan.sim_env["PX4_HOME_LON"] == "-735000000"
