"""``uavtest run``'s engines and which options each one uses (pure).

The local engine flies on this machine; the kubernetes engine creates a UavTest in a cluster and
follows it. Options only one of them understands are named in a warning when given to the other,
never silently dropped.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum

__all__ = ["KUBERNETES_ONLY", "LOCAL_ONLY", "Engine", "ignored_options", "ignored_warning"]


class Engine(StrEnum):
    """Where ``uavtest run`` flies the replicas."""

    LOCAL = "local"  # N (sitl, runner) process pairs on this machine
    KUBERNETES = "kubernetes"  # a UavTest in the cluster: the operator's Indexed Job


#: options only the local engine uses (the cluster's parallelism is spec.parallelism; one replica's
#: exact replay is a local run of that index)
LOCAL_ONLY = ("--jobs", "--replica")
#: options only the kubernetes engine uses
KUBERNETES_ONLY = ("--namespace", "--wait", "--timeout")
#: options that mean nothing once ``--no-wait`` returned right after creating the UavTest
NEEDS_WAIT = ("--out", "--json", "--junit", "--timeout")


def ignored_options(engine: Engine, given: Mapping[str, object], *, wait: bool = True) -> list[str]:
    """The options in ``given`` (option name → value, None when not given) that ``engine`` ignores."""
    named = [k for k, v in given.items() if v is not None]
    if engine is Engine.LOCAL:
        return [k for k in named if k in KUBERNETES_ONLY]
    ignored = [k for k in named if k in LOCAL_ONLY]
    if not wait:
        ignored += [k for k in named if k in NEEDS_WAIT and k not in ignored]
    return ignored


def ignored_warning(engine: Engine, ignored: list[str], *, wait: bool = True) -> str | None:
    """One line for stderr naming the ignored options and why, or None."""
    if not ignored:
        return None
    names = ", ".join(ignored)
    if engine is Engine.LOCAL:
        return f"ignored with --engine local: {names} (they apply to --engine kubernetes only)"
    local = [o for o in ignored if o in LOCAL_ONLY]
    rest = [o for o in ignored if o not in LOCAL_ONLY]
    parts = []
    if local:
        parts.append(
            f"{', '.join(local)} (local engine only: the cluster runs spec.parallelism replicas at a time, "
            "and an exact replay of one replica is `uavtest run --replica I` locally)"
        )
    if rest and not wait:
        parts.append(f"{', '.join(rest)} (--no-wait returns as soon as the UavTest is created)")
    return "ignored with --engine kubernetes: " + "; ".join(parts)
