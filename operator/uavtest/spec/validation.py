"""pydantic ``ValidationError`` → ``BadInput`` naming the field path, the value and what is allowed.

Field paths are written as a user wrote them: camelCase aliases joined by dots, list
indexes in brackets (``spec.world.obstacles[0].size.l``). The path is found by walking the
model's types along the error location, which also drops pydantic's union member tags
(``...params.NAV_X.int``) and yields the allowed field names of a model for unknown fields.
"""

from __future__ import annotations

import types
import typing
from typing import Any, Union

from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from uavtest.errors import BadInput
from uavtest.spec.bounds import PARAM_FLOAT_MAX, PARAM_INT_MAX, PARAM_INT_MIN

__all__ = ["bad_input_from", "model_fields_of"]

_DNS_NAME = "a DNS-1123 name: lowercase letters, digits and '-', starting and ending with a letter or digit"


def model_fields_of(model: type[BaseModel]) -> list[str]:
    """The wire (alias) names of a model's fields, in declaration order."""
    return [f.alias or name for name, f in model.model_fields.items()]


def _unwrap(tp: Any) -> Any:
    while typing.get_origin(tp) is typing.Annotated:
        tp = typing.get_args(tp)[0]
    return tp


def _union_members(tp: Any) -> list[Any] | None:
    if typing.get_origin(tp) in (Union, types.UnionType):
        return [a for a in typing.get_args(tp) if a is not type(None)]
    return None


def _tags_of(tp: Any) -> tuple[str, ...]:
    """The tags pydantic gives a union member in error locations (``float``, ``constrained-float``)."""
    name = getattr(_unwrap(tp), "__name__", str(tp))
    return (name, f"constrained-{name}")


def _metadata_of(tp: Any) -> tuple[Any, list[Any]]:
    """``tp`` without its Annotated layers, and the constraints those layers carried."""
    found: list[Any] = []
    while typing.get_origin(tp) is typing.Annotated:
        tp, *extras = typing.get_args(tp)
        for extra in extras:
            found.extend(getattr(extra, "metadata", None) or [extra])
    return tp, found


def _walk(root: type[BaseModel], loc: tuple[int | str, ...]) -> tuple[str, type[BaseModel] | None, list[Any]]:
    """The display path of ``loc``, the model class the last step is a field of (if any) and the
    constraints (``Ge``, ``Le``, ...) of the value at ``loc``."""
    parts: list[str] = []
    tp: Any = root
    parent: type[BaseModel] | None = None
    items = list(loc)
    constraints: list[Any] = []
    while items:
        tp, found = _metadata_of(tp)
        constraints.extend(found)
        members = _union_members(tp)
        if members is not None:
            if len(members) == 1:
                tp = members[0]
                continue
            tag = items[0]
            chosen = next((m for m in members if tag in _tags_of(m)), None)
            if chosen is not None:
                items.pop(0)
                tp = chosen
            else:
                tp = members[0]
            continue
        item = items.pop(0)
        constraints = []
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            parent = tp
            field_name, info = next(
                ((n, f) for n, f in tp.model_fields.items() if item in (n, f.alias)), (None, None)
            )
            parts.append(f".{info.alias or field_name}" if info is not None else f".{item}")
            tp = info.annotation if info is not None else Any
            constraints = list(info.metadata) if info is not None else []
            continue
        origin = typing.get_origin(tp)
        args = typing.get_args(tp)
        parent = None
        if origin in (list, tuple) and isinstance(item, int):
            parts.append(f"[{item}]")
            tp = args[0] if args else Any
        elif origin is dict:
            if item == "[key]":
                continue
            parts.append(f".{item}")
            tp = args[1] if len(args) == 2 else Any
        else:
            parts.append(f"[{item}]" if isinstance(item, int) else f".{item}")
            tp = Any
    # the leaf: its own Annotated layers, through an optional (X | None) to the one member
    while True:
        tp, found = _metadata_of(tp)
        constraints.extend(found)
        members = _union_members(tp)
        if members is None or len(members) != 1:
            break
        tp = members[0]
    return "".join(parts).lstrip("."), parent, constraints


