"""Pure builders: a UavTest → the ConfigMap holding the test and one Indexed Job of replicas.

No API calls here: every function returns a manifest (a dict) or a number, so the shape of
what the operator creates is unit-tested without a cluster.

The Job, and why it looks like this:

- ``completionMode: Indexed``, ``completions = replicas``: replica *i* is the pod with completion
  index *i* (``JOB_COMPLETION_INDEX``); it flies with seed ``spec.seed + i``.
- Each pod runs the simulator as a native sidecar (an init container with
  ``restartPolicy: Always``) and the runner as the main container; they talk MAVLink over the
  pod's localhost and share the ULog directory (an emptyDir). When the runner exits, the kubelet
  stops the sidecar (SIGTERM: the sim closes its log) and the pod ends with the runner's code.
- ``vehicle.simulator: px4``: the sidecar is a PX4 SITL image (``vehicle.image``, else the
  operator's ``px4_image``) with its own entrypoint, working in the shared emptyDir (workingDir,
  ``PX4_WORKDIR``), so PX4's ``log/<date>/<time>.ulg`` lands where the runner looks; an image
  that writes elsewhere gets its log downloaded over MAVLink by the runner. The test's home and
  speed factor go in as PX4's own variables (``PX4_HOME_LAT/LON/ALT`` in degrees,
  ``PX4_SIM_SPEED_FACTOR``); parameters are set by the runner over MAVLink. ``/tmp`` is an
  emptyDir (PX4's lock file and socket); resources are ``px4_resources``.
- Runner exit codes (``uavtest runner``): 0 pass, 1 fail, 2 bad input, 3 bench error. Only bench
  errors may be retried, so ``podFailurePolicy`` says:

  1. a pod with condition ``DisruptionTarget`` (evicted, preempted, node drained) → ``Ignore``:
     replaced without counting against the retries;
  2. runner exit 1 (verdict ``fail``: ``result.json`` is already uploaded) or 2 (the test cannot
     be flown) → ``FailIndex``: that index is finished, never retried — a failing drone is a
     result, not an accident;
  3. any other non-zero exit of the runner (3, or killed: 137/143) → ``Count``: retried up to
     ``backoffLimitPerIndex`` times, each retry a new pod with the same index and seed.

  ``maxFailedIndexes = replicas`` so failed indexes never stop the others; the Job's own
  ``Failed`` condition at the end only means "some index did not pass". The verdicts come from
  the replicas' ``result.json``, read at aggregation.
- ``activeDeadlineSeconds`` = timeout × waves (replicas / parallelism, rounded up) × attempts
  per index (1 + backoffLimitPerIndex) + a start-up margin: a safety net for a wedged replica.
- Pods run as non-root (uid 65532), read-only root filesystem, all capabilities dropped, seccomp
  RuntimeDefault, no service account token, no service links.
- Replica pods hold no store credentials. The runner reads ``UAVTEST_S3_UPLOAD_POLICY`` from the
  run's Secret ``<job>-upload`` (``build_upload_secret``): a POST policy the operator signed that
  lets it upload under ``<namespace>/<test>/<run-id>/`` only, at most ``upload_max_bytes`` per
  object, until the Job's deadline plus ``upload_margin_seconds`` (``upload_window``; S3 signs for
  at most 7 days, so a longer deadline is clamped and the operator warns). The root credentials stay
  in the operator's own namespace, and a test runs in any namespace the operator watches.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any

import kopf
import yaml

from uavtest.controller import names
from uavtest.controller.settings import OperatorSettings
from uavtest.engine.px4home import px4_home_env
from uavtest.errors import BadInput
from uavtest.spec.models import Metadata, Simulator, UavTest, UavTestSpec
from uavtest.store.layout import run_prefix
from uavtest.store.post_policy import POLICY_ENV, UploadPolicy
from uavtest.store.settings import S3Settings

__all__ = [
    "LOG_DIR",
    "MAX_UPLOAD_POLICY_SECONDS",
    "RUNNER_EXIT_BAD_INPUT",
    "RUNNER_EXIT_ERROR",
    "RUNNER_EXIT_FAIL",
    "RUNNER_EXIT_PASS",
    "UploadWindow",
    "build_configmap",
    "build_job",
    "build_upload_secret",
    "deadline_seconds",
    "job_name_for",
    "labels_for",
    "owned_by",
    "parallelism_for",
    "pod_endpoint_url",
    "rendered_test_yaml",
    "run_id_for",
    "unresolved_files",
    "upload_expires",
    "upload_prefix",
    "upload_secret_name",
    "upload_window",
    "uses_upload_policy",
]

RUNNER_EXIT_PASS = 0
RUNNER_EXIT_FAIL = 1
RUNNER_EXIT_BAD_INPUT = 2
RUNNER_EXIT_ERROR = 3

LOG_DIR = "/var/uavtest/logs"
_TMP_DIR = "/tmp"
_TEST_PATH = f"{names.TEST_MOUNT}/{names.TEST_FILE}"
_API_PORT = 14540
_JOB_NAME_MAX = 48  # leaves room for "-<index>" in Indexed Job pod hostnames (63)
# S3 (SigV4) signatures are valid for at most 7 days; MinIO and AWS refuse longer-lived ones.
MAX_UPLOAD_POLICY_SECONDS = 7 * 24 * 3600


def run_id_for(uid: str) -> str:
    """The run id of a UavTest object: the first 8 hex digits of its uid (one run per object)."""
    head = uid.replace("-", "")[:8].lower()
    if len(head) < 8:
        raise BadInput("a UavTest uid needs at least 8 hex digits", field="metadata.uid", value=uid)
    return head


def job_name_for(test: str, run_id: str) -> str:
    """``<test>-<run id>``, the test name cut so the whole stays a valid pod hostname prefix."""
    head = test[: _JOB_NAME_MAX - len(run_id) - 1].rstrip("-")
    return f"{head}-{run_id}"


def labels_for(test: str, run_id: str) -> dict[str, str]:
    """Labels of every child: recommended ``app.kubernetes.io/*`` plus ``uavtest.io/test`` and ``/run``."""
    return {
        names.LABEL_NAME: "uavtest",
        names.LABEL_INSTANCE: test,
        names.LABEL_COMPONENT: "replica",
        names.LABEL_PART_OF: "uavtest",
        names.LABEL_MANAGED_BY: names.MANAGER,
        names.LABEL_TEST: test,
        names.LABEL_RUN: run_id,
    }


def unresolved_files(spec: UavTestSpec) -> list[str]:
    """Fields naming files, which a cluster cannot read: ``uavtest render`` inlines them first."""
    found = []
    if spec.vehicle.params_file is not None:
        found.append("spec.vehicle.paramsFile")
    if spec.mission is not None and spec.mission.plan_file is not None:
        found.append("spec.mission.planFile")
    if spec.commands_file is not None:
        found.append("spec.commandsFile")
    similarity = spec.assertions.similarity
    if similarity is not None and similarity.log_file is not None:
        found.append("spec.assertions.similarity.logFile")
    return found


def parallelism_for(spec: UavTestSpec, settings: OperatorSettings) -> int:
    """Replicas flown at once: the spec's parallelism (default all), capped by the operator's limit."""
    want = min(spec.parallelism or spec.replicas, spec.replicas)
    if settings.max_parallelism is not None:
        want = min(want, settings.max_parallelism)
    return max(want, 1)


def deadline_seconds(spec: UavTestSpec, settings: OperatorSettings) -> int:
    """activeDeadlineSeconds: timeout × waves × attempts per index + start-up margin."""
    waves = math.ceil(spec.replicas / parallelism_for(spec, settings))
    attempts = 1 + settings.backoff_limit_per_index
    return math.ceil(spec.timeout * waves * attempts) + settings.deadline_margin_seconds


def rendered_test_yaml(test: UavTest) -> str:
    """The test as the sitl and runner read it: a self-contained UavTest YAML."""
    slim = UavTest(
        metadata=Metadata(name=test.metadata.name, namespace=test.metadata.namespace), spec=test.spec
    )
    return yaml.safe_dump(slim.dump(), sort_keys=False)


def build_configmap(test: UavTest, run_id: str, owner: Mapping[str, Any]) -> dict[str, Any]:
    """The ConfigMap mounted at /etc/uavtest in every replica pod, owned by the UavTest."""
    cm: dict[str, Any] = {
        "apiVersion": "v1",
        "kind": "ConfigMap",
        "metadata": {
            "name": job_name_for(test.metadata.name, run_id),
            "labels": labels_for(test.metadata.name, run_id),
        },
        "data": {names.TEST_FILE: rendered_test_yaml(test)},
    }
    kopf.adopt(cm, owner=owner, strict=True)  # type: ignore[arg-type]
    return cm


def _container_security(settings: OperatorSettings) -> dict[str, Any]:
    return {
        "allowPrivilegeEscalation": False,
        "readOnlyRootFilesystem": True,
        "capabilities": {"drop": ["ALL"]},
        "runAsNonRoot": True,
        "runAsUser": settings.run_as_user,
        "runAsGroup": settings.run_as_user,
    }


def _pod_security(settings: OperatorSettings) -> dict[str, Any]:
    ctx: dict[str, Any] = {
        "runAsNonRoot": True,
        "runAsUser": settings.run_as_user,
        "runAsGroup": settings.run_as_user,
        "fsGroup": settings.run_as_user,
    }
    if settings.runtime_default_seccomp:
        ctx["seccompProfile"] = {"type": "RuntimeDefault"}
    return ctx


def _mounts(*, logs: bool = True) -> list[dict[str, Any]]:
    mounts = [
        {"name": "test", "mountPath": names.TEST_MOUNT, "readOnly": True},
        {"name": "tmp", "mountPath": _TMP_DIR},
    ]
    if logs:
        mounts.append({"name": "logs", "mountPath": LOG_DIR})
    return mounts


_COMMON_ENV = [
    {"name": "HOME", "value": _TMP_DIR},
    {"name": "PYTHONDONTWRITEBYTECODE", "value": "1"},
    {"name": "PYTHONUNBUFFERED", "value": "1"},
    {"name": "MPLCONFIGDIR", "value": f"{_TMP_DIR}/matplotlib"},
]

# sh computes the seed (base + index) and passes the index; "$@" keeps the other arguments intact.
_SITL_SCRIPT = 'exec uavtest sitl --seed "$((UAVTEST_BASE_SEED + JOB_COMPLETION_INDEX))" "$@"'
_RUNNER_SCRIPT = (
    'exec uavtest runner --replica "$JOB_COMPLETION_INDEX" '
    '--seed "$((UAVTEST_BASE_SEED + JOB_COMPLETION_INDEX))" "$@"'
)


def _px4_env(spec: UavTestSpec, settings: OperatorSettings) -> list[dict[str, Any]]:
    """PX4's own variables: the test's home (degrees; the uavtest PX4 image converts them for a
    build that takes degrees * 1e7) and the speed factor (the test's, else the operator's)."""
    home = px4_home_env(spec.world.home, int_latlon=False)
    env = [{"name": k, "value": v} for k, v in home.items()]
    speed = spec.vehicle.speed_factor or settings.px4_speed_factor
    if speed is not None:
        env.append({"name": "PX4_SIM_SPEED_FACTOR", "value": f"{speed:g}"})
    return env


def _sitl_container(test: UavTest, settings: OperatorSettings) -> dict[str, Any]:
    spec = test.spec
    base_env = [{"name": "UAVTEST_BASE_SEED", "value": str(spec.seed or 0)}, *(dict(e) for e in _COMMON_ENV)]
    container: dict[str, Any] = {
        "name": names.CONTAINER_SITL,
        "restartPolicy": "Always",  # native sidecar: stopped when the runner ends
        "imagePullPolicy": settings.image_pull_policy,
        "env": base_env,
        "resources": settings.sitl_resources.manifest(),
        "securityContext": _container_security(settings),
        "volumeMounts": _mounts(),
    }
    if spec.vehicle.simulator == Simulator.PX4:
        image = spec.vehicle.image or settings.px4_image
        if not image:
            raise BadInput(
                "a px4 simulator needs an image",
                field="spec.vehicle.image",
                allowed="a PX4 SITL image here, or the operator's UAVTEST_OPERATOR_PX4_IMAGE",
            )
        container["image"] = image
        # PX4 works in the shared emptyDir: its parameters, dataman and log/<date>/<time>.ulg,
        # which the runner collects from there (or, when the image writes elsewhere, downloads)
        container["workingDir"] = LOG_DIR
        container["env"] = [*base_env, {"name": "PX4_WORKDIR", "value": LOG_DIR}, *_px4_env(spec, settings)]
        container["resources"] = settings.px4_resources.manifest()
        if settings.px4_args:
            container["args"] = list(settings.px4_args)
        return container
    container["image"] = spec.vehicle.image or settings.runner_image
    container["command"] = ["/bin/sh", "-c", _SITL_SCRIPT, "uavtest-sitl"]
    container["args"] = ["--test", _TEST_PATH, "--lockstep", "--gcs-quiet", "--log-dir", LOG_DIR]
    return container


def upload_secret_name(test: str, run_id: str) -> str:
    """``<job>-upload``: the run's Secret holding its upload policy."""
    return f"{job_name_for(test, run_id)}-upload"


def upload_prefix(test: UavTest, run_id: str) -> str:
    """``<namespace>/<test>/<run-id>/``: the store keys the run's upload policy allows."""
    return run_prefix(test.metadata.namespace or "default", test.metadata.name, run_id)


@dataclass(frozen=True)
class UploadWindow:
    """When a run's upload policy expires, and when it would have had to (``wanted``)."""

    expires: datetime
    wanted: datetime

    @property
    def clamped(self) -> bool:
        """The Job may outlive the policy: S3's 7-day limit cut it short."""
        return self.expires < self.wanted


def upload_window(spec: UavTestSpec, settings: OperatorSettings, now: datetime) -> UploadWindow:
    """The Job's activeDeadlineSeconds plus the margin from ``now``, at most S3's 7 days."""
    if now.tzinfo is None:
        raise ValueError("now must carry a time zone")
    want = deadline_seconds(spec, settings) + settings.upload_margin_seconds
    now = now.replace(microsecond=0)
    return UploadWindow(
        expires=now + timedelta(seconds=min(want, MAX_UPLOAD_POLICY_SECONDS)),
        wanted=now + timedelta(seconds=want),
    )


def pod_endpoint_url(settings: OperatorSettings, s3: S3Settings) -> str:
    """``http(s)://host:port`` of the store as replica pods reach it (the policy's form action)."""
    endpoint = settings.pod_s3_endpoint or s3.endpoint
    secure = s3.secure if settings.pod_s3_secure is None else settings.pod_s3_secure
    host, secure = S3Settings(endpoint=endpoint, secure=secure).host_and_secure()
    return f"{'https' if secure else 'http'}://{host}"


def build_upload_secret(
    test: UavTest, run_id: str, policy: UploadPolicy, owner: Mapping[str, Any]
) -> dict[str, Any]:
    """The Secret ``<job>-upload`` in the test's namespace, owned by the UavTest: the run's upload policy.

    The annotations say when it expires and where it writes (nothing secret); the policy itself
    (signature included) is only in the data.
    """
    secret: dict[str, Any] = {
        "apiVersion": "v1",
        "kind": "Secret",
        "type": "Opaque",
        "metadata": {
            "name": upload_secret_name(test.metadata.name, run_id),
            "labels": labels_for(test.metadata.name, run_id),
            "annotations": {
                names.UPLOAD_EXPIRES_ANNOTATION: policy.expires.isoformat(),
                names.UPLOAD_PREFIX_ANNOTATION: policy.where(),
            },
        },
        "stringData": {names.UPLOAD_POLICY_KEY: policy.model_dump_json()},
    }
    kopf.adopt(secret, owner=owner, strict=True)  # type: ignore[arg-type]
    return secret


def owned_by(meta: Mapping[str, Any], uid: str) -> bool:
    """Whether an object's metadata names the object with ``uid`` among its owners."""
    return any(ref.get("uid") == uid for ref in meta.get("ownerReferences") or [])


def upload_expires(meta: Mapping[str, Any]) -> datetime | None:
    """When an upload Secret's policy expires, from its annotation; None when it does not say."""
    text = (meta.get("annotations") or {}).get(names.UPLOAD_EXPIRES_ANNOTATION)
    try:
        when = datetime.fromisoformat(text) if text else None
    except ValueError:
        return None
    return when if when is not None and when.tzinfo is not None else None


def uses_upload_policy(settings: OperatorSettings) -> bool:
    """Whether replicas upload through a per-run policy: an ``s3://`` store (a ``file://`` store is
    for runs without a real node, e.g. the scale bench on kwok: its pods never run)."""
    return settings.store_url.startswith("s3://")


def _upload_env(test: UavTest, run_id: str, settings: OperatorSettings) -> list[dict[str, Any]]:
    if not uses_upload_policy(settings):
        return []
    ref = {"name": upload_secret_name(test.metadata.name, run_id), "key": names.UPLOAD_POLICY_KEY}
    return [{"name": POLICY_ENV, "valueFrom": {"secretKeyRef": ref}}]


def _runner_container(test: UavTest, run_id: str, settings: OperatorSettings) -> dict[str, Any]:
    spec = test.spec
    return {
        "name": names.CONTAINER_RUNNER,
        "image": settings.runner_image,
        "imagePullPolicy": settings.image_pull_policy,
        "command": ["/bin/sh", "-c", _RUNNER_SCRIPT, "uavtest-runner"],
        "args": [
            "--test",
            _TEST_PATH,
            "--connect",
            f"udpin:127.0.0.1:{_API_PORT}",
            "--store",
            settings.store_url,
            "--run-id",
            run_id,
            "--namespace",
            test.metadata.namespace or "default",
            "--test-name",
            test.metadata.name,
            "--log-dir",
            LOG_DIR,
        ],
        "env": [
            {"name": "UAVTEST_BASE_SEED", "value": str(spec.seed or 0)},
            *(dict(e) for e in _COMMON_ENV),
            *_upload_env(test, run_id, settings),
        ],
        "resources": settings.runner_resources.manifest(),
        "securityContext": _container_security(settings),
        "volumeMounts": _mounts(),
    }


def _pod_failure_policy() -> dict[str, Any]:
    return {
        "rules": [
            {"action": "Ignore", "onPodConditions": [{"type": "DisruptionTarget", "status": "True"}]},
            {
                "action": "FailIndex",
                "onExitCodes": {
                    "containerName": names.CONTAINER_RUNNER,
                    "operator": "In",
                    "values": [RUNNER_EXIT_FAIL, RUNNER_EXIT_BAD_INPUT],
                },
            },
            {
                "action": "Count",
                "onExitCodes": {
                    "containerName": names.CONTAINER_RUNNER,
                    "operator": "NotIn",
                    "values": [RUNNER_EXIT_PASS, RUNNER_EXIT_FAIL, RUNNER_EXIT_BAD_INPUT],
                },
            },
        ]
    }


def build_job(
    test: UavTest,
    run_id: str,
    settings: OperatorSettings,
    owner: Mapping[str, Any],
) -> dict[str, Any]:
    """One Indexed Job flying every replica of ``test`` (see the module doc), owned by the UavTest."""
    spec = test.spec
    name = job_name_for(test.metadata.name, run_id)
    labels = labels_for(test.metadata.name, run_id)
    job_spec: dict[str, Any] = {
        "completionMode": "Indexed",
        "completions": spec.replicas,
        "parallelism": parallelism_for(spec, settings),
        "backoffLimitPerIndex": settings.backoff_limit_per_index,
        "maxFailedIndexes": spec.replicas,
        "podReplacementPolicy": "Failed",
        "podFailurePolicy": _pod_failure_policy(),
        "activeDeadlineSeconds": deadline_seconds(spec, settings),
        "template": {
            "metadata": {"labels": dict(labels)},
            "spec": {
                "restartPolicy": "Never",
                "automountServiceAccountToken": False,
                "enableServiceLinks": False,
                "securityContext": _pod_security(settings),
                "initContainers": [_sitl_container(test, settings)],
                "containers": [_runner_container(test, run_id, settings)],
                "volumes": [
                    {"name": "test", "configMap": {"name": name}},
                    {"name": "logs", "emptyDir": {}},
                    {"name": "tmp", "emptyDir": {}},
                ],
            },
        },
    }
    if settings.job_ttl_seconds is not None:
        job_spec["ttlSecondsAfterFinished"] = settings.job_ttl_seconds
    job: dict[str, Any] = {
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": {"name": name, "labels": labels},
        "spec": job_spec,
    }
    kopf.adopt(job, owner=owner, strict=True)  # type: ignore[arg-type]
    return job
