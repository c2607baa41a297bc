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
from uavtest.spec.bounds import PARAM_FLOAT_MAX, PARAM_INT_MAX, PARAM_INT_MIN
from uavtest.spec.yaml_io import check_file_size

__all__ = ["PARAM_VALUE_ALLOWED", "check_param_value", "parse_params_csv", "read_params_csv"]

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


#: what a parameter value may be (PX4 stores INT32 or IEEE single-precision FLOAT)
PARAM_VALUE_ALLOWED = (
    f"a finite number: an integer from {PARAM_INT_MIN} to {PARAM_INT_MAX} (PX4 INT32) "
    f"or a decimal within ±{PARAM_FLOAT_MAX:.1e} (PX4 FLOAT)"
)


def check_param_value(value: object) -> bool:
    """True for a value PX4 can hold: an INT32 integer or a finite float within FLOAT's range."""
    if isinstance(value, bool):
        return False
    if isinstance(value, int):
        return PARAM_INT_MIN <= value <= PARAM_INT_MAX or abs(value) <= PARAM_FLOAT_MAX
    return isinstance(value, float) and math.isfinite(value) and abs(value) <= PARAM_FLOAT_MAX


def _number(raw: str, where: str, source: str) -> int | float:
    try:
        value_int = int(raw)
    except ValueError:
        pass
    else:
        if not check_param_value(value_int):
            raise BadInput(
                f"{where}: value out of range", file=source, value=raw, allowed=PARAM_VALUE_ALLOWED
            )
        return value_int
    try:
        value = float(raw)
    except ValueError:
        raise BadInput(
            f"{where}: value is not a number", file=source, value=raw, allowed="a number"
        ) from None
    if not math.isfinite(value):
        raise BadInput(f"{where}: value is not finite", file=source, value=raw, allowed=PARAM_VALUE_ALLOWED)
    if not check_param_value(value):
        raise BadInput(f"{where}: value out of range", file=source, value=raw, allowed=PARAM_VALUE_ALLOWED)
    return value


def read_params_csv(path: Path) -> dict[str, int | float]:
    """The I/O edge of ``parse_params_csv``."""
    check_file_size(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise MissingFile(str(path)) from None
    except (OSError, UnicodeDecodeError) as e:
        raise BadInput(f"cannot read params file: {e}", file=str(path)) from None
    return parse_params_csv(text, str(path))
