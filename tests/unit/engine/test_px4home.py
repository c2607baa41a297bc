"""PX4 SITL starts at the test's home: PX4_HOME_* in the form the build's SIH parameters take."""

from __future__ import annotations

import json
from pathlib import Path

from uavtest.engine.ports import ReplicaPorts
from uavtest.engine.px4home import RC_DIR, RC_PARAMS, px4_home_env, sih_latlon_is_int
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


def _px4_job(tmp_path: Path, **kw: object) -> ReplicaJob:
    fields: dict[str, object] = {
        "test_path": tmp_path / "t.yaml",
        "test_name": "t",
        "run_id": "r1",
        "index": 0,
        "seed": 1,
        "store_url": str(tmp_path / "store"),
        "out_dir": tmp_path / "out",
        "wall_timeout": 60.0,
        "simulator": Simulator.PX4,
        "px4_bin": _build(tmp_path, "Int32"),
        "home": Home(lat=45.0, lon=-73.5, alt=488.79),
    }
    fields.update(kw)
    return ReplicaJob(**fields)  # type: ignore[arg-type]


def test_sih_starts_on_the_ground_at_the_tests_altitude(tmp_path: Path) -> None:
    work = tmp_path / "w"
    plan = plan_processes(_px4_job(tmp_path), ReplicaPorts(api=14541, gcs=0, instance=1), work)
    assert plan.sim_env is not None
    rc = work / RC_DIR / RC_PARAMS
    # rcS sources px4-rc.params from PATH: the replica's own comes first, then the build's
    assert plan.sim_env["PATH"].split(":")[0] == str(rc.parent)
    assert "param set SIH_LOC_H0 488.790" in plan.sim_files[rc]
    assert plan.sim_files[rc].rstrip().endswith('. "${R}etc/init.d-posix/px4-rc.params"')
    assert plan.sim_stdout == tmp_path / "out" / "sim.stdout.log"


def test_the_speed_factor_reaches_px4s_environment(tmp_path: Path) -> None:
    ports = ReplicaPorts(api=14540, gcs=0, instance=0)
    plan = plan_processes(_px4_job(tmp_path, speed_factor=10.0), ports, tmp_path / "w")
    assert plan.sim_env is not None and plan.sim_env["PX4_SIM_SPEED_FACTOR"] == "10"


def test_each_px4_replica_has_its_own_working_directory_and_instance(tmp_path: Path) -> None:
    job = _px4_job(tmp_path)
    plans = [
        plan_processes(job.model_copy(update={"index": i}), ReplicaPorts(14540 + i, 0, i), tmp_path / f"w{i}")
        for i in range(2)
    ]
    assert plans[0].sim_cwd != plans[1].sim_cwd
    assert [p.sim[2] for p in plans] == ["0", "1"]
    assert set(plans[0].sim_files).isdisjoint(plans[1].sim_files)
