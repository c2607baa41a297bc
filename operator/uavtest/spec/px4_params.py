"""A test's PX4 parameters against PX4 v1.15: unknown names, types and ranges; what the built-in
vehicle does not model.

``check_params`` raises ``BadInput`` the way other spec errors read (file, field path, value,
allowed): ``unknown PX4 parameter NAME`` (with close names), a fractional value for an INT32
parameter, a value outside PX4's [min, max] or not among an enum's values.
``unmodelled_params`` names the real PX4 parameters a test sets that the built-in simulator
ignores: every name its parameter defaults (``uavtest.sitl.params.DEFAULTS``) do not declare.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from uavtest.errors import BadInput
from uavtest.px4.parameters import check_value, known, lookup, suggest
from uavtest.spec.models import Simulator, UavTestSpec

__all__ = ["check_params", "modelled_params", "unmodelled_notice", "unmodelled_params"]


def modelled_params() -> frozenset[str]:
    """The PX4 parameters the built-in vehicle models: the names of its parameter defaults."""
    from uavtest.sitl.params import DEFAULTS

    return frozenset(DEFAULTS)


def check_params(params: Mapping[str, int | float], *, source: str | None, field_prefix: str = "") -> None:
    """Raise ``BadInput`` for the first parameter PX4 v1.15 would not take."""
    for name, value in params.items():
        field = f"{field_prefix}.{name}" if field_prefix else name
        if not known(name):
            close = suggest(name)
            raise BadInput(
                f"unknown PX4 parameter {name}" + (f" (did you mean {' or '.join(close)}?)" if close else ""),
                file=source,
                field=field,
                value=value,
                allowed="a parameter PX4 v1.15 has",
            )
        problem = check_value(name, value)
        if problem is not None:
            p = lookup(name)
            assert p is not None
            raise BadInput(
                f"PX4 parameter {name}: {problem}",
                file=source,
                field=field,
                value=value,
                allowed=p.allowed(),
            )


def unmodelled_params(spec: UavTestSpec, names: Iterable[str] | None = None) -> list[str]:
    """PX4 parameters the test sets that have no effect in the built-in simulator (sorted).

    Empty for ``vehicle.simulator: px4``, where PX4 itself interprets every parameter.
    """
    if spec.vehicle.simulator != Simulator.BUILTIN:
        return []
    modelled = modelled_params()
    given = spec.vehicle.params if names is None else names
    return sorted(n for n in given if known(n) and n not in modelled)


def unmodelled_notice(names: list[str]) -> str | None:
    """The warning line for ``names`` (None when there are none)."""
    if not names:
        return None
    return (
        f"{len(names)} PX4 parameter{'s' if len(names) != 1 else ''} set by the test "
        f"{'have' if len(names) != 1 else 'has'} no effect in the built-in simulator: {', '.join(names)}"
    )
