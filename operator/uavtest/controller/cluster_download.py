"""``uavtest run --engine kubernetes --out DIR``: bring a cluster run's artifacts home.

The operator's status names where the run's artifacts are (``artifacts.store``:
``s3://bucket[/prefix]/<namespace>/<test>/<run-id>/``). This machine reads that store with the
same settings the operator uses (``UAVTEST_S3_ENDPOINT``, ``UAVTEST_S3_ACCESS_KEY``,
``UAVTEST_S3_SECRET_KEY``; see ``uavtest.store.settings``) and copies every key under the run's
prefix into ``DIR`` with the store layout, as the local engine writes it:
``DIR/<namespace>/<test>/<run-id>/replica-<i>/{flight.ulg,trajectory.csv,result.json}`` and
``.../aggregate/...``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from uavtest.errors import BadInput, InfrastructureError
from uavtest.store.base import ArtifactStore
from uavtest.store.layout import run_prefix
from uavtest.store.local import LocalStore

__all__ = ["S3_VARIABLES", "check_download_settings", "download_run", "missing_s3_settings", "store_root"]

#: what this machine needs to read the operator's S3 store
S3_VARIABLES = ("UAVTEST_S3_ENDPOINT", "UAVTEST_S3_ACCESS_KEY", "UAVTEST_S3_SECRET_KEY")


def missing_s3_settings(env: Mapping[str, str]) -> list[str]:
    """The S3 variables ``env`` lacks (empty values count as missing)."""
    return [v for v in S3_VARIABLES if not env.get(v, "").strip()]


def check_download_settings(env: Mapping[str, str]) -> None:
    """Refuse ``--out`` before anything is created when the store cannot be read from here."""
    missing = missing_s3_settings(env)
    if missing:
        raise BadInput(
            "downloading the run's artifacts needs the S3 settings the operator uses; "
            f"{', '.join(missing)} {'is' if len(missing) == 1 else 'are'} not set "
            "(e.g. `kubectl port-forward svc/minio 9000` and UAVTEST_S3_ENDPOINT=127.0.0.1:9000 "
            "with the keys from the operator's S3 Secret), or leave out --out",
            field="--out",
            allowed=", ".join(S3_VARIABLES) + " set in the environment",
        )


def store_root(artifacts_store: str, namespace: str, test: str, run_id: str) -> str:
    """The store's URL from the run's ``artifacts.store`` URI (the run prefix taken off its end)."""
    prefix = run_prefix(namespace, test, run_id)
    text = artifacts_store.rstrip("/") + "/"
    if not text.endswith("/" + prefix):
        raise InfrastructureError(
            f"the status names the artifacts at {artifacts_store}, which does not end with the run's "
            f"prefix {prefix}: cannot tell which store to read"
        )
    return text[: -len(prefix) - 1]


def download_run(store: ArtifactStore, prefix: str, out: Path) -> list[Path]:
    """Every artifact under ``prefix`` copied to ``out`` at the same key; the files written."""
    keys = store.list(prefix)
    if not keys:
        raise InfrastructureError(f"no artifacts under {store.url(prefix.rstrip('/'))}/")
    local = LocalStore(out)
    written = []
    for key in keys:
        local.put(key, store.get(key))
        written.append(local.path(key))
    return written
