"""PX4 parameter files as Aerialist writes them: ``NAME, value`` per line, no header.

Integers stay integers and numbers with a decimal point or exponent stay floats, because
PX4 parameters are typed (INT32 vs FLOAT) and the runner sets them with their type.
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

from uavtest.errors import BadInput, MissingFile

__all__ = ["parse_params_csv", "read_params_csv"]

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,15}$")  # PX4: at most 16 characters


def parse_params_csv(text: str, source: str) -> dict[str, int | float]:
    """``{NAME: value}`` from the CSV text; ``BadInput`` naming the line for anything else."""
    params: dict[str, int | float] = {}
    for lineno, row in enumerate(csv.reader(io.StringIO(text)), start=1):
        cells = [c.strip() for c in row]
        if not cells or all(not c for c in cells) or cells[0].startswith("#"):
            continue
        where = f"line {lineno}"
        if len(cells) != 2:
            raise BadInput(
                f"{where}: expected 2 columns, found {len(cells)}",
                file=source,
                value=",".join(row),
                allowed="NAME, value (no header)",
            )
        name, raw = cells
        if not _NAME.match(name):
            raise BadInput(
                f"{where}: not a PX4 parameter name",
                file=source,
                value=name,
                allowed="letters, digits and _, at most 16 characters, starting with a letter",
            )
        params[name] = _number(raw, where, source)
    return params


def _number(raw: str, where: str, source: str) -> int | float:
    try:
        return int(raw)
    except ValueError:
        pass
    try:
        value = float(raw)
    except ValueError:
        raise BadInput(
            f"{where}: value is not a number", file=source, value=raw, allowed="a number"
        ) from None
    if not math.isfinite(value):
        raise BadInput(f"{where}: value is not finite", file=source, value=raw, allowed="a finite number")
    return value


def read_params_csv(path: Path) -> dict[str, int | float]:
    """The I/O edge of ``parse_params_csv``."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise MissingFile(str(path)) from None
    except (OSError, UnicodeDecodeError) as e:
        raise BadInput(f"cannot read params file: {e}", file=str(path)) from None
    return parse_params_csv(text, str(path))
