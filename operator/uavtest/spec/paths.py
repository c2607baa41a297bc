"""Where a file named inside a test file lives.

Upstream test files (Aerialist, the SBFT competition) name paths relative to the root of
the repository the tools ran in (``samples/flights/mission1.plan``), native files name them
relative to themselves. Both are found by looking in the test file's folder first, then in
each parent folder in turn.
"""

from __future__ import annotations

from pathlib import Path

from uavtest.errors import MissingFile

__all__ = ["resolve_reference"]


def resolve_reference(written: str, test_file: Path | None, *, field: str | None = None) -> Path:
    """The existing file ``written`` refers to, searched from ``test_file``'s folder upwards.

    An absolute path is taken as is. Without a test file (text from a cluster or stdin) the
    search starts in the current directory. Raises ``MissingFile`` naming the path as written
    and the test file when it is found nowhere.
    """
    written = str(written).strip()
    referenced_from = str(test_file) if test_file is not None else None
    if not written:
        raise MissingFile("(empty path)", referenced_from=referenced_from, field=field)
    candidate = Path(written).expanduser()
    if candidate.is_absolute():
        if candidate.is_file():
            return candidate
        raise MissingFile(written, referenced_from=referenced_from, field=field)
    start = (test_file.parent if test_file is not None else Path.cwd()).resolve()
    for folder in (start, *start.parents):
        found = folder / candidate
        if found.is_file():
            return found
    raise MissingFile(written, referenced_from=referenced_from, field=field)
