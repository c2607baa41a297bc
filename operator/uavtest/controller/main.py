"""``uavtest operator``: run the kopf operator with our handlers until SIGTERM / SIGINT."""

from __future__ import annotations

import logging
import re
from collections.abc import Sequence

import kopf

from uavtest.controller.settings import OperatorSettings

__all__ = ["run_operator"]

# kopf reports every handler call at INFO; for the per-event handlers that is one line per pod
# event. Without --verbose those lines are dropped (failures are still logged at ERROR).
_ROUTINE = re.compile(r"^Handler '(job_changed|forget_deleted)' succeeded")


class _QuietRoutine(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not _ROUTINE.match(record.getMessage())


def run_operator(
    *,
    namespaces: Sequence[str] = (),
    metrics_port: int | None = None,
    liveness_port: int | None = None,
    verbose: bool = False,
) -> None:
    """Watch UavTests in ``namespaces`` (all namespaces when empty) and reconcile them.

    ``metrics_port`` overrides ``UAVTEST_OPERATOR_METRICS_PORT`` (0 turns metrics off);
    ``liveness_port`` serves kopf's liveness probe at ``/healthz``. Standalone: one operator
    instance (the chart runs one replica with the Recreate strategy), no peering objects.
    """
    import uavtest.controller.handlers  # noqa: F401  (registers the handlers)

    config = OperatorSettings()
    if metrics_port is not None:
        config = config.model_copy(update={"metrics_port": metrics_port})
    logging.getLogger().handlers.clear()  # kopf installs its own handler: no duplicate lines
    kopf.configure(verbose=verbose)
    if not verbose:
        for handler in logging.getLogger().handlers:
            handler.addFilter(_QuietRoutine())
    kopf.run(
        standalone=True,
        clusterwide=not namespaces,
        namespaces=list(namespaces),
        liveness_endpoint=f"http://0.0.0.0:{liveness_port}/healthz" if liveness_port else None,
        memo=kopf.Memo(config=config),
    )
