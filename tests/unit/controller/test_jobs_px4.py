"""The replica pod of a ``vehicle.simulator: px4`` test: PX4 SITL sidecar + runner (pure builders),
and the uavtest PX4 image's entrypoint turning that pod's environment into PX4's command line."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any

import pytest

from uavtest.controller.jobs import LOG_DIR
from uavtest.controller.settings import OperatorSettings

from .controller_bodies import uavtest_body
from .test_jobs import container, make_job, pod_spec

ENTRYPOINT = Path(__file__).resolve().parents[3] / "runner-image" / "px4-entrypoint.sh"
HOME = {"lat": 47.397742, "lon": 8.545594, "alt": 488.0}


def px4_body(**vehicle: Any) -> dict[str, Any]:
    return uavtest_body(
        vehicle={"simulator": "px4", "image": "uavtest-px4:dev", **vehicle}, world={"home": HOME}
    )


def env_of(c: dict[str, Any]) -> dict[str, str]:
    return {e["name"]: e["value"] for e in c["env"] if "value" in e}


def test_px4_works_in_the_shared_folder_where_the_runner_collects_its_log() -> None:
    job = make_job(px4_body())
    sitl, runner = container(job, "sitl"), container(job, "runner")
    assert sitl["workingDir"] == LOG_DIR
    assert env_of(sitl)["PX4_WORKDIR"] == LOG_DIR
    mounts = {m["mountPath"]: m["name"] for m in sitl["volumeMounts"]}
    assert mounts[LOG_DIR] == "logs" and mounts["/tmp"] == "tmp"  # PX4's lock file and socket
    assert {"name": "logs", "mountPath": LOG_DIR} in runner["volumeMounts"]
    assert runner["args"][runner["args"].index("--log-dir") + 1] == LOG_DIR
    volumes = {v["name"]: v for v in pod_spec(job)["volumes"]}
    assert volumes["logs"] == {"name": "logs", "emptyDir": {}}
    assert volumes["tmp"] == {"name": "tmp", "emptyDir": {}}
    assert "command" not in sitl and "args" not in sitl  # the image's own entrypoint


def test_px4_starts_at_the_tests_home_in_degrees() -> None:
    env = env_of(container(make_job(px4_body()), "sitl"))
    assert (env["PX4_HOME_LAT"], env["PX4_HOME_LON"], env["PX4_HOME_ALT"]) == (
        "47.39774200",
        "8.54559400",
        "488.00",
    )


def test_speed_factor_from_the_test_else_the_operator_else_px4s_own() -> None:
    assert "PX4_SIM_SPEED_FACTOR" not in env_of(container(make_job(px4_body()), "sitl"))
    operator = env_of(container(make_job(px4_body(), px4_speed_factor=4), "sitl"))
    assert operator["PX4_SIM_SPEED_FACTOR"] == "4"
    test = env_of(container(make_job(px4_body(speedFactor=2.5), px4_speed_factor=4), "sitl"))
    assert test["PX4_SIM_SPEED_FACTOR"] == "2.5"


def test_px4_runs_unprivileged_with_its_own_resources() -> None:
    sitl = container(make_job(px4_body()), "sitl")
    ctx = sitl["securityContext"]
    assert ctx["runAsNonRoot"] is True and ctx["runAsUser"] == 65532
    assert ctx["readOnlyRootFilesystem"] is True and ctx["capabilities"] == {"drop": ["ALL"]}
    assert ctx["allowPrivilegeEscalation"] is False
    assert sitl["resources"] == OperatorSettings().px4_resources.manifest()
    assert sitl["resources"]["requests"] == {"cpu": "250m", "memory": "64Mi"}
    builtin = container(make_job(uavtest_body()), "sitl")
    assert builtin["resources"] == OperatorSettings().sitl_resources.manifest()
    assert "workingDir" not in builtin


def test_one_px4_resource_set_by_environment_keeps_the_other_px4_defaults(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("UAVTEST_OPERATOR_PX4_RESOURCES__CPU_REQUEST", "1")
    monkeypatch.setenv("UAVTEST_OPERATOR_PX4_SPEED_FACTOR", "3")
    settings = OperatorSettings()
    assert settings.px4_resources.manifest() == {
        "requests": {"cpu": "1", "memory": "64Mi"},
        "limits": {"memory": "512Mi"},
    }
    assert settings.px4_speed_factor == 3


def test_the_operators_px4_image_and_args_serve_tests_that_name_none() -> None:
    body = uavtest_body(vehicle={"simulator": "px4"})
    sitl = container(make_job(body, px4_image="registry.example/px4-sitl:1.15", px4_args=["-s", "x"]), "sitl")
    assert sitl["image"] == "registry.example/px4-sitl:1.15"
    assert sitl["args"] == ["-s", "x"]


# ------------------------------------------------------------------ the image's entrypoint


def fake_px4_root(tmp_path: Path, sih_lat_type: str | None) -> Path:
    """/opt/px4 with a stand-in px4 that prints its arguments, working directory and PX4_* env."""
    root = tmp_path / "opt-px4"
    (root / "bin").mkdir(parents=True)
    (root / "etc").mkdir()
    px4 = root / "bin" / "px4"
    px4.write_text('#!/bin/sh\necho "args $*"\necho "cwd $PWD"\nenv | grep ^PX4_ | sort\n')
    px4.chmod(0o755)
    if sih_lat_type is not None:
        params = [
            {"name": "SIH_LOC_H0", "type": "Float", "default": 32.34},
            {"name": "SIH_LOC_LAT0", "shortDesc": "Initial geodetic latitude", "type": sih_lat_type},
        ]
        (root / "parameters.json").write_text(json.dumps({"parameters": params}))
    return root


def run_entrypoint(tmp_path: Path, root: Path, pod_env: dict[str, str]) -> dict[str, str]:
    work = tmp_path / "work"
    # the pod's env, with the working directory moved from the pod's emptyDir to a temporary one
    env = {**pod_env, "PATH": os.environ["PATH"], "PX4_ROOT": str(root), "PX4_WORKDIR": str(work)}
    out = subprocess.run(["sh", str(ENTRYPOINT)], env=env, capture_output=True, text=True, check=True)
    lines = dict(line.split(" ", 1) if " " in line else (line, "") for line in out.stdout.splitlines())
    assert lines["args"] == f"-i 0 -w {work} -d {root}/etc"
    assert lines["cwd"] == str(work) and work.is_dir()
    return dict(line.split("=", 1) for line in out.stdout.splitlines() if line.startswith("PX4_"))


@pytest.mark.parametrize(
    ("sih_lat_type", "lat", "lon"),
    [
        ("Int32", "473977420", "85455940"),  # PX4 <= v1.15: degrees * 1e7
        ("Float", "47.39774200", "8.54559400"),  # v1.16+: degrees
        (None, "47.39774200", "8.54559400"),  # no parameters.json: as given
    ],
)
def test_the_entrypoint_gives_px4_the_home_in_the_form_its_build_takes(
    tmp_path: Path, sih_lat_type: str | None, lat: str, lon: str
) -> None:
    pod_env = env_of(container(make_job(px4_body(speedFactor=3)), "sitl"))
    px4_env = run_entrypoint(tmp_path, fake_px4_root(tmp_path, sih_lat_type), pod_env)
    assert (px4_env["PX4_HOME_LAT"], px4_env["PX4_HOME_LON"], px4_env["PX4_HOME_ALT"]) == (lat, lon, "488.00")
    assert px4_env["PX4_SIM_SPEED_FACTOR"] == "3"
    assert px4_env["PX4_SIM_MODEL"] == "sihsim_quadx"


def test_the_entrypoint_keeps_a_model_and_an_integer_home_it_is_given(tmp_path: Path) -> None:
    pod_env = {"PX4_SIM_MODEL": "sihsim_airplane", "PX4_HOME_LAT": "473977420", "PX4_HOME_LON": "-5"}
    px4_env = run_entrypoint(tmp_path, fake_px4_root(tmp_path, "Int32"), pod_env)
    assert px4_env["PX4_SIM_MODEL"] == "sihsim_airplane"
    assert (px4_env["PX4_HOME_LAT"], px4_env["PX4_HOME_LON"]) == ("473977420", "-5")
