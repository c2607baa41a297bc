"""Reading and writing YAML documents: syntax errors with line and column, no silent duplicates.

YAML is only ever written from plain dicts with ``yaml.safe_dump`` (never formatted strings).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from uavtest.errors import BadInput
from uavtest.spec.bounds import MAX_DEPTH, MAX_FILE_BYTES, MAX_NODES

__all__ = ["check_file_size", "dump_yaml", "parse_yaml"]


class _TooDeep(yaml.composer.ComposerError):
    """A document nested deeper than ``MAX_DEPTH``."""


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader that refuses a key given twice in one mapping (PyYAML keeps the last silently)
    and a document nested deeper than ``MAX_DEPTH`` (PyYAML would recurse until RecursionError)."""

    _depth = 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node | None:
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark  # type: ignore[no-untyped-call]
                raise _TooDeep(None, None, "nested too deeply", mark)
            return super().compose_node(parent, index)  # type: ignore[no-untyped-call,no-any-return]
        finally:
            self._depth -= 1


def _expanded_size(root: yaml.Node) -> int:
    """How many values the document has once aliases are expanded (a 'billion laughs' is huge)."""
    sizes: dict[int, int] = {}

    def size(node: yaml.Node) -> int:  # depth is bounded by MAX_DEPTH: recursion is safe
        known = sizes.get(id(node))
        if known is not None:
            return known
        total = 1
        if isinstance(node, yaml.SequenceNode):
            total += sum(size(child) for child in node.value)
        elif isinstance(node, yaml.MappingNode):
            total += sum(size(k) + size(v) for k, v in node.value)
        sizes[id(node)] = min(total, MAX_NODES + 1)
        return sizes[id(node)]

    return size(root)


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


def check_file_size(path: Path) -> None:
    """``BadInput`` for an input file larger than ``MAX_FILE_BYTES`` (before reading it whole)."""
    try:
        size = path.stat().st_size
    except OSError:
        return  # reading it reports what is wrong
    if size > MAX_FILE_BYTES:
        raise BadInput(
            "the file is too large",
            file=str(path),
            value=f"{size} bytes",
            allowed=f"at most {MAX_FILE_BYTES // (1024 * 1024)} MiB",
        )


def parse_yaml(text: str, source: str) -> Any:
    """The one YAML document in ``text``; ``BadInput`` with source, line and column on a syntax error."""
    size = len(text.encode("utf-8", errors="replace"))
    if size > MAX_FILE_BYTES:
        raise BadInput(
            "the file is too large",
            file=source,
            value=f"{size} bytes",
            allowed=f"at most {MAX_FILE_BYTES // (1024 * 1024)} MiB",
        )
    loader = _StrictLoader(text)  # a SafeLoader subclass: no arbitrary objects
    try:
        node = loader.get_single_node()  # type: ignore[no-untyped-call]
        if node is None:
            return None
        if _expanded_size(node) > MAX_NODES:
            raise BadInput(
                "the document is too large once its aliases (*name) are expanded",
                file=source,
                allowed=f"at most {MAX_NODES} values",
            )
        return loader.construct_document(node)  # type: ignore[no-untyped-call]
    except RecursionError:
        raise BadInput(
            "the document is nested too deeply",
            file=source,
            allowed=f"at most {MAX_DEPTH} levels of nested mappings and lists",
        ) from None
    except _TooDeep as e:
        mark = e.problem_mark
        where = f" (at line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        raise BadInput(
            f"the document is nested too deeply{where}",
            file=source,
            allowed=f"at most {MAX_DEPTH} levels of nested mappings and lists",
        ) from None
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "unknown place"
        problem = e.problem or str(e)
        context = f" ({e.context})" if e.context else ""
        raise BadInput(f"YAML syntax error at {where}: {problem}{context}", file=source) from None
    except yaml.YAMLError as e:
        raise BadInput(f"YAML syntax error: {e}", file=source) from None
    finally:
        loader.dispose()  # type: ignore[no-untyped-call]


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
