"""The operator's configuration, from environment variables (pydantic-settings).

Everything is prefixed ``UAVTEST_OPERATOR_`` (e.g. ``UAVTEST_OPERATOR_RUNNER_IMAGE``); the store's
own endpoint and credentials are the store's variables (``UAVTEST_S3_ENDPOINT``, ...). The Helm
chart sets these from ``values.yaml``. Nothing secret is held here. Replica pods never see the S3
credentials: each run gets a Secret ``<job>-upload`` in its namespace holding an upload-only POST
policy the operator signs (``uavtest.store.post_policy``), bound to the run's key prefix, to
``upload_max_bytes`` per object, and expiring ``upload_margin_seconds`` after the Job's deadline.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field
from pydantic_settings import BaseSettings, SettingsConfigDict

from uavtest.spec.bounds import SpeedFactor

__all__ = ["OperatorSettings", "Px4Resources", "Resources"]


class Resources(BaseModel):
    """Requests and limits of one container (Kubernetes quantity strings)."""

    model_config = ConfigDict(extra="forbid")

    cpu_request: str = "100m"
    memory_request: str = "128Mi"
    cpu_limit: str | None = None
    memory_limit: str | None = "1Gi"

    def manifest(self) -> dict[str, dict[str, str]]:
        limits = {k: v for k, v in (("cpu", self.cpu_limit), ("memory", self.memory_limit)) if v}
        out: dict[str, dict[str, str]] = {
            "requests": {"cpu": self.cpu_request, "memory": self.memory_request}
        }
        if limits:
            out["limits"] = limits
        return out


class Px4Resources(Resources):
    """The PX4 SITL sidecar's: measured on PX4 v1.15 SIH flying, ~9 MB RSS and ~10 % of a core per
    1x speed factor (no CPU limit: a throttled PX4 falls behind its own clock)."""

    cpu_request: str = "250m"
    memory_request: str = "64Mi"
    memory_limit: str | None = "512Mi"


class OperatorSettings(BaseSettings):
    """How the operator builds replica Jobs and where their artifacts go."""

    model_config = SettingsConfigDict(
        env_prefix="UAVTEST_OPERATOR_", env_nested_delimiter="__", extra="ignore"
    )

    runner_image: str = Field("uavtest-runner:latest", description="image with `uavtest` (sitl + runner)")
    image_pull_policy: Literal["Always", "IfNotPresent", "Never"] = "IfNotPresent"
    px4_image: str | None = Field(
        None, description="PX4 SITL image for vehicle.simulator: px4 (a test's vehicle.image wins)"
    )
    px4_args: list[str] = Field(default_factory=list, description="arguments for the PX4 SITL container")
    px4_speed_factor: SpeedFactor | None = Field(
        None,
        description="PX4_SIM_SPEED_FACTOR of PX4 sidecars when a test sets no vehicle.speedFactor "
        "(None: PX4's own, real time)",
    )

    store_url: str = Field("s3://uavtest", description="s3://bucket[/prefix] the replicas write to")
    pod_s3_endpoint: str | None = Field(
        None, description="S3 endpoint as pods reach it (default: the operator's UAVTEST_S3_ENDPOINT)"
    )
    pod_s3_secure: bool | None = Field(None, description="default: the operator's UAVTEST_S3_SECURE")
    upload_max_bytes: int = Field(
        1 << 30, ge=1, description="largest artifact a replica may upload (the policy's content-length-range)"
    )
    upload_margin_seconds: int = Field(
        3600, ge=0, description="an upload policy outlives the Job's activeDeadlineSeconds by this much"
    )

    backoff_limit_per_index: int = Field(2, ge=0, description="retries of one replica after bench errors")
    job_ttl_seconds: int | None = Field(86400, ge=0, description="ttlSecondsAfterFinished of replica Jobs")
    deadline_margin_seconds: int = Field(300, ge=0, description="added to activeDeadlineSeconds")
    max_parallelism: int | None = Field(None, ge=1, description="cap on a Job's parallelism")
    run_as_user: int = 65532
    runtime_default_seccomp: bool = True

    sitl_resources: Resources = Field(default_factory=Resources)
    runner_resources: Resources = Field(default_factory=Resources)
    px4_resources: Px4Resources = Field(default_factory=Px4Resources, description="the PX4 SITL sidecar")

    aggregate_retry_seconds: float = Field(
        30.0, gt=0, description="how often aggregation is retried while the store is unreachable"
    )
    metrics_port: int = Field(8080, ge=0, le=65535, description="Prometheus metrics port (0: off)")