def _field_model(root: type[BaseModel], loc: tuple[int | str, ...]) -> type[BaseModel] | None:
    """The model class a location points at (for 'which fields are allowed here')."""
    tp: Any = root
    for item in loc:
        tp = _unwrap(tp)
        members = _union_members(tp)
        if members:
            tp = next((m for m in members if isinstance(m, type) and issubclass(m, BaseModel)), members[0])
            tp = _unwrap(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            info = next((f for n, f in tp.model_fields.items() if item in (n, f.alias)), None)
            tp = info.annotation if info is not None else Any
        elif typing.get_origin(tp) in (list, tuple, dict):
            args = typing.get_args(tp)
            tp = args[-1] if args else Any
        else:
            return None
    tp = _unwrap(tp)
    members = _union_members(tp)
    if members:
        tp = next((m for m in members if isinstance(m, type) and issubclass(m, BaseModel)), None)
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


def _short(value: Any) -> Any:
    if isinstance(value, dict):
        keys = ", ".join(str(k) for k in list(value)[:8])
        return f"a mapping with keys {keys}" if value else "an empty mapping"
    text = repr(value)
    if len(text) > 80:
        return text[:77] + "..."
    return value


def _describe(err: ErrorDetails, root: type[BaseModel]) -> tuple[str, str, Any, str | None]:
    """(field path, message, value, allowed) of one pydantic error."""
    loc = tuple(err["loc"])
    path, parent, constraints = _walk(root, loc)
    kind = err["type"]
    ctx: dict[str, Any] = dict(err.get("ctx") or {})
    value: Any = err.get("input")
    msg = err["msg"]
    allowed: str | None = None
    if kind == "missing":
        return path, "required field is missing", None, "must be given"
    if kind == "extra_forbidden":
        owner = parent or _field_model(root, loc[:-1])
        fields = ", ".join(model_fields_of(owner)) if owner else None
        return path, f"unknown field '{loc[-1]}'", None, fields
    if kind in ("enum", "literal_error"):
        allowed = str(ctx.get("expected", ""))
        msg = "value not allowed"
    elif kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        msg = "value out of range"
        allowed = _range_text(constraints, {_KIND_KEY[kind]: next(iter(ctx.values()))})
    elif kind == "finite_number":
        msg = "not a finite number (NaN and infinity are not allowed)"
        allowed = _range_text(constraints, {})
    elif kind in ("float_type", "float_parsing"):
        allowed, msg = _range_text(constraints, {}), "not a number"
    elif kind in ("int_type", "int_parsing", "int_from_float", "int_parsing_size"):
        allowed, msg = "an integer", "not an integer"
    elif kind in ("bool_type", "bool_parsing"):
        allowed, msg = "true or false", "not a boolean"
    elif kind in ("string_type", "string_unicode"):
        allowed, msg = "a string", "not a string"
    elif kind == "string_pattern_mismatch":
        allowed = _DNS_NAME if path.endswith("metadata.name") else f"text matching {ctx.get('pattern')}"
        msg = "not allowed here"
    elif kind in ("string_too_long", "string_too_short"):
        allowed = (
            f"{'at most' if kind.endswith('long') else 'at least'} {next(iter(ctx.values()))} characters"
        )
        msg = "wrong length"
    elif kind in ("too_short", "too_long"):
        bound = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        allowed = f"{'at least' if kind == 'too_short' else 'at most'} {bound} items"
        msg = "wrong number of items"
        value = _short(value) if not isinstance(value, list) else f"{len(value)} items"
    elif kind in ("model_type", "model_attributes_type", "dict_type"):
        model = _field_model(root, loc)
        allowed = f"a mapping with fields {', '.join(model_fields_of(model))}" if model else "a mapping"
        msg = "not a mapping"
    elif kind in ("list_type", "tuple_type"):
        allowed, msg = "a list", "not a list"
    elif kind in ("value_error", "assertion_error"):
        msg = msg.removeprefix("Value error, ").removeprefix("Assertion failed, ")
        value = None
    return path, msg, _short(value) if value is not None else None, allowed


_PARAM_VALUE = (
    f"a finite number: an integer from {PARAM_INT_MIN} to {PARAM_INT_MAX} (PX4 INT32) "
    f"or a decimal within ±{PARAM_FLOAT_MAX:.1e} (PX4 FLOAT)"
)
_SIGNS = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
_KIND_KEY = {"greater_than": "gt", "greater_than_equal": "ge", "less_than": "lt", "less_than_equal": "le"}


def _range_text(constraints: list[Any], bounds: dict[str, Any]) -> str:
    """'a number > 0', or both bounds when the value has two ('a number >= -1 and <= 1')."""
    for m in constraints:
        for key in _SIGNS:
            if getattr(m, key, None) is not None:
                bounds.setdefault(key, getattr(m, key))
    parts = [f"{_SIGNS[k]} {bounds[k]:g}" for k in ("gt", "ge", "lt", "le") if k in bounds]
    return " and ".join(["a number", *parts]).replace("a number and", "a number", 1)


def bad_input_from(
    error: ValidationError, *, source: str | None, root: type[BaseModel], prefix: str = ""
) -> BadInput:
    """One ``BadInput`` for a validation error: the first problem in full, the others listed briefly.

    ``prefix`` is prepended to every field path (for a part validated on its own, such as
    ``simulation.obstacles[2]`` of an Aerialist file).
    """
    described: list[tuple[str, str, Any, str | None]] = []
    for err in error.errors(include_url=False):
        path, msg, value, allowed = _describe(err, root)
        full = f"{prefix}.{path}".strip(".") if prefix else path
        full = full.replace(".[", "[")
        same = next((i for i, d in enumerate(described) if d[0] == full), None)
        if same is None:
            described.append((full, msg, value, allowed))
            continue
        # a union (int | float, model | None) reports one problem once per member: merge them
        _, first_msg, first_value, first_allowed = described[same]
        if "params." in full and (first_allowed or "").startswith(("a number", "an integer")):
            # a PX4 parameter (int | float): say what PX4 takes, with the float member's message
            message = msg if first_msg == "not an integer" else first_msg
            message = "not a number" if message == "not an integer" else message
            described[same] = (full, message, first_value, _PARAM_VALUE)
            continue
        options = {a for a in (first_allowed, allowed) if a}
        merged = "a number" if options == {"an integer", "a number"} else " or ".join(sorted(options))
        described[same] = (full, "not a number" if merged == "a number" else first_msg, first_value, merged)
    first_path, msg, value, allowed = described[0]
    if len(described) > 1:
        rest = "; ".join(f"'{p}': {m}" for p, m, _, _ in described[1:4])
        more = f" and {len(described) - 4} more" if len(described) > 4 else ""
        allowed = (allowed + " " if allowed else "") + f"[also wrong: {rest}{more}]"
    return BadInput(msg, file=source, field=first_path or None, value=value, allowed=allowed)
