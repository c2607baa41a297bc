"""S3 connection settings, from the environment (a Kubernetes Secret mapped to env vars).

``UAVTEST_S3_ENDPOINT`` (``host:port`` or ``http(s)://host:port``), ``UAVTEST_S3_ACCESS_KEY``,
``UAVTEST_S3_SECRET_KEY``, ``UAVTEST_S3_SECURE``; retry tuning with ``UAVTEST_S3_RETRY_TOTAL``
(seconds before an upload gives up), ``UAVTEST_S3_RETRY_INITIAL``, ``UAVTEST_S3_RETRY_MAX`` and the
per-request ``UAVTEST_S3_TIMEOUT``. A replica pod in a cluster has no keys: ``UAVTEST_S3_UPLOAD_POLICY``
holds the upload-only policy the operator signed for its run (``uavtest.store.post_policy``). The keys
and the policy are ``SecretStr``: they never show in a repr or a log.
"""

from __future__ import annotations

from urllib.parse import urlsplit

from pydantic import Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict

from uavtest.errors import BadInput

__all__ = ["S3Settings"]


class S3Settings(BaseSettings):
    """Where the S3 server is, who we are, and how long to keep trying."""

    model_config = SettingsConfigDict(env_prefix="UAVTEST_S3_", extra="ignore")

    endpoint: str = Field("localhost:9000", description="host:port, or http(s)://host:port")
    access_key: SecretStr | None = None
    secret_key: SecretStr | None = None
    upload_policy: SecretStr | None = Field(
        None, description="JSON of an UploadPolicy: upload-only, instead of the keys (replica pods)"
    )
    secure: bool = Field(False, description="HTTPS; an https:// endpoint turns it on")
    region: str | None = None
    retry_total: float = Field(120.0, gt=0, description="seconds an operation keeps retrying")
    retry_initial: float = Field(0.5, gt=0, description="first wait between retries, seconds")
    retry_max: float = Field(10.0, gt=0, description="longest wait between retries, seconds")
    timeout: float = Field(10.0, gt=0, description="connect and read timeout of one request, seconds")

    def host_and_secure(self) -> tuple[str, bool]:
        """``host:port`` for the minio client and whether to use HTTPS."""
        text = self.endpoint.strip()
        if "://" not in text:
            host, secure = text, self.secure
        else:
            parts = urlsplit(text)
            if parts.scheme not in {"http", "https"}:
                raise BadInput(
                    "S3 endpoint scheme must be http or https",
                    field="UAVTEST_S3_ENDPOINT",
                    value=parts.scheme,
                    allowed="host:port, http://host:port, https://host:port",
                )
            host, secure = parts.netloc, parts.scheme == "https"
            if parts.path not in {"", "/"}:
                raise BadInput(
                    "S3 endpoint must not have a path",
                    field="UAVTEST_S3_ENDPOINT",
                    value=parts.path,
                    allowed="host:port",
                )
        if "@" in host:
            # never echo the value: it holds credentials
            raise BadInput(
                "S3 endpoint must not carry credentials; use UAVTEST_S3_ACCESS_KEY / UAVTEST_S3_SECRET_KEY",
                field="UAVTEST_S3_ENDPOINT",
            )
        if not host:
            raise BadInput("S3 endpoint is empty", field="UAVTEST_S3_ENDPOINT", allowed="host:port")
        return host, secure
