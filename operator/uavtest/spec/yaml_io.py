"""Reading and writing YAML documents: syntax errors with line and column, no silent duplicates.

YAML is only ever written from plain dicts with ``yaml.safe_dump`` (never formatted strings).
"""

from __future__ import annotations

from typing import Any

import yaml

from uavtest.errors import BadInput

__all__ = ["dump_yaml", "parse_yaml"]


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader that refuses a key given twice in one mapping (PyYAML keeps the last silently)."""


def _construct_mapping(loader: _StrictLoader, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
    seen: dict[Any, yaml.Node] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)  # type: ignore[no-untyped-call]
        if isinstance(key, list | dict):
            continue  # unhashable keys: let PyYAML report them
        if key in seen:
            mark = key_node.start_mark
            raise yaml.constructor.ConstructorError(
                None, None, f"key {key!r} is given twice in one mapping", mark
            )
        seen[key] = key_node
    return loader.construct_mapping(node, deep=deep)  # type: ignore[no-any-return]


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def parse_yaml(text: str, source: str) -> Any:
    """The one YAML document in ``text``; ``BadInput`` with source, line and column on a syntax error."""
    try:
        return yaml.load(text, Loader=_StrictLoader)  # a SafeLoader subclass: no arbitrary objects
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "unknown place"
        problem = e.problem or str(e)
        context = f" ({e.context})" if e.context else ""
        raise BadInput(f"YAML syntax error at {where}: {problem}{context}", file=source) from None
    except yaml.YAMLError as e:
        raise BadInput(f"YAML syntax error: {e}", file=source) from None


class _Dumper(yaml.SafeDumper):
    """SafeDumper writing lists of scalars on one line (``[0, 0, 0.5, 0]``), everything else as blocks."""


def _represent_list(dumper: _Dumper, data: list[Any]) -> yaml.Node:
    flat = all(not isinstance(v, dict | list | tuple) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flat and bool(data))


_Dumper.add_representer(list, _represent_list)

# YAML 1.1 readers (Go's sigs.k8s.io/yaml in kubectl, among others) read a bare y / n as a boolean;
# PyYAML does not, so it would write them bare. Quote them (obstacle and waypoint field "y").
_YAML11_BOOLEANS = {"y", "Y", "n", "N"}


def _represent_str(dumper: _Dumper, data: str) -> yaml.Node:
    style = "'" if data in _YAML11_BOOLEANS else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", data, style=style)


_Dumper.add_representer(str, _represent_str)


def dump_yaml(document: dict[str, Any]) -> str:
    """YAML of a plain dict, keys in the order given; short scalar lists inline."""
    return yaml.dump(
        document, Dumper=_Dumper, sort_keys=False, default_flow_style=False, allow_unicode=True, width=100
    )
