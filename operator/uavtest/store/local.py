"""An artifact store in a local directory: keys are relative paths under the root."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from uavtest.errors import BadInput
from uavtest.store.errors import ArtifactNotFound, StoreUnavailable

__all__ = ["LocalStore"]


class LocalStore:
    """Artifacts as files under ``root``; writes are atomic (temporary file, then rename)."""

    def __init__(self, root: Path | str) -> None:
        self.root = Path(root).expanduser().resolve()

    def __repr__(self) -> str:
        return f"LocalStore({str(self.root)!r})"

    def path(self, key: str) -> Path:
        """The file that holds ``key``; refuses keys that would leave the root."""
        parts = key.split("/")
        if not key or key.startswith("/") or any(p in {"", ".", ".."} for p in parts):
            raise BadInput("not a store key", field="key", value=key, allowed="a/relative/key")
        return self.root.joinpath(*parts)

    def put(self, key: str, data: bytes, content_type: str = "application/octet-stream") -> None:
        target = self.path(key)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
            try:
                with os.fdopen(fd, "wb") as f:
                    f.write(data)
                os.replace(tmp, target)
            except BaseException:
                Path(tmp).unlink(missing_ok=True)
                raise
        except OSError as e:
            raise StoreUnavailable("put", key, f"{type(e).__name__}: {e}") from e

    def get(self, key: str) -> bytes:
        target = self.path(key)
        try:
            return target.read_bytes()
        except FileNotFoundError as e:
            raise ArtifactNotFound(key, str(self.root)) from e
        except OSError as e:
            raise StoreUnavailable("get", key, f"{type(e).__name__}: {e}") from e

    def exists(self, key: str) -> bool:
        return self.path(key).is_file()

    def list(self, prefix: str = "") -> list[str]:
        if not self.root.is_dir():
            return []
        keys = []
        for path in self.root.rglob("*"):
            if path.is_file() and not path.name.startswith("."):
                key = path.relative_to(self.root).as_posix()
                if key.startswith(prefix):
                    keys.append(key)
        return sorted(keys)

    def url(self, key: str) -> str:
        return self.path(key).as_uri()
