"""uavtest.engine: the local engine — N replicas as (sitl, runner) process pairs, then aggregation.

``run_command`` is what ``uavtest run`` calls; ``aggregate_run`` (in ``uavtest.engine.aggregate``)
is shared with the Kubernetes operator. Heavy modules are imported only when used.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from uavtest.engine.aggregate import aggregate_run
    from uavtest.engine.command import run_command

__all__ = ["aggregate_run", "run_command"]


def __getattr__(name: str) -> Any:
    """On first use (PEP 562): a replica process (``uavtest.engine.entry``) imports neither."""
    if name == "aggregate_run":
        from uavtest.engine.aggregate import aggregate_run

        return aggregate_run
    if name == "run_command":
        from uavtest.engine.command import run_command

        return run_command
    raise AttributeError(f"module 'uavtest.engine' has no attribute {name!r}")
